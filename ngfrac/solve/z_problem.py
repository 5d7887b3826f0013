"""The z-sub-problem of one step and the non-repair projection.

    alpha2 (zt - z_old)/dt = eps div(gamma grad zt) - gamma zt/eps + W (1 - zt)   (AT2)
    z = min(1, max(zt, z_old))        at the Lagrange nodes of z

The crack model supplies the surface terms and the drive (:mod:`ngfrac.physics.crack_models`;
AT1 adds a constant source; a model with another degradation g gives the drive
``-1/2 g'(zt) W`` linearized at z_old, :meth:`~ngfrac.physics.crack_models.CrackModel.drive_factors`). The matrix is K + (alpha2/dt) M + D(W): K and M change only with the
mesh and are assembled once per mesh, only the drive part D is assembled per step
(docs/benchmarks.md has the saving). The right-hand side needs no assembly of its own:
int (alpha2/dt z_old + W) w = (alpha2/dt) M z_old + D 1, with 1 the coefficients of the
constant function (the vertex dofs of the hierarchical basis), plus the source assembled
once per mesh and the crack pressure's term per step. A concave surface part C
(PF-CZM's ``-z^2/eps``, :meth:`~ngfrac.physics.crack_models.CrackModel.concave`) stays out of
the matrix and enters the right-hand side at z_old, ``-C z_old`` (assembled once per mesh, one
product per step). The surface energy is a quadratic form of K (and C):
E_surf = 1/2 z.(K + C) z - s.z (s the source), the same sum as its quadrature.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
import ngsolve as ngs
from ngsolve.krylovspace import CGSolver

from ..fem.nodal import vertex_dofs_first
from ..physics.crack_models import CrackModel
from ..scene import Scene
from .context import StepContext
from .obstacle import NodalObstacle
from ..mesh.fields import MeshFields
from .u_problem import SolverError

CG_MAXITER = 2000


class PhaseFieldProblem:
    """Forms and solver of the z-sub-step on one :class:`MeshFields`, and the projection.

    Parameters
    ----------
    fields : MeshFields
        z holds z_old during a step; the sub-step's solution goes to :attr:`z_trial`.
    scene : Scene
    crack_model : CrackModel
    gamma : float or ngsolve.CoefficientFunction
        The toughness.
    drive : ngsolve.CoefficientFunction
        W, the elastic drive (sigma:e at u_prev or u; 2 psi+ with a split; PF-CZM's Rankine
        drive: :meth:`ngfrac.solve.u_problem.DisplacementProblem.drive`).
    context : StepContext
        The step's 1/dt, threads and timer.
    u_drive : ngsolve.GridFunction, optional
        The u of the drive (u_prev or u); with ``phase_field.crack_pressure`` p the right-hand
        side gets ``-p u_drive . grad w``, the z-derivative of the work term ``int p u.grad z``.
    """

    def __init__(self, fields: MeshFields, scene: Scene, crack_model: CrackModel, gamma: Any,
                 drive: ngs.CoefficientFunction, context: StepContext,
                 u_drive: ngs.GridFunction | None = None) -> None:
        self.fields, self.context = fields, context
        inv_dt = context.inv_dt
        pf = scene.phase_field
        self.alpha2, self.solver = pf.alpha2, scene.discretization.z_solver
        update = crack_model.resolve_z_update(scene.discretization.z_update)
        self.update = update
        """The z-update in use: "projection", "descent" or "obstacle"."""
        self.z_trial = ngs.GridFunction(fields.fes_z, "z_trial")
        zt, w = fields.fes_z.TnT()
        dx, eps = fields.dx, pf.epsilon
        factors = crack_model.drive_factors(fields.z)  # z holds z_old during a step
        implicit, explicit = (drive, drive) if factors is None else (factors[0] * drive,
                                                                     factors[1] * drive)
        self.a_z = ngs.BilinearForm(fields.fes_z, symmetric=True)
        self.a_z += implicit * zt * w * dx
        self._drive_rhs = None if factors is None else ngs.LinearForm(explicit * w * dx)
        """int explicit W w, when the drive's two parts differ (else D 1 from the matrix)."""
        self._k = ngs.BilinearForm(fields.fes_z, symmetric=True)
        self._k += crack_model.stiffness(zt, w, gamma, eps) * dx
        self._m = ngs.BilinearForm(fields.fes_z, symmetric=True)
        self._m += zt * w * dx
        concave = crack_model.concave(zt, w, gamma, eps)  # PF-CZM: explicit, -C z_old
        self._concave = None if concave is None else ngs.BilinearForm(fields.fes_z, symmetric=True)
        if concave is not None:
            self._concave += concave * dx
        self._fixed_assembled = False
        source = crack_model.source(w, gamma, eps)  # AT1: -3 gamma/(8 eps) w
        self._source = None if source is None else ngs.LinearForm(source * dx)
        pressure = None
        if pf.pressurized and u_drive is not None:
            pressure = -pf.crack_pressure.to_coefficient(context.time) \
                * ngs.InnerProduct(u_drive, ngs.grad(w))
        self._pressure = None if pressure is None else ngs.LinearForm(pressure * dx)
        self._gamma = gamma
        self._unit_surface: tuple[ngs.BilinearForm, ngs.LinearForm | None] | None = None
        if not isinstance(gamma, (int, float)):  # the crack length: the surface energy at gamma = 1
            unit_k = ngs.BilinearForm(fields.fes_z, symmetric=True)
            unit_k += crack_model.stiffness(zt, w, 1.0, eps) * dx
            unit_concave = crack_model.concave(zt, w, 1.0, eps)
            if unit_concave is not None:  # one matrix for the length: K + C at gamma = 1
                unit_k += unit_concave * dx
            unit_source = crack_model.source(w, 1.0, eps)
            self._unit_surface = (unit_k, None if unit_source is None
                                  else ngs.LinearForm(unit_source * dx))
        self.rhs = fields.z.vec.CreateVector()
        """The right-hand side of the last sub-step."""
        self._ones = None if context.comm.distributed else _constant_one(fields.fes_z, fields.z.vec)
        self._inverse: Any = None
        self._obstacle = NodalObstacle(fields.nodes) if update == "obstacle" else None
        self._distributed: Any = None
        """The communicator's z-system of a distributed mesh (:meth:`Communicator.z_system`)."""
        if context.comm.distributed:  # no AsVector, smoother or direct solve of its matrices
            rhs = (pf.alpha2 * inv_dt * fields.z + explicit) * w
            explicit_concave = crack_model.concave(fields.z, w, gamma, eps)
            if explicit_concave is not None:
                rhs = rhs - explicit_concave
            for part in (source, pressure):
                rhs = rhs if part is None else rhs + part
            self._distributed_rhs = ngs.LinearForm(rhs * dx)
            self._distributed = context.comm.z_system(
                fields.fes_z, (crack_model.stiffness(zt, w, gamma, eps)
                               + pf.alpha2 * inv_dt * zt * w + implicit * zt * w) * dx)
        self.shortened = 0
        """Projections the descent shortened (``discretization.z_update = "descent"``)."""

    def solve(self, step: int | str = "?") -> int:
        """The z-sub-step into :attr:`z_trial`; returns the CG iterations (0 for a direct
        solve; the active-set iterations with ``z_update = "obstacle"``). Raises
        :class:`SolverError`."""
        if self._distributed is not None:
            with self.context.timer.phase("z: assemble and solve"), self.context.threads.solves():
                self._distributed_rhs.Assemble()
                self.rhs.data = self._distributed_rhs.vec
                iterations = self._distributed.solve(self.rhs, self.fields.z.vec,
                                                     self.z_trial.vec, step)
            return iterations
        with self.context.timer.phase("z: assemble"), self.context.threads.assembly(kind="z"):
            self._assemble_system()
        if self._obstacle is not None:
            with self.context.timer.phase("z: obstacle solve"), self.context.threads.solves():
                iterations = self._solve_obstacle()
        else:
            with self.context.timer.phase("z: solve"), self.context.threads.solves():
                iterations = self._solve_system(step)
        if not np.all(np.isfinite(self.z_trial.vec.FV().NumPy())):
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

    def _assemble_system(self) -> None:
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

    def surface_energy(self) -> tuple[float, float] | None:
        """(E_surf, crack_length) of the current z from the assembled K and source.

        1/2 z.(K + C) z - s.z is the crack model's surface energy summed with the forms' quadrature
        (the same rule as the energies' integrals); the crack length is the same at gamma = 1.
        None on a distributed mesh, whose matrices are not local.
        """
        if self._distributed is not None:
            return None
        self._assemble_fixed()
        z = self.fields.z.vec
        e_surf = _surface_value(self._k.mat, self._source, z,
                                None if self._concave is None else self._concave.mat)
        if self._unit_surface is None:
            return e_surf, e_surf / float(self._gamma)
        return e_surf, _surface_value(self._unit_surface[0].mat, self._unit_surface[1], z)

    def _solve_system(self, step: int | str) -> int:
        fes, z = self.fields.fes_z, self.fields.z
        if self.solver == "cg":
            self.z_trial.vec.data = z.vec  # z^{k-1} is a good initial guess
            cg = CGSolver(self.a_z.mat, self.a_z.mat.CreateSmoother(fes.FreeDofs()),
                          tol=1e-10, maxiter=CG_MAXITER)
            cg.Solve(rhs=self.rhs, sol=self.z_trial.vec, initialize=False)
            if cg.iterations >= CG_MAXITER:
                raise SolverError(f"the z-solve (CG) did not converge at step {step}; "
                                  "set discretization.z_solver = 'sparsecholesky'")
            return cg.iterations
        if self._inverse is None:
            self._inverse = self.a_z.mat.Inverse(fes.FreeDofs(), inverse=self.solver)
        else:
            self._inverse.Update()
        self.z_trial.vec.data = self._inverse * self.rhs
        return 0

    def _solve_obstacle(self) -> int:
        """The sub-step as min of its quadratic energy over z >= z_old at the nodes
        (:mod:`ngfrac.solve.obstacle`); the minimizer goes to :attr:`z_trial`."""
        solution = self._obstacle.solve(self.a_z.mat, self.rhs, self.fields.z, self.z_trial)
        if not solution.converged:
            self.context.timer.add("z: unsettled active sets", 0.0)
        return solution.iterations

    def trial_values(self) -> np.ndarray:
        """The sub-step's solution at the Lagrange nodes."""
        return self.fields.nodes.values(self.z_trial)

    def project(self) -> tuple[np.ndarray, np.ndarray]:
        """Non-repair: z = min(1, max(z_trial, z_old)) at the nodes (with
        ``z_update = "descent"`` the energy minimizer between z_old and that projection);
        returns (z_old, z) at the nodes and sets the field z."""
        nodes = self.fields.nodes
        old = nodes.values(self.fields.z)
        new = np.minimum(1.0, np.maximum(self.trial_values(), old))
        if self.update == "descent":
            new = self._descent(old, new)
        nodes.assign(self.fields.z, new)
        return old, new

    def _descent(self, old: np.ndarray, projected: np.ndarray) -> np.ndarray:
        """z_old + theta (P - z_old) with theta in [0, 1] minimizing the z-step's energy.

        The z-step minimizes G(z) = 1/2 z.A z - f.z (A, f: the assembled z-forms, which hold
        z_old). Every point between z_old and the projection P is feasible (both are), G is
        quadratic along the segment, so the exact minimizer over it never exceeds G(z_old).
        """
        direction_nodes = projected - old
        if not np.any(direction_nodes):
            return projected
        z_old = self.fields.z.vec.CreateVector()
        z_old.data = self.fields.z.vec  # z still holds z_old here
        direction = ngs.GridFunction(self.fields.fes_z)
        self.fields.nodes.assign(direction, direction_nodes)
        matrix = self.a_z.mat if self._distributed is None else self._distributed.form.mat
        a_d = (matrix * direction.vec).Evaluate()
        curvature = ngs.InnerProduct(direction.vec, a_d)
        slope = ngs.InnerProduct(z_old, a_d) - ngs.InnerProduct(self.rhs, direction.vec)
        theta = 1.0 if curvature <= 0 else min(1.0, max(0.0, -slope / curvature))
        if theta < 1.0:
            self.shortened += 1
            self.context.timer.add("z: shortened projections", 0.0)
        return old + theta * direction_nodes


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
