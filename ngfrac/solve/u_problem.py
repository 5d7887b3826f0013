"""The u-sub-problem of one step: the degraded elastic equation for the current z.

    alpha1 (u - u_prev)/dt = div((g(z) + eta) sigma[u]) + f - p grad z     u = g_D(t) on Gamma_D
                                                          sigma n = t_N(t) on Gamma_N

One linear solve (a factorization made once per mesh and numerically updated after each
assembly, or CG with BDDC), or Newton on the energy with a tension/compression split
(:mod:`ngfrac.physics.splits`; with ``material.split_mode = "hybrid"`` the split only drives z
and the u-step stays linear). Its residual gives the reaction forces
(:mod:`ngfrac.post.reactions`).
"""
from __future__ import annotations

from contextlib import contextmanager
from typing import Any, Iterator

import numpy as np
import ngsolve as ngs

from ..physics.crack_models import CrackModel
from ..physics.elastic import Elasticity, traction_of
from ..fem.newton import NewtonResult, NewtonSolver
from ..physics.splits import make_split, tangent_integrators
from ..scene import Scene
from ..fem.linear import SystemInverse, register_preconditioner, resolve_u_solver
from ..fem.p1_elasticity import P1ElasticStiffness
from .context import StepContext
from ..fem.quadrature import dx_of_order
from ..mesh.fields import MeshFields
from ..fem.threads import integrate


class SolverError(RuntimeError):
    """A linear solve failed or produced non-finite values."""


class NewtonFailure(SolverError):
    """Newton's u-solve (with a split) did not converge: the stepper redoes the step with
    half the time step while it can (:meth:`ngfrac.solve.time_control.StepSizeControl.halve`)."""


