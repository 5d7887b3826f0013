"""The z-sub-problem of one step and the non-repair projection.

    alpha2 (zt - z_old)/dt = eps div(gamma grad zt) - gamma zt/eps + W (1 - zt)   (AT2)
    z = min(1, max(zt, z_old))        at the Lagrange nodes of z

The crack model supplies the surface terms (:mod:`ngfrac.physics.crack_models`; AT1 adds a
constant source). The matrix is K + (alpha2/dt) M + D(W): K and M change only with the
mesh and are assembled once per mesh, only the drive part D is assembled per step
(docs/benchmarks.md has the saving).
"""
from __future__ import annotations

from typing import Any

import numpy as np
import ngsolve as ngs
from ngsolve.krylovspace import CGSolver

from ..physics.crack_models import CrackModel
from ..scene import Scene
from .context import StepContext
from .obstacle import NodalObstacle
from .spaces import MeshFields
from .threads import parallel
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
        W, the elastic drive (sigma:e at u_prev or u; 2 psi+ with a split).
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
        self.a_z = ngs.BilinearForm(fields.fes_z, symmetric=True)
        self.a_z += drive * zt * w * dx
        self._k = ngs.BilinearForm(fields.fes_z, symmetric=True)
        self._k += crack_model.stiffness(zt, w, gamma, eps) * dx
        self._m = ngs.BilinearForm(fields.fes_z, symmetric=True)
        self._m += zt * w * dx
        self._fixed_assembled = False
        rhs = (pf.alpha2 * inv_dt * fields.z + drive) * w
        source = crack_model.source(w, gamma, eps)  # AT1: -3 gamma/(8 eps) w
        if pf.pressurized and u_drive is not None:
            pressure = -pf.crack_pressure.to_coefficient(context.time) \
                * ngs.InnerProduct(u_drive, ngs.grad(w))
            source = pressure if source is None else source + pressure
        self.f_z = ngs.LinearForm((rhs if source is None else rhs + source) * dx)
        self._inverse: Any = None
        self._obstacle = NodalObstacle(fields.nodes) if update == "obstacle" else None
        self._distributed: DistributedSystem | None = None
        if context.comm.distributed:  # no AsVector, smoother or direct solve of its matrices
            self._distributed = DistributedSystem(
                fields.fes_z, (crack_model.stiffness(zt, w, gamma, eps)
                               + pf.alpha2 * inv_dt * zt * w + drive * zt * w) * dx,
                context.comm.z_preconditioner)
        self.shortened = 0
        """Projections the descent shortened (``discretization.z_update = "descent"``)."""

    def solve(self, step: int | str = "?") -> int:
        """The z-sub-step into :attr:`z_trial`; returns the CG iterations (0 for a direct
        solve; the active-set iterations with ``z_update = "obstacle"``). Raises
        :class:`SolverError`."""
        if self._distributed is not None:
            with self.context.timer.phase("z: assemble and solve"), self.context.threads.solves():
                self.f_z.Assemble()
                iterations = self._distributed.solve(self.f_z.vec, self.fields.z.vec,
                                                     self.z_trial.vec, step)
            return iterations
        with self.context.timer.phase("z: assemble"), parallel():
            self._assemble_matrix()
            self.f_z.Assemble()
        if self._obstacle is not None:
            with self.context.timer.phase("z: obstacle solve"), self.context.threads.solves():
                iterations = self._solve_obstacle()
        else:
            with self.context.timer.phase("z: solve"), self.context.threads.solves():
                iterations = self._solve_system(step)
        if not np.all(np.isfinite(self.z_trial.vec.FV().NumPy())):
            raise SolverError(f"the z-solve gave non-finite values at step {step}; lower time.dt")
        return iterations

    def _assemble_matrix(self) -> None:
        """a_z.mat = K + (alpha2/dt) M + D(W): D assembled, K and M once per mesh."""
        if not self._fixed_assembled:
            self._k.Assemble()
            self._m.Assemble()
            self._fixed_assembled = True
        self.a_z.Assemble()
        values = self.a_z.mat.AsVector()
        k, m = self._k.mat.AsVector(), self._m.mat.AsVector()
        if not (len(values) == len(k) == len(m)):  # never seen; the forms share fes_z
            raise RuntimeError("the z-forms do not share a sparsity pattern")
        values.data += k + (self.alpha2 * self.context.inv_dt.Get()) * m

    def _solve_system(self, step: int | str) -> int:
        fes, z = self.fields.fes_z, self.fields.z
        if self.solver == "cg":
            self.z_trial.vec.data = z.vec  # z^{k-1} is a good initial guess
            cg = CGSolver(self.a_z.mat, self.a_z.mat.CreateSmoother(fes.FreeDofs()),
                          tol=1e-10, maxiter=CG_MAXITER)
            cg.Solve(rhs=self.f_z.vec, sol=self.z_trial.vec, initialize=False)
            if cg.iterations >= CG_MAXITER:
                raise SolverError(f"the z-solve (CG) did not converge at step {step}; "
                                  "set discretization.z_solver = 'sparsecholesky'")
            return cg.iterations
        if self._inverse is None:
            self._inverse = self.a_z.mat.Inverse(fes.FreeDofs(), inverse=self.solver)
        else:
            self._inverse.Update()
        self.z_trial.vec.data = self._inverse * self.f_z.vec
        return 0

    def _solve_obstacle(self) -> int:
        """The sub-step as min of its quadratic energy over z >= z_old at the nodes
        (:mod:`ngfrac.solve.obstacle`); the minimizer goes to :attr:`z_trial`."""
        solution = self._obstacle.solve(self.a_z.mat, self.f_z.vec, self.fields.z, self.z_trial)
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
        slope = ngs.InnerProduct(z_old, a_d) - ngs.InnerProduct(self.f_z.vec, direction.vec)
        theta = 1.0 if curvature <= 0 else min(1.0, max(0.0, -slope / curvature))
        if theta < 1.0:
            self.shortened += 1
            self.context.timer.add("z: shortened projections", 0.0)
        return old + theta * direction_nodes


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
