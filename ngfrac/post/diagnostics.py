"""Per-step diagnostics: energies, crack length and element diameters."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ngsolve as ngs

from ..fem.elements import ElementGeometry
from ..physics.crack_models import CrackModel
from ..fem.threads import integrate


@dataclass(frozen=True)
class Energies:
    """Energies of a state: elastic, surface, the crack length and the work of the loads."""

    E_el: float
    E_surf: float
    crack_length: float
    work: float = 0.0
    """The work of the loads: int f.u of the body force (the stepper adds the tractions' and
    the crack pressure's, :meth:`ngfrac.solve.u_problem.DisplacementProblem.surface_work`)."""

    @property
    def E_total(self) -> float:
        """``E_el + E_surf - work``."""
        return self.E_el + self.E_surf - self.work


def energies(mesh: ngs.Mesh, z: ngs.GridFunction, energy_density: ngs.CoefficientFunction,
             gamma: ngs.CoefficientFunction, epsilon: float, residual_stiffness: float,
             crack_model: CrackModel, force_times_u: ngs.CoefficientFunction | None = None,
             order: int = 5, surface: tuple[float, float] | None = None) -> Energies:
    """Integrate the energies in one pass.

    ``E_el = 1/2 int g(z) W`` with the crack model's degradation g (``(1-z)^2 + eta`` for
    AT2 and AT1), ``E_surf = int gamma w``, ``crack_length = int w`` (the Gamma-limit of the
    surface term; ``w`` the crack model's surface density), and the work
    ``int f.u`` when a body force is given. ``surface``, when given, is (E_surf,
    crack_length) already computed (from the z-problem's matrices,
    :meth:`ngfrac.solve.z_problem.PhaseFieldProblem.surface_energy`), and only E_el and the
    work are integrated.
    """
    model = crack_model
    elastic = 0.5 * model.degradation(z, residual_stiffness) * energy_density
    if surface is not None:
        parts = [elastic] if force_times_u is None else [elastic, force_times_u]
        values = integrate(ngs.CoefficientFunction(tuple(parts)), mesh, order=order)
        values = values if isinstance(values, list) else [values]
        work = values[1] if len(values) > 1 else 0.0
        return Energies(values[0], surface[0], surface[1], work)
    density = model.surface_density(z, epsilon)
    work_cf = force_times_u if force_times_u is not None else ngs.CoefficientFunction(0.0)
    values = integrate(ngs.CoefficientFunction((elastic, gamma * density, density, work_cf)),
                       mesh, order=order)
    return Energies(*values)


def element_diameters(mesh: ngs.Mesh) -> np.ndarray:
    """The longest edge of each volume element, in NGSolve's element order.

    This is the element's h (Netgen's ``maxh`` is a longest edge); it is
    :attr:`ngfrac.mesh.remesh.ElementGeometry.diameters`. Not to be confused with
    :meth:`ngfrac.mesh.adapter.MeshAdapter.element_sizes`, the sizes the adapter requests.

    Parameters
    ----------
    mesh : ngsolve.Mesh
        A simplicial 2D or 3D mesh.

    Returns
    -------
    numpy.ndarray
        One length per volume element.
    """
    return ElementGeometry.of(mesh).diameters
