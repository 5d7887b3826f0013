"""The unit system of a scene (the top-level key ``units``): what the scene's numbers mean,
for the labels of plots, the units of the history columns and the ``units`` attributes of
results.h5. ngfrac computes the same numbers in every system; the key only names them.

2D models (mode III, plane strain, plane stress) compute per unit thickness: their forces,
energies and crack areas are per unit length out of the plane (``force(2)`` is N/m in SI).
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["SCENE_UNITS", "UNIT_SYSTEMS", "UnitSystem", "column_units", "unit_system"]

SCENE_UNITS = "scene units"
"""The default: the scene's numbers are in some consistent system that ngfrac does not know."""


@dataclass(frozen=True)
class UnitSystem:
    """The base units of a consistent system: length, force and stress = force/length²."""

    name: str
    length: str
    force_unit: str
    stress: str
    energy_unit: str
    """Force times length (J in SI)."""

    @property
    def known(self) -> bool:
        """False for :data:`SCENE_UNITS` (labels then say "scene units")."""
        return self.name != SCENE_UNITS

    def force(self, dim: int) -> str:
        """A reaction force: per unit thickness in 2D."""
        if not self.known:
            return SCENE_UNITS + (", per unit thickness" if dim == 2 else "")
        return f"{self.force_unit}/{self.length}" if dim == 2 else self.force_unit

    def energy(self, dim: int) -> str:
        """An energy: per unit thickness in 2D."""
        if not self.known:
            return SCENE_UNITS + (", per unit thickness" if dim == 2 else "")
        return f"{self.energy_unit}/{self.length}" if dim == 2 else self.energy_unit

    def crack_measure(self, dim: int) -> str:
        """The crack's size: a length in 2D (an area per unit thickness), an area in 3D."""
        if not self.known:
            return SCENE_UNITS
        return self.length if dim == 2 else f"{self.length}²"

    def volume(self, dim: int) -> str:
        """A crack volume: an area in 2D (per unit thickness), a volume in 3D."""
        if not self.known:
            return SCENE_UNITS + (", per unit thickness" if dim == 2 else "")
        return f"{self.length}²" if dim == 2 else f"{self.length}³"

    def label(self, quantity: str, unit: str) -> str:
        """An axis label: ``"reaction force [N/m]"``."""
        return f"{quantity} [{unit}]" if unit else quantity


UNIT_SYSTEMS = {
    SCENE_UNITS: UnitSystem(SCENE_UNITS, SCENE_UNITS, SCENE_UNITS, SCENE_UNITS, SCENE_UNITS),
    "SI": UnitSystem("SI", "m", "N", "Pa", "J"),
    "mm-N-MPa": UnitSystem("mm-N-MPa", "mm", "N", "MPa", "mJ"),
    "mm-kN-GPa": UnitSystem("mm-kN-GPa", "mm", "kN", "GPa", "J"),
}
"""The systems a scene may name (``units``): lengths, forces, stresses (E, lam, mu) and
energies; the toughness gamma is force/length (J/m² in SI, N/mm in mm-N-MPa, kN/mm in
mm-kN-GPa)."""


def unit_system(name: str) -> UnitSystem:
    """The system called ``name`` (a key of :data:`UNIT_SYSTEMS`); ValueError otherwise."""
    try:
        return UNIT_SYSTEMS[name]
    except KeyError:
        raise ValueError(f"units = {name!r} is not allowed: give one of "
                         f"{', '.join(repr(n) for n in UNIT_SYSTEMS)}") from None


def column_units(columns: list[str], units: UnitSystem, dim: int) -> list[str]:
    """The unit of each history column ("" for counts and the load parameter t, "1" for the
    dimensionless dz_max, "s" for wall times).

    ``t`` and ``dt`` are the load parameter of the scene's expressions (a load ``"10*t"`` is
    10 t of length); ngfrac gives them no unit.
    """
    length = units.length
    fixed = {"wall_s": "s", "step_s": "s", "solve_s": "s", "adapt_s": "s",
             "hmin": length, "hmax": length, "E_el": units.energy(dim),
             "E_surf": units.energy(dim), "E_total": units.energy(dim),
             "crack_length": units.crack_measure(dim), "tip_x": length, "tip_y": length,
             "tip_z": length, "path_length": length, "dz_max": "1",
             "crack_volume": units.volume(dim)}
    out = []
    for name in columns:
        if name in fixed:
            out.append(fixed[name])
        elif name.startswith("F") and "_" in name:
            out.append(units.force(dim))
        elif name.startswith("u") and "_" in name:
            out.append(length)
        else:
            out.append("")
    return out
