"""Linear solvers for the u-step: sparse direct factorizations or CG with BDDC.

``discretization.u_solver``:

- ``"sparsecholesky"``, ``"umfpack"``: NGSolve's sparse direct solvers; the factorization is
  made once per mesh and numerically updated after each assembly;
- ``"cg"``: conjugate gradients (NGSolve's ``CGSolver``, relative tolerance 1e-10 in the
  preconditioned norm) with NGSolve's BDDC preconditioner (``Preconditioner(a, "bddc")``), which
  is registered with the bilinear form before its first assembly and set up again by every
  assembly. ``h1amg`` fails on VectorH1 ("matrix singular"), ``multigrid`` has no mesh
  hierarchy on Netgen-generated meshes (its coarse solve is the direct one) and Jacobi needed
  556 iterations where BDDC needs 80 (2D, P2, a crack band with eta = 1e-6); see docs/solvers.md.
"""
from __future__ import annotations

from typing import Any

import ngsolve as ngs
from ngsolve.krylovspace import CGSolver

U_SOLVERS = ("sparsecholesky", "umfpack", "cg")
"""Values of ``discretization.u_solver``."""
CG_TOL = 1e-10
CG_MAXITER = 10000


def register_preconditioner(form: ngs.BilinearForm, solver: str) -> Any | None:
    """BDDC for ``form`` when ``solver == "cg"`` (call before the form's first assembly)."""
    return ngs.Preconditioner(form, "bddc") if solver == "cg" else None


def u_inverse(form: ngs.BilinearForm, freedofs: ngs.BitArray, solver: str,
              preconditioner: Any | None = None) -> Any:
    """An operator applying the inverse of the assembled ``form`` on ``freedofs``."""
    if solver == "cg":
        if preconditioner is None:
            raise ValueError("u_solver = 'cg' needs the preconditioner registered before assembly")
        return CGSolver(form.mat, preconditioner.mat, tol=CG_TOL, maxiter=CG_MAXITER)
    return form.mat.Inverse(freedofs, inverse=solver)


def update(inverse: Any) -> None:
    """After a new assembly: refactorize numerically (direct); CG's preconditioner was already
    set up again by the assembly."""
    if not isinstance(inverse, CGSolver):
        inverse.Update()


def iterations(inverse: Any) -> int:
    """CG iterations of the last application (0 for a direct solver); raises RuntimeError if
    CG stopped at its iteration limit."""
    if not isinstance(inverse, CGSolver):
        return 0
    if inverse.iterations >= CG_MAXITER:
        raise RuntimeError(f"CG did not reach the tolerance {CG_TOL:g} in {CG_MAXITER} iterations")
    return int(inverse.iterations)


class UOperator:
    """The inverse of an assembled u-matrix, made at the first :meth:`factorize` and
    numerically updated at the later ones (or CG with the registered BDDC).

    Parameters
    ----------
    form : ngsolve.BilinearForm
    freedofs : ngsolve.BitArray
    solver : str
        A ``discretization.u_solver``.
    preconditioner : optional
        :func:`register_preconditioner` of ``form`` (for ``"cg"``).
    """

    def __init__(self, form: ngs.BilinearForm, freedofs: ngs.BitArray, solver: str,
                 preconditioner: Any | None = None) -> None:
        self.form, self.freedofs, self.solver = form, freedofs, solver
        self.preconditioner = preconditioner
        self.inverse: Any = None

    def factorize(self) -> Any:
        """After an assembly of the form: the operator applying its inverse."""
        if self.inverse is None:
            self.inverse = u_inverse(self.form, self.freedofs, self.solver, self.preconditioner)
        else:
            update(self.inverse)
        return self.inverse

    def iterations(self) -> int:
        """CG iterations of the last application (0 for a direct solver); raises
        RuntimeError if CG stopped at its iteration limit."""
        return iterations(self.inverse)
