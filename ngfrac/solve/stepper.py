"""The time stepper: the semi-implicit staggered scheme of the paper (its equation 7).

Step k, from t_{k-1} to t_k = t_{k-1} + dt (all times on the grid n * time.dt)::

    alpha1 (u^k - u^{k-1})/dt = div(((1 - z^{k-1})^2 + eta) sigma[u^k])       u = g(t_k) on Gamma_D
    alpha2 (zt - z^{k-1})/dt  = eps div(gamma grad zt) - gamma zt/eps + W (1 - zt)
    z^k = min(1, max(zt, z^{k-1}))        at the Lagrange nodes of z

with ``W = sigma[u^{k-1}]:e[u^{k-1}]`` (``coupling = "paper"``) or ``sigma[u^k]:e[u^k]``
(``coupling = "staggered"``). Both sub-steps are linear; forms are built once per mesh and
only reassembled, and the u-factorization is reused with a numeric update.
"""
from __future__ import annotations

import logging
import math
import time
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass, field, fields
from typing import Iterator

import numpy as np
import ngsolve as ngs
from ngsolve.krylovspace import CGSolver

from ..mesh.adapter import Adaptation, MeshAdapter
from ..physics.cracks import distance_to_cracks, initial_tip
from ..physics.crack_models import crack_model
from ..post.crackset import CrackSet, NodeGraph, find_crack
from ..post.diagnostics import element_diameters, energies
from ..mesh.domains import build_mesh
from ..physics.elastic import make_model
from .nodal import LagrangeNodes
from .profiling import PhaseTimer
from ..post.reactions import reaction_columns
from ..scene import Scene
from .linear import iterations as solver_iterations, register_preconditioner, u_inverse, update
from ..physics.splits import NewtonSolver, make_split, tangent_integrators
from .threads import parallel, serial
from ..mesh.transfer import crack_length, evaluate, locate, transfer, transfer_phase_field

log = logging.getLogger(__name__)

OPEN_LEVEL = 0.95
"""After a mesh change z is restored where one z-sub-step gives at least this (the open crack)."""


class SolverError(RuntimeError):
    """A linear solve failed or produced non-finite values."""


@dataclass(frozen=True)
class StepRecord:
    """What one step reports. Diagnostic fields are NaN on steps that skip diagnostics.

    ``eta_total`` is the estimator total of the last adaptation, ``n_adapt`` the number of
    mesh changes so far, ``step_s`` the wall time of this step, ``solve_s`` the part in the two
    sub-steps (assembly and linear solves) and ``adapt_s`` the part spent changing the mesh.
    """

    step: int
    t: float
    wall_s: float
    nv: int
    ndof: int
    hmin: float = math.nan
    hmax: float = math.nan
    E_el: float = math.nan
    E_surf: float = math.nan
    E_total: float = math.nan
    crack_length: float = math.nan
    tip_x: float = math.nan
    tip_y: float = math.nan
    path_length: float = math.nan
    """Geometric length of the crack: the initial cracks plus the grown ridge (2D; NaN in 3D)."""
    n_damage_zones: int = 0
    """Components of {z >= 1/2} other than the crack (ngfrac.post.crackset)."""
    dz_max: float = math.nan
    z_iterations: int = 0
    dt: float = math.nan
    eta_total: float = math.nan
    n_adapt: int = 0
    step_s: float = math.nan
    solve_s: float = math.nan
    adapt_s: float = 0.0
    forces: dict[str, float] = field(default_factory=dict)
    """Reaction force and mean displacement per loaded boundary: ``Fx_top``, ``ux_top``, ..."""
    tip_z: float = math.nan
    """z of the tip, a column of 3D runs only (after tip_y)."""
    dim: int = 2
    """Dimension of the domain (not a column)."""

    NOT_FIXED = ("forces", "tip_z", "dim")

    @property
    def has_diagnostics(self) -> bool:
        return not math.isnan(self.E_total)

    @classmethod
    def columns(cls) -> list[str]:
        """The fixed columns (without tip_z and the per-boundary force columns)."""
        return [f.name for f in fields(cls) if f.name not in cls.NOT_FIXED]

    def _names(self) -> list[str]:
        names = self.columns()
        if self.dim == 3:
            names.insert(names.index("tip_y") + 1, "tip_z")
        return names

    def header(self) -> list[str]:
        """All column names of this record: the fixed ones (and tip_z in 3D), then the
        force columns."""
        return self._names() + list(self.forces)

    def row(self) -> list[float | int]:
        return [getattr(self, name) for name in self._names()] + list(self.forces.values())