class DisplacementProblem:
    """Forms, solver and residual of the u-sub-step on one :class:`MeshFields`.

    Parameters
    ----------
    fields : MeshFields
        u is solved for in place; z and u_prev are read.
    scene : Scene
    model : ElasticModel
        The elastic model (:func:`ngfrac.scene.build.elastic_model_of`).
    crack_model : CrackModel
        Its degradation g(z) multiplies the stress.
    context : StepContext
        The step's time and 1/dt, threads and timer.
    """

    def __init__(self, fields: MeshFields, scene: Scene, model: Any, crack_model: CrackModel,
                 context: StepContext) -> None:
        self.fields, self.model, self.context, self.scene = fields, model, context, scene
        time, inv_dt = context.time, context.inv_dt
        pf, disc = scene.phase_field, scene.discretization
        self.eta = pf.residual_stiffness
        fes, dx = fields.fes_u, fields.dx
        self.dirichlet = DirichletValues(fes, model, model.boundary_values(fields.mesh, scene.loads, time))
        material = scene.material
        self.drive_split = make_split(model, material.split)
        """The split of the drive W (with ``split_mode = "hybrid"`` only of the drive)."""
        self.hybrid = material.split_mode == "hybrid"
        self.split = None if self.hybrid else self.drive_split
        """The split of the u-step's energy (Newton), None for the isotropic, linear u-step."""
        self.crack_model = crack_model
        self.rankine = pf.drive == "rankine"
        self.degradation = crack_model.degradation(fields.z, self.eta)
        u, v = fes.TnT()
        stiffness = self.degradation * model.stress_strain(u, v)
        if self.split is not None:  # nonlinear: a_u is the tangent at the current u
            stiffness = self.split.tangent(fields.u, u, v, self.degradation)
        if pf.alpha1 > 0:
            stiffness = stiffness + pf.alpha1 * inv_dt * u * v
        self.a_u = ngs.BilinearForm(fes, symmetric=True)
        with tangent_integrators(self.split):
            self.a_u += stiffness * dx
        # MPI: CG with BDDC; "auto": by the mesh (ngfrac.fem.linear.resolve_u_solver)
        solver = context.comm.u_solver(resolve_u_solver(disc.u_solver, fields.mesh))
        pre = register_preconditioner(self.a_u, solver)  # before any assembly
        self.linear = SystemInverse(self.a_u, fes.FreeDofs(), solver, pre)
        self.m_u = (ngs.BilinearForm(pf.alpha1 * u * v * dx, symmetric=True).Assemble()
                    if pf.alpha1 > 0 else None)
        self.body_force = model.body_force(scene.material, time)
        self.f_u = self._load_form(scene, v)
        self._newton = self._newton_solver(pf.alpha1) if self.split is not None else None
        self.indicators: dict = {}
        """Reaction test functions of this mesh (:func:`ngfrac.post.reactions.reaction`)."""
        self._element_weights_wanted = (
            fields.mesh.dim == 3 and self.split is None and pf.alpha1 == 0
            and crack_model.quadratic_degradation and isinstance(model, Elasticity)
            and P1ElasticStiffness.applies(fes, fields.fes_z))
        """3D P1 u and z, linear u-step, g = (1 - z)^2 + eta: after NGSolve's first assembly
        the matrix is assembled from element weights (:mod:`ngfrac.fem.p1_elasticity`)."""
        self._element_weights: P1ElasticStiffness | None = None

    def _load_form(self, scene: Scene, v: Any) -> ngs.LinearForm | None:
        """f_u: the body force, the tractions and pressures on the boundary (not degraded)
        and the crack pressure ``-p grad z . v`` (the u-derivative of ``int p u.grad z``);
        None when all are absent, so that scenes without them assemble nothing."""
        f, time = self.fields, self.context.time
        # a body force is any expression: its quadrature keeps two orders above the forms'
        dx_f = dx_of_order(f.mesh, f.integration_order + 2)
        terms = [] if self.body_force is None else [self.body_force * v * dx_f]
        boundary = self.model.boundary_force(f.mesh, scene.loads, time, v)
        if boundary is not None:
            terms.append(boundary)
        if scene.phase_field.pressurized:
            p = scene.phase_field.crack_pressure.to_coefficient(time)
            terms.append(-p * ngs.InnerProduct(ngs.grad(f.z), v) * f.dx)
        if not terms:
            return None
        return ngs.LinearForm(sum(terms[1:], terms[0]))

    def surface_work(self) -> float | None:
        """The work of the tractions, pressures and the crack pressure at the current u and z,
        ``int_Gamma_N t.u ds - int p u.grad z``, or None without any (E_total subtracts it
        with the body force's work)."""
        f, scene, time = self.fields, self.scene, self.context.time
        boundary = [load for load in scene.loads if not load.is_dirichlet]
        total = None
        for load in boundary:
            traction = traction_of(load, f.mesh, time)
            density = traction * f.u if f.u.dim == 1 else ngs.InnerProduct(traction, f.u)
            value = float(integrate(density, f.mesh, order=f.integration_order, vb=ngs.BND,
                                    definedon=f.mesh.Boundaries(load.boundary)))
            total = value if total is None else total + value
        if scene.phase_field.pressurized:
            p = scene.phase_field.crack_pressure.to_coefficient(time)
            value = -float(integrate(p * ngs.InnerProduct(f.u, ngs.grad(f.z)), f.mesh,
                                     order=f.integration_order))
            total = value if total is None else total + value
        return total

    @property
    def iterations(self) -> int:
        """CG iterations of the last linear solve (0 for a direct solver or before one)."""
        return 0 if self.linear.inverse is None else self.linear.iterations()

    @property
    def newton(self) -> NewtonResult | None:
        """The last Newton solve (with a split)."""
        return None if self._newton is None else self._newton.last

    def apply_boundary_values(self) -> None:
        """Set u's Dirichlet dofs to the boundary values at the current time."""
        self.dirichlet.apply(self.fields.u)

    @contextmanager
    def static(self) -> Iterator[None]:
        """1/dt = 0 inside: :meth:`solve` then solves the elastic problem without the alpha1
        term (the initial state u0), and :meth:`residual` is its residual."""
        inv_dt = self.context.inv_dt.Get()
        self.context.inv_dt.Set(0.0)
        try:
            yield
        finally:
            self.context.inv_dt.Set(inv_dt)

    def solve(self, step: int | str = "?") -> None:
        """The u-sub-step for the current z, time and u_prev; ``step`` names the step in
        error messages. Raises :class:`SolverError`."""
        self.apply_boundary_values()
        if self.split is not None:
            self._solve_newton(step)
        else:
            self._solve_linear(step)
        if not np.all(np.isfinite(self.fields.u.vec.FV().NumPy())):
            raise SolverError(f"the u-solve gave non-finite values at step {step}; "
                              "raise phase_field.residual_stiffness or lower time.dt")

    def _at_rest(self) -> bool:
        """u = 0 (boundary values included), no load form and no alpha1 term from a non-zero
        u_prev: the residual is 0 without an assembly (u0 of a scene unloaded at t = 0).
        Collective norms under MPI, so every rank decides alike."""
        f = self.fields
        return (self.f_u is None and f.u.vec.Norm() == 0.0
                and (self.m_u is None or f.u_prev.vec.Norm() == 0.0))

    def _solve_linear(self, step: int | str) -> None:
        if self._at_rest():  # the solution is u = 0: no assembly, no factorization
            return
        with self.context.timer.phase("u: assemble"), self.context.threads.assembly(self.linear.preconditioner, "u"):
            self._assemble_stiffness()
            if self.f_u is not None:
                self.f_u.Assemble()
        with self.context.timer.phase("u: residual"), self.context.threads.solves():
            u = self.fields.u.vec
            residual = u.CreateVector()
            if self.m_u is not None:
                residual.data = self.context.inv_dt.Get() * (self.m_u.mat * self.fields.u_prev.vec) \
                    - self.a_u.mat * u
            else:
                residual.data = -self.a_u.mat * u
            if self.f_u is not None:
                residual.data += self.f_u.vec
            # exactly zero (loads that vanish at t = 0): the solution is u, no factorization
            if residual.Norm() == 0.0:
                return
        with self.context.timer.phase("u: factorize"), self.context.threads.solves():
            inverse = self.linear.factorize()
        with self.context.timer.phase("u: solve"), self.context.threads.solves():
            u.data += inverse * residual
            try:
                self.linear.iterations()
            except RuntimeError as err:
                raise SolverError(f"the u-solve failed at step {step}: {err}; "
                                  "set discretization.u_solver = 'sparsecholesky'") from None

    def _assemble_stiffness(self) -> None:
        """``a_u`` for the current z: by NGSolve, or by element weights into the matrix NGSolve
        assembled first on this mesh (3D P1, see ``_element_weights_wanted``)."""
        weights = self._element_weights
        if weights is not None and weights.writes_into(self.a_u.mat):
            weights.assemble(self.fields.z)
            return
        self.a_u.Assemble()
        if self._element_weights_wanted and isinstance(self.a_u.mat, ngs.la.SparseMatrixd):
            self._element_weights = P1ElasticStiffness(self.a_u.mat, self.fields.fes_u,
                                                       self.model.lam, self.model.mu, self.eta)

    def _solve_newton(self, step: int | str) -> None:
        rhs = self.fields.u.vec.CreateVector()
        rhs[:] = 0.0
        if self.m_u is not None:
            rhs.data = self.context.inv_dt.Get() * (self.m_u.mat * self.fields.u_prev.vec)
        if self.f_u is not None:
            self.f_u.Assemble()
            rhs.data += self.f_u.vec
        with self.context.timer.phase("u: newton"):
            try:
                self._newton.solve(rhs)
            except RuntimeError as err:
                raise NewtonFailure(f"the u-solve (material.split = {self.split.kind!r}) failed at "
                                    f"step {step}: {err}; lower time.dt (with time.adaptive = "
                                    "true a failed step is first redone with half the step, "
                                    "down to time.dt)") from None

    def _newton_solver(self, alpha1: float) -> NewtonSolver:
        """Newton for the split problem; alpha1 > 0 adds the energy of the alpha1 term (its
        linear part is the solve's right-hand side)."""
        f = self.fields
        energy = self.split.elastic_density(f.u, self.degradation)
        if alpha1 > 0:
            energy = energy + 0.5 * alpha1 * self.context.inv_dt * ngs.InnerProduct(f.u, f.u)
        return NewtonSolver(self.a_u, f.u, energy, f.integration_order, f.fes_u.FreeDofs(),
                            self.linear.solver, preconditioner=self.linear.preconditioner,
                            solves=self.context.threads.solves)

    def residual(self) -> ngs.BaseVector:
        """``R = A u - (1/dt) M u_prev - f`` with the forms of the last solve (A holds
        alpha1/dt M); zero at the free dofs, the reactions at the Dirichlet dofs."""
        if self._at_rest():  # 0 without assembling A (A 0 = 0 exactly)
            r = self.fields.u.vec.CreateVector()
            r[:] = 0.0
            return r
        try:
            matrix = self.a_u.mat
        except TypeError:  # not assembled yet
            self._assemble_stiffness()
            matrix = self.a_u.mat
        f = self.fields
        r = f.u.vec.CreateVector()
        r.data = matrix * f.u.vec
        if self.m_u is not None:  # m_u holds alpha1 M; the step's 1/dt is a Parameter
            r.data -= self.context.inv_dt.Get() * (self.m_u.mat * f.u_prev.vec)
        if self.f_u is not None:
            r.data -= self.f_u.vec
        return r

    def drive(self, u: ngs.GridFunction) -> ngs.CoefficientFunction:
        """W of the z-equation at ``u``: sigma:e, or 2 psi+ with a split (hybrid: 0 where
        psi+ < psi-), or PF-CZM's Rankine ``<sigma_1>^2/E`` (``phase_field.drive``)."""
        if self.rankine:
            return self.crack_model.rankine_drive(self.model.stress(u), self.model.n_components)
        if self.drive_split is None:
            return self.model.energy_density(u)
        return self.drive_split.hybrid_drive(u) if self.hybrid else self.drive_split.drive(u)

    def elastic_density(self) -> ngs.CoefficientFunction:
        """W with E_el = 1/2 int (g(z) + eta) W at the current u: sigma:e, or with a split
        2 ((g + eta) psi+ + psi-) / (g + eta)."""
        f = self.fields
        if self.split is None:
            return self.model.energy_density(f.u)
        return 2 * self.split.elastic_density(f.u, self.degradation) / self.degradation


class DirichletValues:
    """The Dirichlet values of u: interpolated into a GridFunction, copied to u's fixed dofs.

    Parameters
    ----------
    fes : ngsolve.FESpace
        The space of u.
    model : ElasticModel
        Interpolates the boundary values (``model.set_boundary``).
    values : ngsolve.CoefficientFunction
        The boundary values (they depend on the time Parameter).
    """

    def __init__(self, fes: ngs.FESpace, model: Any, values: Any) -> None:
        self.model, self.values = model, values
        self.gf = ngs.GridFunction(fes, "u_boundary")
        # a numpy mask, once per mesh: the BitArray conversion cost a quarter of a u-solve
        self.fixed = ~np.array(fes.FreeDofs(), dtype=bool)

    def apply(self, u: ngs.GridFunction) -> None:
        """Set u's Dirichlet dofs to the values at the current time."""
        self.model.set_boundary(self.gf, self.values)
        u.vec.FV().NumPy()[self.fixed] = self.gf.vec.FV().NumPy()[self.fixed]
