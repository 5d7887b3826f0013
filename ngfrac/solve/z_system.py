"""The linear algebra of the z-sub-step: what the z-problem (:mod:`ngfrac.solve.z_problem`)
asks of its communicator's z-system (:class:`ZSystem`), the terms it gives it
(:class:`ZForms`), and the one-process system (:class:`AssembledSystem`,
:meth:`ngfrac.solve.communicator.Serial.z_system`).

The one-process matrix is K + (alpha2/dt) M + D(W): K and M change only with the mesh and are
assembled once per mesh, only the drive part D is assembled per step, and K and M join it by
value (docs/benchmarks.md has the saving). The right-hand side needs no assembly of its own:
int (alpha2/dt z_old + W) w = (alpha2/dt) M z_old + D 1, with 1 the coefficients of the
constant function (the vertex dofs of the hierarchical basis), plus the source assembled once
per mesh and the crack pressure's term per step. A concave surface part C (PF-CZM's
``-z^2/eps``) stays out of the matrix and enters the right-hand side at z_old, ``-C z_old``
(assembled once per mesh, one product per step). The surface energy is a quadratic form of K
(and C): E_surf = 1/2 z.(K + C) z - s.z (s the source), the same sum as its quadrature.

The system of a distributed mesh (:class:`ngfrac.parallel.z_system.DistributedSystem`)
answers the same questions with one form assembled every step and solved by CG.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import ngsolve as ngs
from ngsolve.krylovspace import CGSolver

from ..fem.linear import SystemInverse
from ..fem.nodal import vertex_dofs_first
from .obstacle import NodalObstacle
from .u_problem import SolverError

if TYPE_CHECKING:
    from ..mesh.fields import MeshFields
    from ..physics.crack_models import CrackModel
    from .context import StepContext

__all__ = ["CG_MAXITER", "AssembledSystem", "ZForms", "ZSystem"]

CG_MAXITER = 2000
"""Iterations of a z-CG before it counts as not converged."""


@dataclass(frozen=True, eq=False)
class ZForms:
    """The terms of the z-sub-step of one mesh, as the z-problem makes them of the crack model
    and the drive, and how it is solved.

    Attributes
    ----------
    fields : MeshFields
        z holds z_old during a step.
    context : StepContext
        1/dt, threads, timer and communicator of the step.
    crack_model : CrackModel
        Gives the stiffness, concave part and source of the surface terms.
    gamma : float or ngsolve.CoefficientFunction
        The toughness.
    epsilon, alpha2 : float
        ``phase_field.epsilon`` and ``phase_field.alpha2``.
    implicit : ngsolve.CoefficientFunction
        The drive's factor of ``zt w`` in the matrix.
    explicit : ngsolve.CoefficientFunction or None
        The drive's factor of ``w`` on the right-hand side when it differs from ``implicit``
        (:meth:`~ngfrac.physics.crack_models.CrackModel.drive_factors`); None: the same W.
    crack_pressure : ngsolve.CoefficientFunction or None
        p(t) of ``phase_field.crack_pressure`` (None: no pressure term).
    u_drive : ngsolve.GridFunction or None
        The u of the drive (u_prev or u), of the pressure's term :meth:`pressure`.
    solver : str
        ``discretization.z_solver``.
    update : str
        The z-update: ``"projection"``, ``"descent"`` or ``"obstacle"``.
    """

    fields: "MeshFields"
    context: "StepContext"
    crack_model: "CrackModel"
    gamma: Any
    epsilon: float
    alpha2: float
    implicit: ngs.CoefficientFunction
    explicit: ngs.CoefficientFunction | None
    crack_pressure: ngs.CoefficientFunction | None
    u_drive: ngs.GridFunction | None
    solver: str
    update: str

    def pressure(self, w: Any) -> ngs.CoefficientFunction | None:
        """The crack pressure's linear integrand ``-p u_drive . grad w`` of the test function
        ``w`` (the z-derivative of the work term ``int p u.grad z``), or None."""
        if self.crack_pressure is None:
            return None
        return -self.crack_pressure * ngs.InnerProduct(self.u_drive, ngs.grad(w))

    def matrix_integrand(self, zt: Any, w: Any) -> ngs.CoefficientFunction:
        """K + (alpha2/dt) M + D(W) as one integrand of the trial and test functions, for a
        form assembled whole (a distributed mesh's)."""
        return (self.crack_model.stiffness(zt, w, self.gamma, self.epsilon)
                + self.alpha2 * self.context.inv_dt * zt * w + self.implicit * zt * w)

    def rhs_integrand(self, w: Any) -> ngs.CoefficientFunction:
        """(alpha2/dt z_old + W) w - C(z_old, w) + source + the pressure's term as one
        integrand of the test function, for a linear form assembled whole (a distributed
        mesh's)."""
        z_old, model = self.fields.z, self.crack_model
        explicit = self.implicit if self.explicit is None else self.explicit
        rhs = (self.alpha2 * self.context.inv_dt * z_old + explicit) * w
        concave = model.concave(z_old, w, self.gamma, self.epsilon)
        if concave is not None:
            rhs = rhs - concave
        for part in (model.source(w, self.gamma, self.epsilon), self.pressure(w)):
            rhs = rhs if part is None else rhs + part
        return rhs


class ZSystem(Protocol):
    """What the z-problem asks of its communicator's z-system."""

    rhs: ngs.BaseVector
    """The right-hand side of the last sub-step."""

    @property
    def matrix(self) -> Any:
        """The matrix of the last sub-step."""

    def solve(self, z_trial: ngs.GridFunction, step: int | str) -> int:
        """Assemble the step's system from z_old and solve it into ``z_trial``; returns the
        iterations (0 for a direct solve). Raises :class:`SolverError`."""

    def surface_energy(self) -> tuple[float, float] | None:
        """(E_surf, crack_length) of the current z, or None (then the records integrate)."""


class AssembledSystem:
    """The z-system of one process: K, M (and C, the source) once per mesh, D(W) per step, K
    and M added to its values; a direct solve (the factorization updated in place), CG with
    a smoother, or the obstacle problem z >= z_old at the nodes (:mod:`ngfrac.solve.obstacle`).

    Parameters
    ----------
    forms : ZForms
        The terms of the sub-step.
    """

    def __init__(self, forms: ZForms) -> None:
        fields, model, gamma, eps = forms.fields, forms.crack_model, forms.gamma, forms.epsilon
        self.fields, self.context = fields, forms.context
        self.alpha2, self.solver = forms.alpha2, forms.solver
        zt, w = fields.fes_z.TnT()
        dx = fields.dx
        self.a_z = ngs.BilinearForm(fields.fes_z, symmetric=True)
        self.a_z += forms.implicit * zt * w * dx
        self._drive_rhs = (None if forms.explicit is None
                           else ngs.LinearForm(forms.explicit * w * dx))
        """int explicit W w, when the drive's two parts differ (else D 1 from the matrix)."""
        self._k = ngs.BilinearForm(fields.fes_z, symmetric=True)
        self._k += model.stiffness(zt, w, gamma, eps) * dx
        self._m = ngs.BilinearForm(fields.fes_z, symmetric=True)
        self._m += zt * w * dx
        concave = model.concave(zt, w, gamma, eps)  # PF-CZM: explicit, -C z_old
        self._concave = None if concave is None else ngs.BilinearForm(fields.fes_z, symmetric=True)
        if concave is not None:
            self._concave += concave * dx
        self._fixed_assembled = False
        source = model.source(w, gamma, eps)  # AT1: -3 gamma/(8 eps) w
        self._source = None if source is None else ngs.LinearForm(source * dx)
        pressure = forms.pressure(w)
        self._pressure = None if pressure is None else ngs.LinearForm(pressure * dx)
        self._gamma = gamma
        self._unit_surface: tuple[ngs.BilinearForm, ngs.LinearForm | None] | None = None
        if not isinstance(gamma, (int, float)):  # the crack length: the surface energy at gamma = 1
            unit_k = ngs.BilinearForm(fields.fes_z, symmetric=True)
            unit_k += model.stiffness(zt, w, 1.0, eps) * dx
            unit_concave = model.concave(zt, w, 1.0, eps)
            if unit_concave is not None:  # one matrix for the length: K + C at gamma = 1
                unit_k += unit_concave * dx
            unit_source = model.source(w, 1.0, eps)
            self._unit_surface = (unit_k, None if unit_source is None
                                  else ngs.LinearForm(unit_source * dx))
        self.rhs = fields.z.vec.CreateVector()
        """The right-hand side of the last sub-step."""
        self._ones = _constant_one(fields.fes_z, fields.z.vec)
        self._inverse: SystemInverse | None = None
        self._obstacle = (NodalObstacle(fields.nodes, fields.damage_free_nodes)
                          if forms.update == "obstacle" else None)
        self.lower: ngs.GridFunction | None = None
        """The obstacle's bound when it is not z_old (``coupling = "alternate"``: the step's
        z^{k-1} while z_old is the last pass's z); None: z_old."""

    @property
    def matrix(self) -> Any:
        """K + (alpha2/dt) M + D(W) of the last :meth:`assemble`."""
        return self.a_z.mat

    def solve(self, z_trial: ngs.GridFunction, step: int | str) -> int:
        """:meth:`assemble`, then the solve into ``z_trial``; returns the CG iterations (0 for
        a direct solve; the active-set iterations of the obstacle problem). Raises
        :class:`SolverError`, also for non-finite values."""
        with self.context.timer.phase("z: assemble"), self.context.threads.assembly(kind="z"):
            self.assemble()
        if self._obstacle is not None:
            with self.context.timer.phase("z: obstacle solve"), self.context.threads.solves():
                iterations = self._solve_obstacle(z_trial)
        else:
            with self.context.timer.phase("z: solve"), self.context.threads.solves():
                iterations = self.solve_system(z_trial, step)
        if not np.all(np.isfinite(z_trial.vec.FV().NumPy())):
            raise SolverError(f"the z-solve gave non-finite values at step {step}; lower time.dt")
        return iterations

    def _assemble_fixed(self) -> None:
        """K, M and the source terms: once per mesh."""
        if self._fixed_assembled:
            return
        forms = [self._k, self._m, self._source, self._concave]
        if self._unit_surface is not None:
            forms += list(self._unit_surface)
        for form in forms:
            if form is not None:
                form.Assemble()
        self._fixed_assembled = True

    def assemble(self) -> None:
        """a_z.mat = K + (alpha2/dt) M + D(W) (D assembled, K and M once per mesh) and
        :attr:`rhs` = (alpha2/dt) M z_old + D 1 + source + the pressure's term."""
        self._assemble_fixed()
        self.a_z.Assemble()
        mass_factor = self.alpha2 * self.context.inv_dt.Get()
        rhs, mass = self.rhs, self._m.mat
        if self._drive_rhs is None:
            rhs.data = self.a_z.mat * self._ones  # int W w, before K and M join the matrix
        else:
            self._drive_rhs.Assemble()
            rhs.data = self._drive_rhs.vec
        rhs.data += mass_factor * (mass * self.fields.z.vec)
        if self._source is not None:
            rhs.data += self._source.vec
        if self._concave is not None:
            rhs.data -= self._concave.mat * self.fields.z.vec
        if self._pressure is not None:
            self._pressure.Assemble()
            rhs.data += self._pressure.vec
        values = self.a_z.mat.AsVector()
        k, m = self._k.mat.AsVector(), mass.AsVector()
        if not (len(values) == len(k) == len(m)):  # never seen; the forms share fes_z
            raise RuntimeError("the z-forms do not share a sparsity pattern")
        values.data += k + mass_factor * m

    def surface_energy(self) -> tuple[float, float]:
        """(E_surf, crack_length) of the current z from the assembled K and source.

        1/2 z.(K + C) z - s.z is the crack model's surface energy summed with the forms'
        quadrature (the same rule as the energies' integrals); the crack length is the same at
        gamma = 1.
        """
        self._assemble_fixed()
        z = self.fields.z.vec
        e_surf = _surface_value(self._k.mat, self._source, z,
                                None if self._concave is None else self._concave.mat)
        if self._unit_surface is None:
            return e_surf, e_surf / float(self._gamma)
        return e_surf, _surface_value(self._unit_surface[0].mat, self._unit_surface[1], z)

    def solve_system(self, z_trial: ngs.GridFunction, step: int | str) -> int:
        """The assembled system solved into ``z_trial``: CG from z_old, or the direct solve
        (its factorization updated in place from the second step on), or CG preconditioned
        with an earlier factorization (``"reused_cholesky"``, :class:`ngfrac.fem.linear.ReusedCholesky`);
        returns the CG iterations (0 for a direct solve)."""
        fes, z = self.fields.fes_z, self.fields.z
        if self.solver == "cg":
            z_trial.vec.data = z.vec  # z^{k-1} is a good initial guess
            cg = CGSolver(self.a_z.mat, self.a_z.mat.CreateSmoother(fes.FreeDofs()),
                          tol=1e-10, maxiter=CG_MAXITER)
            cg.Solve(rhs=self.rhs, sol=z_trial.vec, initialize=False)
            if cg.iterations >= CG_MAXITER:
                raise SolverError(f"the z-solve (CG) did not converge at step {step}; "
                                  "set discretization.z_solver = 'sparsecholesky'")
            return cg.iterations
        if self._inverse is None:
            self._inverse = SystemInverse(self.a_z, fes.FreeDofs(), self.solver)
        z_trial.vec.data = self._inverse.factorize() * self.rhs
        return self._inverse.iterations()

    def _solve_obstacle(self, z_trial: ngs.GridFunction) -> int:
        """The sub-step as min of its quadratic energy over z >= z_old at the nodes
        (:mod:`ngfrac.solve.obstacle`); the minimizer goes to ``z_trial``."""
        lower = self.fields.z if self.lower is None else self.lower
        solution = self._obstacle.solve(self.a_z.mat, self.rhs, lower, z_trial)
        if not solution.converged:
            self.context.timer.add("z: unsettled active sets", 0.0)
        return solution.iterations


def _constant_one(fes: ngs.FESpace, like: ngs.BaseVector) -> ngs.BaseVector:
    """The coefficients of the constant 1 in a scalar H1 space (a vector like ``like``): 1 at
    the vertex dofs (the barycentric hat functions, which sum to one), 0 at the higher-order
    ones."""
    ones = like.CreateVector()
    values = ones.FV().NumPy()
    values[:] = 0.0
    mesh = fes.mesh
    if vertex_dofs_first(fes):
        values[:mesh.nv] = 1.0
    else:
        for vertex in mesh.vertices:
            for dof in fes.GetDofNrs(vertex):
                if dof >= 0:
                    values[dof] = 1.0
    return ones


def _surface_value(stiffness: Any, source: ngs.LinearForm | None, z: ngs.BaseVector,
                   concave: Any = None) -> float:
    """1/2 z.(K + C) z - s.z, summed with :func:`math.fsum` (independent of the thread count)."""
    values = z.FV().NumPy()
    terms = 0.5 * values * (stiffness * z).Evaluate().FV().NumPy()
    if concave is not None:
        terms = terms + 0.5 * values * (concave * z).Evaluate().FV().NumPy()
    if source is not None:
        terms = terms - source.vec.FV().NumPy() * values
    return math.fsum(terms)
