"""Newton's method for a convex energy that is homogeneous of degree 2 in u (the split u-step)."""
from __future__ import annotations

from contextlib import AbstractContextManager
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import ngsolve as ngs

from .linear import SystemInverse, iterations as solver_iterations
from .threads import integrate, threaded, single_thread

__all__ = ["NewtonResult", "NewtonSolver"]


@dataclass
class NewtonResult:
    """Iterations and the relative residuals of one solve: ``|r|/|H u|`` on the free dofs at each
    iterate (H u holds the reactions on the Dirichlet dofs, the natural scale)."""

    iterations: int
    residuals: list[float] = field(default_factory=list)


class NewtonSolver:
    """Minimizes ``E(u) = int energy(u) - <rhs, u>`` over the free dofs of u (u keeps its
    Dirichlet values), for an energy that is convex and homogeneous of degree 2, so that its
    gradient is ``H(u) u``.

    Parameters
    ----------
    a : ngsolve.BilinearForm
        The tangent H at the GridFunction ``u`` (its integrand refers to ``u``); after each
        :meth:`solve` ``a.mat`` is the tangent at the solution.
    u : ngsolve.GridFunction
        The unknown, with its Dirichlet values set.
    energy : ngsolve.CoefficientFunction
        The energy density at ``u`` (for the line search).
    order : int
        Integration order of the energy.
    freedofs : ngsolve.BitArray
        Dofs to solve for.
    inverse : str
        Solver for the Newton systems, a ``discretization.u_solver`` (H is symmetric positive
        definite: the energy is convex and the residual stiffness keeps it strictly so).
    rtol : float
        Stop when the residual on the free dofs is at most ``rtol |H u|`` (checked before a
        Newton system is solved, so a converged iterate costs one assembly).
    max_iterations : int
        More Newton steps than this raise RuntimeError.
    preconditioner : ngsolve.Preconditioner, optional
        Registered with ``a`` before its first assembly; needed for ``inverse = "cg"``.
    solves : callable, optional
        Returns the context of factorizations and solves (default :func:`ngfrac.fem.threads.single_thread`,
        bitwise reproducible).
    """

    def __init__(self, a: ngs.BilinearForm, u: ngs.GridFunction, energy: Any, order: int,
                 freedofs: ngs.BitArray, inverse: str = "sparsecholesky", rtol: float = 1e-10,
                 max_iterations: int = 30, preconditioner: Any = None,
                 solves: Callable[[], AbstractContextManager] = single_thread) -> None:
        self.a, self.u, self.energy, self.order = a, u, energy, order
        self.solves = solves
        self.freedofs, self.inverse, self.preconditioner = freedofs, inverse, preconditioner
        self._free = np.array(freedofs, dtype=bool)  # element by element: once, not per solve
        self.rtol, self.max_iterations = rtol, max_iterations
        self._operator = SystemInverse(a, freedofs, inverse, preconditioner)
        self.last: NewtonResult | None = None
        """The result of the last :meth:`solve`."""

    def _factorize(self) -> Any:
        return self._operator.factorize()

    def total_energy(self, rhs: ngs.BaseVector | None) -> float:
        """E at the current u."""
        value = integrate(self.energy, self.u.space.mesh, order=self.order)
        return value - (ngs.InnerProduct(rhs, self.u.vec) if rhs is not None else 0.0)

    def solve(self, rhs: ngs.BaseVector | None = None) -> NewtonResult:
        """Newton steps from the current u until converged; ``rhs`` holds the linear terms
        (body force, alpha1/dt M u_prev), None for none. Raises RuntimeError if it does not
        converge."""
        a, vec = self.a, self.u.vec
        residual, step, start = vec.CreateVector(), vec.CreateVector(), vec.CreateVector()
        result = self.last = NewtonResult(0)
        for iteration in range(self.max_iterations + 1):
            # BDDC (u_solver = 'cg') factorizes inside the assembly: no threads for it
            with threaded() if self.preconditioner is None else self.solves():
                a.Assemble()
                residual.data = a.mat * vec
            scale = float(np.linalg.norm(residual.FV().NumPy()))
            if rhs is not None:
                residual.data -= rhs
            relative = float(np.linalg.norm(residual.FV().NumPy()[self._free])) / scale if scale else 0.0
            result.residuals.append(relative)
            if relative <= self.rtol:
                result.iterations = iteration
                return result
            if iteration == self.max_iterations:
                break
            with self.solves():
                inverse = self._factorize()
                step.data = inverse * residual
            solver_iterations(inverse)  # raises if CG did not converge
            decrement2 = max(ngs.InnerProduct(step, residual), 0.0)
            # backtracking on the energy: a full step unless it raises E (Armijo, 1e-4); the
            # slack lets through decreases below the round-off of E itself
            start.data = vec
            energy, s = self.total_energy(rhs), 1.0
            slack = 1e-12 * abs(energy)
            for _ in range(30):
                vec.data = start - s * step
                if self.total_energy(rhs) <= energy - 1e-4 * s * decrement2 + slack:
                    break
                s *= 0.5
        raise RuntimeError(f"Newton did not converge in {self.max_iterations} steps (relative "
                           f"residuals {', '.join(f'{d:.2e}' for d in result.residuals[-4:])})")
