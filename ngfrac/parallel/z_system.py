"""The z-system of a distributed mesh: one form, assembled with its parallel preconditioner,
solved by CG (:meth:`ngfrac.parallel.MPICommunicator.z_system`; the one-process system is
:class:`ngfrac.solve.z_system.AssembledSystem`)."""
from __future__ import annotations

from typing import Any

import ngsolve as ngs
from ngsolve.krylovspace import CGSolver

from ..solve.u_problem import SolverError
from ..solve.z_system import CG_MAXITER, ZForms

__all__ = ["DistributedSystem"]


class DistributedSystem:
    """The z-system of a distributed mesh: K + (alpha2/dt) M + D(W) as one form and its
    right-hand side as one linear form
    (:meth:`~ngfrac.solve.z_system.ZForms.matrix_integrand`,
    :meth:`~ngfrac.solve.z_system.ZForms.rhs_integrand`), both assembled every step, the form
    with its parallel preconditioner registered, solved by CG from z_old.

    Distributed matrices have no ``AsVector`` (the serial path adds K and M to D's values),
    no ``CreateSmoother`` and no direct solve in the pip wheel. The z-update is the projection
    (:meth:`ngfrac.parallel.MPICommunicator.check`).

    Parameters
    ----------
    forms : ZForms
        The terms of the sub-step.
    preconditioner : str
        ``"local"`` (Jacobi) or ``"bddc"``.
    """

    def __init__(self, forms: ZForms, preconditioner: str) -> None:
        fields = forms.fields
        self.fields, self.context = fields, forms.context
        zt, w = fields.fes_z.TnT()
        self._rhs_form = ngs.LinearForm(forms.rhs_integrand(w) * fields.dx)
        self.form = ngs.BilinearForm(fields.fes_z, symmetric=True)
        self.form += forms.matrix_integrand(zt, w) * fields.dx
        self.kind = preconditioner
        self.preconditioner = ngs.Preconditioner(self.form, preconditioner)
        self.rhs = fields.z.vec.CreateVector()
        """The right-hand side of the last sub-step."""

    @property
    def matrix(self) -> Any:
        """The distributed matrix of the last :meth:`solve`."""
        return self.form.mat

    def solve(self, z_trial: ngs.GridFunction, step: int | str) -> int:
        """Assemble, then CG (relative tolerance 1e-10) from z_old into ``z_trial``; returns
        the iterations."""
        with self.context.timer.phase("z: assemble and solve"), self.context.threads.solves():
            self._rhs_form.Assemble()
            self.rhs.data = self._rhs_form.vec
            self.form.Assemble()
            z_trial.vec.data = self.fields.z.vec
            cg = CGSolver(self.form.mat, self.preconditioner.mat, tol=1e-10, maxiter=CG_MAXITER)
            cg.Solve(rhs=self.rhs, sol=z_trial.vec, initialize=False)
        if cg.iterations >= CG_MAXITER:
            raise SolverError(f"the z-solve (CG, preconditioner {self.kind!r}) did "
                              f"not converge at step {step}; run serially")
        return int(cg.iterations)

    def surface_energy(self) -> None:
        """None: the matrices of a distributed mesh are not local (the records integrate)."""
        return None
