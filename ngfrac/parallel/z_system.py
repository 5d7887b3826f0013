"""The z-system of a distributed mesh: one form, assembled with its parallel preconditioner,
solved by CG (:meth:`ngfrac.parallel.MPICommunicator.z_system`)."""
from __future__ import annotations

from typing import Any

import ngsolve as ngs
from ngsolve.krylovspace import CGSolver

from ..solve.u_problem import SolverError
from ..solve.z_problem import CG_MAXITER

__all__ = ["DistributedSystem"]


class DistributedSystem:
    """The z-system of a distributed mesh: K + (alpha2/dt) M + D(W) as one form, assembled
    every step with its parallel preconditioner registered, solved by CG from z_old.

    Distributed matrices have no ``AsVector`` (the serial path adds K and M to D's values),
    no ``CreateSmoother`` and no direct solve in the pip wheel.

    Parameters
    ----------
    fes : ngsolve.FESpace
        The space of z.
    integrand : ngsolve.comp.SumOfIntegrals
        The whole bilinear form.
    preconditioner : str
        ``"local"`` (Jacobi) or ``"bddc"``.
    """

    def __init__(self, fes: ngs.FESpace, integrand: Any, preconditioner: str) -> None:
        self.form = ngs.BilinearForm(fes, symmetric=True)
        self.form += integrand
        self.kind = preconditioner
        self.preconditioner = ngs.Preconditioner(self.form, preconditioner)

    def solve(self, rhs: ngs.BaseVector, z_old: ngs.BaseVector, out: ngs.BaseVector,
              step: int | str) -> int:
        """Assemble, then CG (relative tolerance 1e-10) from z_old into ``out``; returns the
        iterations."""
        self.form.Assemble()
        out.data = z_old
        cg = CGSolver(self.form.mat, self.preconditioner.mat, tol=1e-10, maxiter=CG_MAXITER)
        cg.Solve(rhs=rhs, sol=out, initialize=False)
        if cg.iterations >= CG_MAXITER:
            raise SolverError(f"the z-solve (CG, preconditioner {self.kind!r}) did "
                              f"not converge at step {step}; run serially")
        return int(cg.iterations)
