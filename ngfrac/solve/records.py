"""What one step reports: :class:`StepRecord`, one row of the history."""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields


@dataclass(frozen=True)
class StepRecord:
    """What one step reports. Diagnostic fields are NaN on steps that skip diagnostics.

    ``eta_total`` is the estimator total of the last adaptation, ``n_adapt`` the number of
    mesh changes so far, ``step_s`` the wall time of this step, ``solve_s`` the part in the two
    sub-steps (assembly and linear solves) and ``adapt_s`` the part spent changing the mesh.
    """

    step: int
    t: float
    wall_s: float
    nv: int
    ndof: int
    hmin: float = math.nan
    hmax: float = math.nan
    E_el: float = math.nan
    E_surf: float = math.nan
    E_total: float = math.nan
    crack_length: float = math.nan
    tip_x: float = math.nan
    tip_y: float = math.nan
    path_length: float = math.nan
    """Geometric length of the crack: the initial cracks plus the grown ridge (2D; NaN in 3D)."""
    n_damage_zones: int = 0
    """Components of {z >= 1/2} other than the crack (ngfrac.post.crackset)."""
    dz_max: float = math.nan
    z_iterations: int = 0
    dt: float = math.nan
    eta_total: float = math.nan
    n_adapt: int = 0
    step_s: float = math.nan
    solve_s: float = math.nan
    adapt_s: float = 0.0
    forces: dict[str, float] = field(default_factory=dict)
    """Reaction force and mean displacement per loaded boundary: ``Fx_top``, ``ux_top``, ..."""
    tip_z: float = math.nan
    """z of the tip, a column of 3D runs only (after tip_y)."""
    dim: int = 2
    """Dimension of the domain (not a column)."""
    crack_volume: float = math.nan
    """-int u.grad z, a column of runs with ``phase_field.crack_pressure`` only (after
    path_length)."""
    pressurized: bool = False
    """Whether the scene sets a crack pressure (not a column)."""

    NOT_FIXED = ("forces", "tip_z", "dim", "crack_volume", "pressurized")

    @property
    def has_diagnostics(self) -> bool:
        return not math.isnan(self.E_total)

    @classmethod
    def columns(cls) -> list[str]:
        """The fixed columns (without tip_z and the per-boundary force columns)."""
        return [f.name for f in fields(cls) if f.name not in cls.NOT_FIXED]

    def _names(self) -> list[str]:
        names = self.columns()
        if self.dim == 3:
            names.insert(names.index("tip_y") + 1, "tip_z")
        if self.pressurized:
            names.insert(names.index("path_length") + 1, "crack_volume")
        return names

    def header(self) -> list[str]:
        """All column names of this record: the fixed ones (and tip_z in 3D, crack_volume
        with a crack pressure), then the force columns."""
        return self._names() + list(self.forces)

    def row(self) -> list[float | int]:
        return [getattr(self, name) for name in self._names()] + list(self.forces.values())
