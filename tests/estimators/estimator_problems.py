"""Model problems with known solutions for the estimator tests (not a test module)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ngsolve
from netgen.geom2d import unit_square
from ngsolve import (
    CF,
    BilinearForm,
    GridFunction,
    H1,
    Integrate,
    LinearForm,
    Mesh,
    dx,
    exp,
    grad,
    pi,
    sin,
    sqrt,
    x,
    y,
)

SMOOTH_SOLUTION = sin(pi * x) * sin(pi * y) * exp(x)
SMOOTH_GRADIENT = CF((SMOOTH_SOLUTION.Diff(x), SMOOTH_SOLUTION.Diff(y)))
SMOOTH_SOURCE = -(SMOOTH_SOLUTION.Diff(x).Diff(x) + SMOOTH_SOLUTION.Diff(y).Diff(y))


@dataclass(frozen=True)
class Solution:
    """A discrete solution with its true error."""

    gf: ngsolve.GridFunction
    ndof: int
    error: float


def square_mesh(maxh: float) -> ngsolve.Mesh:
    """Unstructured Netgen mesh of the unit square."""
    return Mesh(unit_square.GenerateMesh(maxh=maxh))


def solve_smooth_poisson(mesh: ngsolve.Mesh, order: int) -> Solution:
    """-Laplace u = f, u = 0 on the boundary, u = sin(pi x) sin(pi y) exp(x).

    The error is the H1 seminorm ``||grad(u - u_h)||``.
    """
    space = H1(mesh, order=order, dirichlet=".*")
    trial, test = space.TnT()
    stiffness = BilinearForm(grad(trial) * grad(test) * dx).Assemble()
    load = LinearForm(SMOOTH_SOURCE * test * dx(bonus_intorder=4)).Assemble()
    gf = GridFunction(space)
    gf.vec.data = stiffness.mat.Inverse(space.FreeDofs(), "sparsecholesky") * load.vec
    diff = grad(gf) - SMOOTH_GRADIENT
    error = sqrt(Integrate(diff * diff, mesh, order=2 * order + 4))
    return Solution(gf, space.ndof, float(error))


def layer_solution(eps: float) -> ngsolve.CoefficientFunction:
    """Boundary layers of width eps along x = 0 and y = 0."""
    return exp(-x / eps) + exp(-y / eps)


def solve_layer(mesh: ngsolve.Mesh, eps: float, order: int = 1) -> Solution:
    """-eps^2 Laplace u + u = 0 with Dirichlet data from :func:`layer_solution`.

    The error is the energy norm ``(eps^2 ||grad e||^2 + ||e||^2)^(1/2)``.
    """
    exact = layer_solution(eps)
    exact_grad = CF((exact.Diff(x), exact.Diff(y)))
    space = H1(mesh, order=order, dirichlet=".*")
    trial, test = space.TnT()
    form = BilinearForm(eps**2 * grad(trial) * grad(test) * dx + trial * test * dx).Assemble()
    gf = GridFunction(space)
    gf.Set(exact, ngsolve.BND)
    residual = -form.mat * gf.vec
    gf.vec.data += form.mat.Inverse(space.FreeDofs(), "sparsecholesky") * residual
    grad_err = grad(gf) - exact_grad
    energy = eps**2 * grad_err * grad_err + (gf - exact) ** 2
    error = sqrt(Integrate(energy, mesh, order=12))
    return Solution(gf, space.ndof, float(error))


def total(eta: np.ndarray) -> float:
    """Global estimate ``(sum eta_T^2)^(1/2)``."""
    return float(np.sqrt(np.sum(np.asarray(eta) ** 2)))


def table(header: str, rows: list[tuple]) -> str:
    """Plain-text table for assertion messages."""
    lines = [header]
    for row in rows:
        lines.append("  ".join(f"{v:10.4g}" if isinstance(v, float) else f"{v:>8}" for v in row))
    return "\n".join(lines)


def loglog_rate(ndofs: list[int], errors: list[float]) -> float:
    """Slope of log(error) against log(ndof), fitted with numpy.polyfit."""
    return float(np.polyfit(np.log(ndofs), np.log(errors), 1)[0])
