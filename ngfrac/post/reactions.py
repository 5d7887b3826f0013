"""Reaction forces on Dirichlet boundaries, from the residual of the discrete u-equation.

The force that holds a boundary Gamma in place is ``F = int_Gamma sigma n ds``. Integrating
the stress of the finite-element solution loses an order (sigma is a derivative) and ignores
the body force; the variationally consistent value comes from the residual instead::

    R = A(z) u - alpha1/dt M u_prev - f     (A(z) includes alpha1/dt M: the assembled u-equation)
    F_i(Gamma) = <R, w_i>,   w_i = e_i on the dofs of Gamma, 0 on all other dofs

R vanishes at the free dofs, so only the constrained dofs of Gamma contribute, and by Green's
formula ``<R, w_i> = int_Gamma ((1-z)^2 + eta) sigma n . e_i ds`` whenever the traction is
smooth. A corner shared with another boundary that prescribes the same component counts for
both boundaries; a component the load leaves free has F_i = 0. Tractions and pressures
(Neumann loads) are part of f, so the reactions balance them: without alpha1 and with no
dof on two Dirichlet boundaries, the reactions sum to minus the applied force.

Compute reactions after the u-solve and before any mesh change: the residual uses the matrix
of that solve (assembled with the z it used, z^{k-1} inside a step).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import ngsolve as ngs

from ..fem.threads import integrate

if TYPE_CHECKING:
    from ..scene import Load


def indicator(fes: ngs.FESpace, boundary: str, component: int = 0) -> ngs.GridFunction:
    """w = e_component on the constrained dofs of ``boundary``, 0 elsewhere.

    Its trace on the boundary is exactly e_component (the vertex functions of Gamma sum to 1
    there; the higher-order dofs of a constant are 0).
    """
    w = ngs.GridFunction(fes)
    target = w.components[component] if w.components else w
    target.Set(1.0, ngs.BND, definedon=fes.mesh.Boundaries(boundary))
    free = np.array(fes.FreeDofs(), dtype=bool)
    w.vec.FV().NumPy()[free] = 0.0
    return w


def reaction(residual: ngs.BaseVector, fes: ngs.FESpace, boundary: str,
             components: tuple[int, ...], cache: dict | None = None) -> np.ndarray:
    """``<R, w_i>`` for each component i in ``components`` (the constrained ones).

    ``cache`` (a dict kept per space) saves rebuilding the indicators every step.
    """
    forces = np.zeros(fes.mesh.dim if isinstance(fes, ngs.VectorH1) else 1)
    for i in components:
        key = (boundary, i)
        if cache is None or key not in cache:
            w = indicator(fes, boundary, i)
            if cache is not None:
                cache[key] = w
        else:
            w = cache[key]
        forces[i] = ngs.InnerProduct(residual, w.vec)
    return forces


def reaction_forces(problem: Any, loads: tuple["Load", ...],
                    boundaries: tuple[str, ...] | None = None) -> dict[str, np.ndarray]:
    """The reaction force on each loaded boundary, one entry per component of u.

    Parameters
    ----------
    problem : DisplacementProblem
        The u-sub-problem (:mod:`ngfrac.solve.u_problem`) after its solve, before any mesh
        change: its residual holds the reactions.
    loads : tuple of Load
        The scene's loads; only displacement loads (Dirichlet boundaries) have a reaction.
    boundaries : tuple of str, optional
        Dirichlet boundaries to report; all of them by default.

    Returns
    -------
    dict
        boundary -> array of (Fx, Fy) (mode III: (Fz,), the out-of-plane force).
    """
    by_name = {load.boundary: load for load in loads if load.is_dirichlet}
    r = problem.residual()
    out = {}
    for name in boundaries or tuple(by_name):
        constrained = tuple(i for i, free in enumerate(by_name[name].free) if not free)
        out[name] = reaction(r, problem.fields.fes_u, name, constrained, problem.indicators)
    return out


def boundary_mean(u: ngs.GridFunction, boundary: str) -> np.ndarray:
    """The mean of u over a boundary, per component (the imposed displacement of a load)."""
    mesh = u.space.mesh
    region = mesh.Boundaries(boundary)
    length = integrate(1.0, mesh, vb=ngs.BND, definedon=region)
    return np.atleast_1d(np.asarray(integrate(u, mesh, vb=ngs.BND, definedon=region))) / length


def reaction_columns(problem: Any, loads: tuple["Load", ...]) -> dict[str, float]:
    """History columns: ``F<c>_<boundary>`` and ``u<c>_<boundary>`` for each Dirichlet boundary.

    ``c`` is x, y (plane models) or z (mode III, out of plane); ``u<c>`` is the boundary mean
    of u, which is the imposed displacement for a uniform load.
    """
    names = problem.model.component_names
    row: dict[str, float] = {}
    for boundary, force in reaction_forces(problem, loads).items():
        mean = boundary_mean(problem.fields.u, boundary)
        row.update({f"F{c}_{boundary}": float(force[i]) for i, c in enumerate(names)})
        row.update({f"u{c}_{boundary}": float(mean[i]) for i, c in enumerate(names)})
    return row
