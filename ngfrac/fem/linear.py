"""Linear solvers for the u-step: sparse direct factorizations or CG with BDDC.

``discretization.u_solver``:

- ``"auto"`` (the default): ``"reused_cholesky"`` on a 3D mesh of at least
  :data:`AUTO_REUSE_VERTICES` vertices, else ``"sparsecholesky"``, decided for each mesh
  (:func:`resolve_u_solver`);
- ``"sparsecholesky"``, ``"umfpack"``: NGSolve's sparse direct solvers; the factorization is
  made once per mesh and numerically updated after each assembly;
- ``"reused_cholesky"``: CG preconditioned with the sparse Cholesky factor of an earlier
  u-matrix of the same mesh (:class:`ReusedCholesky`): refactorized only when a solve needed
  more than :data:`REFACTOR_ITERATIONS` iterations. It pays where a factorization costs many
  triangular solves (3D: ~40);
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

U_SOLVERS = ("auto", "sparsecholesky", "umfpack", "cg", "reused_cholesky")
"""Values of ``discretization.u_solver``."""
AUTO_REUSE_VERTICES = 4000
"""``u_solver = "auto"``: 3D meshes from this many vertices reuse a factorization. Measured
(docs/solvers.md): no gain at 1,717 vertices and a loss at 3,000 with a running crack; gains
of 1.07-2.6x from 4,311 vertices on, crack running or not."""
Z_SOLVERS = ("cg", "sparsecholesky", "umfpack", "reused_cholesky")
"""Values of ``discretization.z_solver`` (``"cg"``: Jacobi-preconditioned, in
:mod:`ngfrac.solve.z_system`)."""
CG_TOL = 1e-10
CG_MAXITER = 10000
REUSE_MAXITER = 20
"""``"reused_cholesky"``: CG iterations after which a solve gives up on the old factor,
refactorizes and solves directly (in 3D a factorization costs ~40 triangular solves: the
wasted iterations stay below half of it)."""
REFACTOR_ITERATIONS = REUSE_MAXITER // 2
"""``"reused_cholesky"``: a solve that needed more CG iterations than this refactorizes before
the next one (the counts grow while a crack runs: refactorize before they reach the cap)."""


class ReusedCholesky(ngs.BaseMatrix):
    """The inverse of ``mat`` by CG preconditioned with the sparse Cholesky factor of an
    earlier state of ``mat`` (the same sparsity: the form's matrix, reassembled in place).

    :meth:`update` after an assembly refactorizes only if the last solve needed more than
    :data:`REFACTOR_ITERATIONS` iterations; a solve that does not converge in
    :data:`REUSE_MAXITER` refactorizes and solves directly. Deterministic: the decisions follow
    iteration counts, never timings.

    Parameters
    ----------
    mat : ngsolve.BaseMatrix
        The assembled matrix (its values change with each assembly).
    freedofs : ngsolve.BitArray
    """

    def __init__(self, mat: ngs.BaseMatrix, freedofs: ngs.BitArray) -> None:
        super().__init__()
        self.mat = mat
        self.factor = mat.Inverse(freedofs, inverse="sparsecholesky")
        self.cg = CGSolver(mat, self.factor, tol=CG_TOL, maxiter=REUSE_MAXITER)
        self.iterations = 0
        """CG iterations of the last application (0 after a direct one)."""
        self.factorizations = 1
        """Numeric factorizations so far."""

    def Height(self) -> int:  # noqa: N802 (NGSolve's BaseMatrix interface)
        return self.mat.height

    def Width(self) -> int:  # noqa: N802
        return self.mat.width

    def IsComplex(self) -> bool:  # noqa: N802
        return False

    def CreateColVector(self) -> ngs.BaseVector:  # noqa: N802
        return self.mat.CreateColVector()

    def CreateRowVector(self) -> ngs.BaseVector:  # noqa: N802
        return self.mat.CreateRowVector()

    def _refactorize(self) -> None:
        self.factor.Update()
        self.factorizations += 1

    def update(self) -> None:
        """After an assembly: refactorize if the last solve needed too many iterations."""
        if self.iterations > REFACTOR_ITERATIONS:
            self._refactorize()

    def Mult(self, x: ngs.BaseVector, y: ngs.BaseVector) -> None:  # noqa: N802
        self.cg.Solve(rhs=x, sol=y, initialize=True)
        residuals = self.cg.residuals
        if residuals and residuals[-1] > CG_TOL * residuals[0]:
            self._refactorize()
            y.data = self.factor * x
            self.iterations = 0
            return
        self.iterations = self.cg.iterations


def resolve_u_solver(solver: str, mesh: ngs.Mesh) -> str:
    """The u-solver of ``mesh`` for a ``discretization.u_solver`` (``"auto"`` by dimension and
    vertex count: reproducible, it depends on the mesh alone)."""
    if solver != "auto":
        return solver
    return "reused_cholesky" if mesh.dim == 3 and mesh.nv >= AUTO_REUSE_VERTICES else "sparsecholesky"


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
    return factorized_inverse(form.mat, freedofs, solver)


def factorized_inverse(mat: ngs.BaseMatrix, freedofs: ngs.BitArray, solver: str) -> Any:
    """The inverse of ``mat`` from a sparse factorization: ``mat.Inverse`` with
    ``"sparsecholesky"`` or ``"umfpack"``, :class:`ReusedCholesky` with ``"reused_cholesky"``
    (:func:`update` after each assembly; the u- and the z-sub-step)."""
    if solver == "reused_cholesky":
        return ReusedCholesky(mat, freedofs)
    return mat.Inverse(freedofs, inverse=solver)


def update(inverse: Any) -> None:
    """After a new assembly: refactorize numerically (direct); CG's preconditioner was already
    set up again by the assembly; the reused factor only when it must)."""
    if isinstance(inverse, ReusedCholesky):
        inverse.update()
    elif not isinstance(inverse, CGSolver):
        inverse.Update()


def iterations(inverse: Any) -> int:
    """CG iterations of the last application (0 for a direct solver); raises RuntimeError if
    CG stopped at its iteration limit."""
    if isinstance(inverse, ReusedCholesky):
        return inverse.iterations
    if not isinstance(inverse, CGSolver):
        return 0
    if inverse.iterations >= CG_MAXITER:
        raise RuntimeError(f"CG did not reach the tolerance {CG_TOL:g} in {CG_MAXITER} iterations")
    return int(inverse.iterations)


class SystemInverse:
    """The inverse of an assembled matrix (the u- or the z-sub-step's), made at the first
    :meth:`factorize` and numerically updated at the later ones (or CG with the registered
    BDDC).

    Parameters
    ----------
    form : ngsolve.BilinearForm
    freedofs : ngsolve.BitArray
    solver : str
        A ``discretization.u_solver`` or, but for ``"cg"`` (which the z-step runs itself, from
        z_old), a ``discretization.z_solver``.
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