class PhaseFieldStepper:
    """Owns mesh, spaces, forms and state of one run.

    Parameters
    ----------
    scene : Scene
        The validated run description.
    mesh : ngsolve.Mesh, optional
        A mesh to use instead of the uniform mesh the scene describes.

    Examples
    --------
    >>> stepper = PhaseFieldStepper(load_scene("demos/mode3_slit.toml"))  # doctest: +SKIP
    >>> for record in stepper.run():                                        # doctest: +SKIP
    ...     print(record.t, record.tip_x)
    """

    def __init__(self, scene: Scene, mesh: ngs.Mesh | None = None) -> None:
        self._scene = scene
        self.model = make_model(scene)
        self.crack_model = crack_model(scene.phase_field.model)
        """The phase-field functional (:mod:`ngfrac.physics.crack_models`)."""
        self.k = 0
        self.ticks = 0
        """Time as a count of ``time.dt``: t = ticks * dt, exact for any number of steps."""
        self.level = scene.time.max_doublings if scene.time.adaptive else 0
        """Current step is dt * 2**level (adaptive time steps)."""
        self.timer = PhaseTimer()
        self.time = ngs.Parameter(0.0)
        self.inv_dt = ngs.Parameter(1.0 / scene.time.dt)
        self._started = time.perf_counter()
        self._polylines = [crack.points for crack in scene.cracks]
        self._start_tip = (initial_tip(scene.cracks[0].points, self._on_boundary)
                           if scene.cracks else None)
        self.nucleus: np.ndarray | None = None
        """With no initial crack: where z first reached 1/2 (the crack grows from there)."""
        self.previous_tip: np.ndarray | None = None
        """The last tip found (:func:`ngfrac.post.crackset.find_crack` keeps it while it is farther
        along the crack than a new estimate)."""
        self._crack_cache: tuple[bytes, CrackSet] | None = None
        gamma = scene.material.gamma
        # A constant toughness stays a number: no coefficient evaluation in the forms.
        self.gamma = gamma.value() if gamma.is_constant else gamma.to_coefficient()
        self.adapter = MeshAdapter(scene) if scene.adaptivity.enabled else None
        self.adaptations: list[Adaptation] = []
        self.forces: dict[str, float] = {}  # reaction columns of the last diagnosed u-solve
        given = mesh is not None
        if mesh is None:
            size = self.adapter.sizes.hmax if self.adapter else scene.mesh_size
            mesh = build_mesh(scene.geometry, size, self._polylines)
        self._setup(mesh)
        self._set_initial_state()
        if self.adapter is not None and not given:
            self._adapt_initial_mesh()

    @property
    def scene(self) -> Scene:
        """The scene this stepper was built for (read-only: its forms, spaces and loads are
        made from it; for another scene build a new stepper, e.g. from
        ``dataclasses.replace(stepper.scene, ...)``)."""
        return self._scene

    @scene.setter
    def scene(self, value: Scene) -> None:
        raise AttributeError("a stepper's scene cannot be changed: its forms, spaces and loads "
                             "were built from it; make a new PhaseFieldStepper(new_scene)")

    def _on_boundary(self, point: np.ndarray) -> bool:
        """Whether a point lies on the boundary of the scene's rectangle or box."""
        g = self.scene.geometry
        tol = 1e-10 * max(g.extent)
        return any(abs(p - o) <= tol or abs(p - o - e) <= tol
                   for p, o, e in zip(point, g.origin, g.extent))

    # -- set-up -----------------------------------------------------------------------------
    def _setup(self, mesh: ngs.Mesh) -> None:
        """Spaces, GridFunctions and forms on ``mesh`` (called again after a mesh change)."""
        sc = self.scene
        pf, disc = sc.phase_field, sc.discretization
        self.mesh = mesh
        self.fes_u = self.model.space(mesh, disc.order, sc.loads)
        self.fes_z = ngs.H1(mesh, order=disc.z_order)
        self.nodes = LagrangeNodes(self.fes_z)
        self.u = ngs.GridFunction(self.fes_u, "u")
        self.u_prev = ngs.GridFunction(self.fes_u, "u_prev")
        self.z = ngs.GridFunction(self.fes_z, "z")
        self.z_trial = ngs.GridFunction(self.fes_z, "z_trial")
        self.u_boundary = ngs.GridFunction(self.fes_u, "u_boundary")
        # Dirichlet dofs as a numpy mask, once per mesh: converting the BitArray costs 8-62 ms
        # (18k-46k dofs), a quarter to a half of a u-solve when it was done at every solve.
        self._fixed_u_dofs = ~np.array(self.fes_u.FreeDofs(), dtype=bool)
        self._boundary_cf = self.model.boundary_values(mesh, sc.loads, self.time)
        self._sizes: np.ndarray | None = None
        self._node_graph: NodeGraph | None = None
        self._crack_cache = None
        self.indicators: dict = {}  # reaction-force test functions of this mesh

        inv_dt = self.inv_dt
        # One quadrature, exact for constant gamma, in every form and energy: the u-step then
        # minimizes exactly the energy that the diagnostics report.
        self.integration_order = 2 * disc.order + 2 * disc.z_order
        element = ngs.TET if mesh.dim == 3 else ngs.TRIG
        dx = ngs.dx(intrules={element: ngs.IntegrationRule(element, self.integration_order)})
        self.dx = dx
        u, v = self.fes_u.TnT()
        stiffness = self.crack_model.degradation(self.z, pf.residual_stiffness) * self.model.stress_strain(u, v)
        self.split = make_split(self.model, sc.material.split)
        if self.split is not None:  # nonlinear: a_u is the tangent at the current u (ngfrac.physics.splits)
            stiffness = self.split.tangent(self.u, u, v, self.z, pf.residual_stiffness)
        if pf.alpha1 > 0:
            stiffness = stiffness + pf.alpha1 * inv_dt * u * v
        self.a_u = ngs.BilinearForm(self.fes_u, symmetric=True)
        with tangent_integrators(self.split):
            self.a_u += stiffness * dx
        self._pre_u = register_preconditioner(self.a_u, disc.u_solver)  # before any assembly
        self.m_u = None
        if pf.alpha1 > 0:
            self.m_u = ngs.BilinearForm(pf.alpha1 * u * v * dx, symmetric=True).Assemble()
        self._inv_u = None
        self.body_force = self.model.body_force(sc.material, self.time)
        self.f_u = None if self.body_force is None else ngs.LinearForm(self.body_force * v * dx)
        if self.split is not None:
            self._newton = self._newton_solver(self.a_u, pf.alpha1, self._pre_u)

        drive = self.u_prev if disc.coupling == "paper" else self.u
        self._drive = (self.model.energy_density(drive) if self.split is None
                       else self.split.drive(drive))  # 2 psi+ with a split
        zt, w = self.fes_z.TnT()
        gamma, eps = self.gamma, pf.epsilon
        # The z-matrix is  K + (alpha2/dt) M + D(u):  K and M change only with the mesh, so
        # they are assembled once per mesh and only the drive part D is assembled per step
        # (its matrix then receives K + (alpha2/dt) M; all three share the sparsity pattern
        # of fes_z). Assembling all of it every step cost ~30 % more (docs/benchmarks.md).
        self.a_z = ngs.BilinearForm(self.fes_z, symmetric=True)
        self.a_z += self._drive * zt * w * dx
        self._k_z = ngs.BilinearForm(self.fes_z, symmetric=True)
        self._k_z += self.crack_model.stiffness(zt, w, gamma, eps) * dx
        self._m_z = ngs.BilinearForm(self.fes_z, symmetric=True)
        self._m_z += zt * w * dx
        self._z_fixed_assembled = False
        rhs = (pf.alpha2 * inv_dt * self.z + self._drive) * w
        source = self.crack_model.source(w, gamma, eps)  # AT1: -3 gamma/(8 eps) w
        self.f_z = ngs.LinearForm((rhs if source is None else rhs + source) * dx)
        self._inv_z = None

    def _set_initial_state(self) -> None:
        """z0 = the crack model's optimal profile of the distance to the initial cracks at the
        nodes (AT2: exp(-dist/eps)); u0 solves the elastic problem at t = 0."""
        if self._polylines:
            distance = distance_to_cracks(self.nodes.points, self._polylines)
            self.nodes.assign(self.z, self.crack_model.profile(distance, self.scene.phase_field.epsilon))
        else:
            self.z.vec[:] = 0.0
        self.time.Set(0.0)
        self.u.vec[:] = 0.0
        self._apply_boundary_values()
        if self.split is not None:
            self._solve_u_split(initial=True)
            self.u_prev.vec.data = self.u.vec
            self.forces = reaction_columns(self)
            return
        pf = self.scene.phase_field
        u, v = self.fes_u.TnT()
        static = ngs.BilinearForm(self.fes_u, symmetric=True)
        static += (self.crack_model.degradation(self.z, pf.residual_stiffness)
                   * self.model.stress_strain(u, v) * self.dx)
        solver = self.scene.discretization.u_solver
        pre = register_preconditioner(static, solver)
        with self._assembly_threads(pre):
            static.Assemble()
            residual = (-static.mat * self.u.vec).Evaluate()
            if self.f_u is not None:
                self.f_u.Assemble()
                residual.data += self.f_u.vec
        with self._solves():
            inverse = u_inverse(static, self.fes_u.FreeDofs(), solver, pre)
            self.u.vec.data += inverse * residual
        self.u_prev.vec.data = self.u.vec
        self.forces = reaction_columns(self)

    # -- threads (ngfrac.solve.threads) -------------------------------------------------------------
    def _step_threads(self) -> AbstractContextManager:
        """The context of a whole step: NGSolve's TaskManager with
        ``discretization.threaded_solves`` (results then vary with the schedule), else none."""
        return parallel() if self.scene.discretization.threaded_solves else nullcontext()

    def _solves(self) -> AbstractContextManager:
        """The context of factorizations, solves, estimators and remeshing: one thread (bitwise
        reproducible) unless ``discretization.threaded_solves``."""
        return nullcontext() if self.scene.discretization.threaded_solves else serial()

    def _assembly_threads(self, preconditioner: object = None) -> AbstractContextManager:
        """Threads for an assembly, unless it also sets up a registered preconditioner
        (BDDC factorizes inside the assembly)."""
        return parallel() if preconditioner is None else self._solves()

    # -- mesh adaptation --------------------------------------------------------------------
    INITIAL_PASSES = 3

    def _adapt_initial_mesh(self) -> None:
        """Resolve z0 before the first step: remesh and set z0 anew from its formula."""
        assert self.adapter is not None
        for _ in range(self.INITIAL_PASSES):
            with self._solves():
                mesh, _ = self.adapter.new_mesh(self.mesh, self.nodes, self.z, self.tip())
            self._setup(mesh)
            self._set_initial_state()
        self.adapter.remember(self.mesh, self.nodes, self.z_node_values(), self.tip())

    def crack(self) -> CrackSet:
        """The crack set of the current z: tip, ridge, grown length, other damage zones
        (:func:`ngfrac.post.crackset.find_crack`)."""
        values = self.nodes.values(self.z)
        key = values.tobytes()
        if self._crack_cache is not None and self._crack_cache[0] == key:
            return self._crack_cache[1]
        if self._sizes is None:
            self._sizes = element_diameters(self.mesh)
        if self._node_graph is None:
            self._node_graph = NodeGraph(self.mesh, self.nodes)
        eps = self.scene.phase_field.epsilon
        near = self.adapter.sizes.h_band if self.adapter else float(self._sizes.max())
        if not self._polylines and self.nucleus is None and values.size and values.max() >= 0.5:
            self.nucleus = self.nodes.points[int(np.argmax(values))].copy()
        found = find_crack(self._node_graph, values, self._polylines, self._start_tip,
                           band=self.crack_model.half_width(eps) + near, bin_width=2 * eps,
                           nucleus=self.nucleus, previous_tip=self.previous_tip)
        self._crack_cache = (key, found)
        self.previous_tip = found.tip.copy()
        return found

    def tip(self) -> np.ndarray:
        """The current crack tip: the end of the crack's ridge (:meth:`crack`)."""
        return self.crack().tip

    def adapt(self, tip: np.ndarray | None = None) -> Adaptation:
        """Change the mesh now and move u and z (with its non-repair bound) onto it."""
        if self.adapter is None:
            raise RuntimeError("adaptivity is not enabled in this scene ([adaptivity] enabled = true)")
        tip = self.tip() if tip is None else tip
        reason, self.adapter.reason = self.adapter.reason or "requested", ""
        eps = self.scene.phase_field.epsilon
        nv_before = self.mesh.nv
        length_before = crack_length(self.z, eps, self.crack_model)
        with self._solves():
            new_mesh, times = self.adapter.new_mesh(self.mesh, self.nodes, self.z, tip)
        started = time.perf_counter()
        z_old, u_old = self.z, self.u
        self._setup(new_mesh)
        if self.model.n_components == 1 and self.fes_u.globalorder == self.fes_z.globalorder:
            # u and z have the same Lagrange nodes: locate them in the old mesh once (a scalar u
            # only: VectorH1.dim is 1 too, its components are separate spaces)
            located = locate(z_old.space.mesh, self.nodes.points)
            self.nodes.assign(self.z, np.clip(evaluate(z_old, located), 0.0, 1.0))
            self.nodes.assign(self.u, evaluate(u_old, located))
        else:
            z_new, _ = transfer_phase_field(z_old, z_old, self.fes_z)
            self.z.vec.data = z_new.vec
            self.u.vec.data = transfer(u_old, self.fes_u, method="set").vec
        self.u_prev.vec.data = self.u.vec
        length_after = crack_length(self.z, eps, self.crack_model)
        if self.scene.adaptivity.relax_core:
            self._relax_core(tip)
        times["transfer_s"] = time.perf_counter() - started
        for name, seconds in times.items():
            self.timer.add(f"adapt: {name[:-2]}", seconds)
        self.adapter.remember(self.mesh, self.nodes, self.z_node_values(), tip)
        record = Adaptation(step=self.k, nv_before=nv_before, nv_after=self.mesh.nv,
                            eta_total=self.adapter.eta_total, crack_length_before=length_before,
                            crack_length_after=length_after, reason=reason, **times)
        self.adaptations.append(record)
        log.info("step %d: new mesh %d -> %d vertices in %.2f s", self.k, nv_before, self.mesh.nv,
                 sum(times.values()))
        return record

    def _relax_core(self, tip: np.ndarray) -> None:
        """Give the crack back the values the scheme gives it on the new mesh.

        Interpolation at the new nodes lowers z where they miss the ridge of the crack
        (z = 1 on a line): a few percent there leaves (1 - z)^2 ~ 1e-3 instead of ~1e-6
        across the crack, which then carries stress, and the first u-solve on the new mesh
        saw a stiffer specimen (SENT with adaptive steps: the force jumped by up to 27 % for
        one step after a change). One z-sub-step at the transferred u, kept only where the
        crack already is (transferred z >= 1/2) and the sub-step opens it (z >=
        :data:`OPEN_LEVEL`), outside the tip disc (z never decreases, stays <= 1), restores
        the ridge. At the tip a z-sub-step would advance the crack, and ahead of it it could
        create damage where there was none (the z >= 1/2 condition; it changed nothing in the
        runs measured); on the flanks of the band it would add damage (kept wherever it gave
        z >= 1/2, the mode III crack length of the quick preset rose 1-2 % above its
        reference). Off by default (docs/adaptivity.md: a mode III run it changed for the worse).
        """
        self._solve_z()
        old = self.nodes.values(self.z)
        trial = self.nodes.values(self.z_trial)
        relax = (trial >= OPEN_LEVEL) & (old >= 0.5)
        if np.all(np.isfinite(tip)):
            margin = self.adapter.sizes.tip_margin
            relax &= np.linalg.norm(self.nodes.points - tip[: self.mesh.dim], axis=1) > margin
        new = old.copy()
        new[relax] = np.minimum(1.0, np.maximum(trial[relax], old[relax]))
        self.nodes.assign(self.z, new)

    # -- one step ---------------------------------------------------------------------------
    @property
    def t(self) -> float:
        """Current time, ticks * time.dt (a product, never a sum of steps)."""
        return self.ticks * self.scene.time.dt

    @property
    def n_steps(self) -> int:
        """Steps of a fixed-step run; for adaptive steps an upper bound."""
        return self.scene.time.n_steps

    @property
    def finished(self) -> bool:
        return self.ticks >= self.scene.time.n_ticks

    def output_due(self, every: int) -> bool:
        """True at every ``every``-th output time (every step for fixed steps, every
        dt * 2**max_doublings for adaptive ones), and at the end."""
        return self.finished or (every > 0 and self.ticks % (every * self.scene.time.output_ticks) == 0)

    def _step_ticks(self) -> int:
        return min(2 ** self.level, self.scene.time.n_ticks - self.ticks)

    def _apply_boundary_values(self) -> None:
        self.model.set_boundary(self.u_boundary, self._boundary_cf)
        fixed = self._fixed_u_dofs
        self.u.vec.FV().NumPy()[fixed] = self.u_boundary.vec.FV().NumPy()[fixed]

    def solve_u(self) -> None:
        """The u-sub-step for the current z (z^{k-1} inside a step) and the current time."""
        if self.split is not None:
            self._solve_u_split()
            return
        with self.timer.phase("u: assemble"), self._assembly_threads(self._pre_u):
            self.a_u.Assemble()
            if self.f_u is not None:
                self.f_u.Assemble()
        with self.timer.phase("u: factorize"), self._solves():
            if self._inv_u is None:
                self._inv_u = u_inverse(self.a_u, self.fes_u.FreeDofs(),
                                        self.scene.discretization.u_solver, self._pre_u)
            else:
                update(self._inv_u)
        with self.timer.phase("u: solve"), self._solves():
            self._apply_boundary_values()
            residual = self.u.vec.CreateVector()
            if self.m_u is not None:
                residual.data = self.inv_dt.Get() * (self.m_u.mat * self.u_prev.vec) \
                    - self.a_u.mat * self.u.vec
            else:
                residual.data = -self.a_u.mat * self.u.vec
            if self.f_u is not None:
                residual.data += self.f_u.vec
            self.u.vec.data += self._inv_u * residual
            try:
                self.u_iterations = solver_iterations(self._inv_u)
            except RuntimeError as err:
                raise SolverError(f"the u-solve failed at step {self.k + 1} (t={self.time.Get():g}): "
                                  f"{err}; set discretization.u_solver = 'sparsecholesky'") from None
        if not np.all(np.isfinite(self.u.vec.FV().NumPy())):
            raise SolverError(f"the u-solve gave non-finite values at step {self.k + 1} "
                              f"(t={self.time.Get():g}); "
                              "raise phase_field.residual_stiffness or lower time.dt")

    def _solve_u_split(self, initial: bool = False) -> None:
        """The u-sub-step with a tension/compression split: Newton on the energy
        (:mod:`ngfrac.physics.splits`); ``initial``: the static problem at t = 0 (no alpha1 term)."""
        self._apply_boundary_values()
        newton = self._newton
        rhs = self.u.vec.CreateVector()
        rhs[:] = 0.0
        if initial:  # the static problem: the tangent without the alpha1 term
            u, v = self.fes_u.TnT()
            static = ngs.BilinearForm(self.fes_u, symmetric=True)
            static += self.split.tangent(self.u, u, v, self.z,
                                         self.scene.phase_field.residual_stiffness) * self.dx
            newton = self._newton_solver(
                static, 0.0, register_preconditioner(static, self.scene.discretization.u_solver))
        elif self.m_u is not None:
            rhs.data = self.inv_dt.Get() * (self.m_u.mat * self.u_prev.vec)
        if self.f_u is not None:
            self.f_u.Assemble()
            rhs.data += self.f_u.vec
        with self.timer.phase("u: newton"):
            try:
                self.newton = newton.solve(rhs)
            except RuntimeError as err:
                raise SolverError(f"the u-solve (material.split = {self.scene.material.split!r}) "
                                  f"failed at step {self.k + 1} (t={self.time.Get():g}): {err}; "
                                  "lower time.dt") from None
            if initial:  # a_u.mat, the tangent at u, gives the reactions (ngfrac.post.reactions)
                self.a_u.Assemble()
        if not np.all(np.isfinite(self.u.vec.FV().NumPy())):
            raise SolverError(f"the u-solve gave non-finite values at step {self.k + 1} "
                              f"(t={self.time.Get():g}); lower time.dt")

    def _newton_solver(self, tangent: ngs.BilinearForm, alpha1: float,
                       preconditioner: object = None) -> NewtonSolver:
        """Newton for the split u-problem with this tangent; alpha1 > 0 adds the energy of
        the alpha1 term (its linear part is the solve's right-hand side); the preconditioner
        (registered with the tangent) is for u_solver = 'cg'."""
        energy = self.split.elastic_density(self.u, self.z, self.scene.phase_field.residual_stiffness)
        if alpha1 > 0:
            energy = energy + 0.5 * alpha1 * self.inv_dt * ngs.InnerProduct(self.u, self.u)
        return NewtonSolver(tangent, self.u, energy, self.integration_order,
                            self.fes_u.FreeDofs(), self.scene.discretization.u_solver,
                            preconditioner=preconditioner, solves=self._solves)

    def _elastic_density(self) -> ngs.CoefficientFunction:
        """W with E_el = 1/2 int ((1-z)^2 + eta) W: sigma:e, or with a split
        2 (((1-z)^2 + eta) psi+ + psi-) / ((1-z)^2 + eta)."""
        if self.split is None:
            return self.model.energy_density(self.u)
        eta = self.scene.phase_field.residual_stiffness
        return 2 * self.split.elastic_density(self.u, self.z, eta) / self.crack_model.degradation(self.z, eta)

    def _solve_z(self) -> int:
        """The z-sub-step into z_trial; returns the CG iterations (0 for a direct solve)."""
        with self.timer.phase("z: assemble"), parallel():
            self._assemble_z_matrix()
            self.f_z.Assemble()
        with self.timer.phase("z: solve"), self._solves():
            iterations = self._solve_z_system()
        if not np.all(np.isfinite(self.z_trial.vec.FV().NumPy())):
            raise SolverError(f"the z-solve gave non-finite values at step {self.k + 1} "
                              f"(t={self.time.Get():g}); "
                              "lower time.dt")
        return iterations

    def _assemble_z_matrix(self) -> None:
        """a_z.mat = K + (alpha2/dt) M + D(u): the drive D assembled, K and M once per mesh."""
        if not self._z_fixed_assembled:
            self._k_z.Assemble()
            self._m_z.Assemble()
            self._z_fixed_assembled = True
        self.a_z.Assemble()
        values = self.a_z.mat.AsVector()
        k, m = self._k_z.mat.AsVector(), self._m_z.mat.AsVector()
        if not (len(values) == len(k) == len(m)):  # never seen; the forms share fes_z
            raise RuntimeError("the z-forms do not share a sparsity pattern")
        values.data += k + (self.scene.phase_field.alpha2 * self.inv_dt.Get()) * m

    def _solve_z_system(self) -> int:
        solver = self.scene.discretization.z_solver
        iterations = 0
        if solver == "cg":
            self.z_trial.vec.data = self.z.vec  # z^{k-1} is a good initial guess
            cg = CGSolver(self.a_z.mat, self.a_z.mat.CreateSmoother(self.fes_z.FreeDofs()),
                          tol=1e-10, maxiter=2000)
            cg.Solve(rhs=self.f_z.vec, sol=self.z_trial.vec, initialize=False)
            iterations = cg.iterations
            if iterations >= 2000:
                raise SolverError(f"the z-solve (CG) did not converge at step {self.k + 1} "
                                  f"(t={self.time.Get():g}); "
                                  "set discretization.z_solver = 'sparsecholesky'")
        else:
            if self._inv_z is None:
                self._inv_z = self.a_z.mat.Inverse(self.fes_z.FreeDofs(), inverse=solver)
            else:
                self._inv_z.Update()
            self.z_trial.vec.data = self._inv_z * self.f_z.vec
        return iterations

    def _descent(self, old: np.ndarray, projected: np.ndarray) -> np.ndarray:
        """z_old + theta (P - z_old) with theta in [0, 1] minimizing the z-step's energy.

        The z-step minimizes G(z) = 1/2 z.A z - f.z (A, f: the assembled z-forms, which hold
        z_old). Every point between z_old and the projection P is feasible (both are), G is
        quadratic along the segment, so the exact minimizer over it never exceeds G(z_old).
        """
        direction_nodes = projected - old
        if not np.any(direction_nodes):
            return projected
        z_old = self.z.vec.CreateVector()
        z_old.data = self.z.vec  # z still holds z_old here
        direction = ngs.GridFunction(self.fes_z)
        self.nodes.assign(direction, direction_nodes)
        a_d = (self.a_z.mat * direction.vec).Evaluate()
        curvature = ngs.InnerProduct(direction.vec, a_d)
        slope = ngs.InnerProduct(z_old, a_d) - ngs.InnerProduct(self.f_z.vec, direction.vec)
        theta = 1.0 if curvature <= 0 else min(1.0, max(0.0, -slope / curvature))
        if theta < 1.0:
            self.timer.add("z: shortened projections", 0.0)
        return old + theta * direction_nodes

    def step(self, diagnose: bool = True) -> StepRecord:
        """Advance one time step (with adaptive time steps, redo it smaller if z jumped).

        Parameters
        ----------
        diagnose : bool
            Compute energies, crack length, tip and reactions; else those are NaN.
        """
        if self.finished:
            raise RuntimeError(f"the run is at its end time t = {self.t:g} (time.t_end); "
                               "build a stepper of a scene with a later time.t_end to go on")
        started = time.perf_counter()
        settings = self.scene.time
        with self._step_threads():
            self.u_prev.vec.data = self.u.vec
            saved_z = self.z.vec.CreateVector()
            saved_z.data = self.z.vec
            solve_s = 0.0
            while True:
                n = self._step_ticks()
                self.time.Set((self.ticks + n) * settings.dt)
                self.inv_dt.Set(1.0 / (n * settings.dt))
                solve_started = time.perf_counter()
                self.solve_u()
                solve_s += time.perf_counter() - solve_started
                if diagnose:  # before z changes and before any new mesh: the residual of this solve
                    with self.timer.phase("diagnostics: reactions"):
                        self.forces = reaction_columns(self)
                solve_started = time.perf_counter()
                iterations = self._solve_z()
                solve_s += time.perf_counter() - solve_started
                with self.timer.phase("z: bounds at nodes"):
                    old = self.nodes.values(self.z)
                    trial = self.nodes.values(self.z_trial)
                    new = np.minimum(1.0, np.maximum(trial, old))
                    if self.scene.discretization.z_update == "descent":
                        new = self._descent(old, new)
                    self.nodes.assign(self.z, new)
                dz_max = float(np.max(new - old)) if len(new) else 0.0
                if not (settings.adaptive and dz_max > settings.dz_target and self.level > 0):
                    break
                # z changed too much: halve the step (more if far off) and redo it
                self.level = max(0, self.level - max(1, math.ceil(math.log2(dz_max / settings.dz_target))))
                self.z.vec.data = saved_z
                self.timer.add("time: rejected steps", 0.0)
            self.ticks += n
            self.k += 1
            if (settings.adaptive and dz_max < settings.dz_target / 4 and self.level < settings.max_doublings
                    and self.ticks % 2 ** (self.level + 1) == 0):
                self.level += 1
        adapt_s = 0.0
        if self.adapter is not None and self.k % self.scene.adaptivity.every == 0:
            adapt_started = time.perf_counter()
            with self.timer.phase("adapt: check"), self._solves():
                tip = self.tip()
                wanted = self.adapter.wants_new_mesh(self.mesh, self.nodes, new, tip)
            if wanted:
                with self._step_threads():
                    self.adapt(tip)
            adapt_s = time.perf_counter() - adapt_started
        return self.record(diagnose, dz_max=dz_max, z_iterations=iterations, dt=n * settings.dt,
                           step_s=time.perf_counter() - started, solve_s=solve_s, adapt_s=adapt_s)

    def record(self, diagnose: bool = True, dz_max: float = math.nan, z_iterations: int = 0,
               dt: float = math.nan, step_s: float = math.nan, solve_s: float = math.nan,
               adapt_s: float = 0.0) -> StepRecord:
        """A record of the current state (diagnostics only when asked for)."""
        eta_total = self.adapter.eta_total if self.adapter is not None else math.nan
        base = dict(step=self.k, t=self.t, dt=dt, wall_s=time.perf_counter() - self._started,
                    dim=self.mesh.dim,
                    nv=self.mesh.nv, ndof=self.fes_u.ndof + self.fes_z.ndof,
                    dz_max=dz_max, z_iterations=z_iterations, eta_total=eta_total,
                    n_adapt=len(self.adaptations), step_s=step_s, solve_s=solve_s, adapt_s=adapt_s)
        if not diagnose:
            return StepRecord(**base)
        pf = self.scene.phase_field
        with self.timer.phase("diagnostics: energies, tip"):
            e = energies(self.mesh, self.z, self._elastic_density(), self.gamma,
                         pf.epsilon, pf.residual_stiffness,
                         None if self.body_force is None else self.body_force * self.u,
                         order=self.integration_order, crack_model=self.crack_model)
        crack = self.crack()
        tip = crack.tip
        path_length = self._initial_length + crack.grown_length if self.mesh.dim == 2 else math.nan
        return StepRecord(**base, forces=dict(self.forces), hmin=float(self._sizes.min()),
                          hmax=float(self._sizes.max()),
                          E_el=e.E_el, E_surf=e.E_surf, E_total=e.E_total,
                          crack_length=e.crack_length, tip_x=float(tip[0]), tip_y=float(tip[1]),
                          path_length=path_length, n_damage_zones=crack.n_damage_zones,
                          tip_z=float(tip[2]) if len(tip) > 2 else math.nan)

    @property
    def _initial_length(self) -> float:
        """Total length of the initial crack polylines (2D)."""
        return float(sum(np.linalg.norm(np.diff(np.asarray(line, dtype=float), axis=0), axis=1).sum()
                         for line in self._polylines))

    def run(self, history_every: int | None = None) -> Iterator[StepRecord]:
        """Step to the end time, yielding one record per step.

        Diagnostics are computed every ``history_every`` steps (the scene's
        ``output.history_every`` by default) and at the last step.
        """
        every = history_every or self.scene.output.history_every
        with self._step_threads():
            while not self.finished:
                last = self.ticks + self._step_ticks() >= self.scene.time.n_ticks
                yield self.step(diagnose=last or (self.k + 1) % every == 0)

    def z_node_values(self) -> np.ndarray:
        """z at the Lagrange nodes (vertices, then edge midpoints for P2)."""
        return self.nodes.values(self.z)
