"""The time stepper: the semi-implicit staggered scheme of the paper (its equation 7).

Step k, from t_{k-1} to t_k = t_{k-1} + dt (all times on the grid n * time.dt)::

    alpha1 (u^k - u^{k-1})/dt = div(((1 - z^{k-1})^2 + eta) sigma[u^k])       u = g(t_k) on Gamma_D
    alpha2 (zt - z^{k-1})/dt  = eps div(gamma grad zt) - gamma zt/eps + W (1 - zt)
    z^k = min(1, max(zt, z^{k-1}))        at the Lagrange nodes of z

with ``W = sigma[u^{k-1}]:e[u^{k-1}]`` (``coupling = "paper"``) or ``sigma[u^k]:e[u^k]``
(``coupling = "staggered"``; ``"alternate"`` repeats the two sub-steps from the new fields
until z settles); the crack model (AT2 above, or AT1) sets the surface terms.
The stepper composes the u-sub-problem (:mod:`~ngfrac.solve.u_problem`), the z-sub-problem
(:mod:`~ngfrac.solve.z_problem`) and the step-size control (:mod:`~ngfrac.solve.time_control`);
the adapter (:mod:`ngfrac.mesh.adapter`) owns every mesh change.
"""
from __future__ import annotations

import dataclasses
import logging
import math
import time
from concurrent.futures import ThreadPoolExecutor, wait
from functools import cached_property
from typing import Any, Iterator

import numpy as np
import ngsolve as ngs

from ..mesh.adapter import Adaptation
from ..geometry.domains import Domain, domain_of
from .communicator import SERIAL, Communicator
from ..physics.crack_models import CrackModel
from ..physics.cracks import distance_to_cracks, initial_tip
from ..physics.elastic import ElasticModel
from ..post.crackset import CrackSet
from ..post.diagnostics import energies
from ..post.pressurized import crack_volume
from ..post.reactions import reaction_columns
from ..scene import Scene
from ..scene.build import crack_model_of, elastic_model_of
from .crack_tracking import CrackTracker
from .context import StepContext
from .profiling import PhaseTimer
from .records import StepRecord
from ..mesh.fields import MeshFields
from .state import STATE_FIELDS, StepperState, copy_of
from ..fem.threads import ThreadPolicy
from .time_control import StepSizeControl
from .u_problem import DisplacementProblem, NewtonFailure, SolverError
from .z_problem import PhaseFieldProblem

__all__ = ["PhaseFieldStepper"]

log = logging.getLogger(__name__)


class PhaseFieldStepper:
    """One run: the fields on the current mesh, the two sub-problems, the time and the crack.

    Parameters
    ----------
    scene : Scene
        The validated run description.
    mesh : ngsolve.Mesh, optional
        A mesh to use instead of the uniform mesh the scene describes (no initial adaptation).
    state : StepperState, optional
        Continue from this state (:meth:`state`, a checkpoint) instead of the initial one.
    comm : Communicator, optional
        The processes of the run (:mod:`ngfrac.parallel`): one (the default) or an MPI job
        (:class:`~ngfrac.parallel.MPICommunicator`; the mesh is made on rank 0 and
        distributed, so no ``mesh`` can be given, and a ``state`` must be on the distributed
        mesh: :func:`ngfrac.parallel.checkpoints.resume_distributed`).
    elastic_model : ElasticModel, optional
        A model of the elastic energy (:class:`ngfrac.physics.elastic.ElasticModel`) instead of
        the scene's ``model.kind``; the loads are still the scene's.
    crack_model : CrackModel, optional
        A crack model (:class:`ngfrac.physics.crack_models.CrackModel`) instead of the scene's
        ``phase_field.model``.

    Examples
    --------
    >>> stepper = PhaseFieldStepper(load_scene("demos/mode3_slit.toml"))  # doctest: +SKIP
    >>> for record in stepper.run():                                        # doctest: +SKIP
    ...     print(record.t, record.tip_x)
    """

    def __init__(self, scene: Scene, mesh: ngs.Mesh | None = None,
                 state: StepperState | None = None, comm: Communicator | None = None, *,
                 elastic_model: ElasticModel | None = None,
                 crack_model: CrackModel | None = None) -> None:
        self._scene = scene
        self.comm: Communicator = SERIAL if comm is None else comm
        """The processes of the run (:mod:`ngfrac.parallel`)."""
        self.comm.check(scene)
        self.comm.check_start(mesh, state)  # MPI: no given mesh, no serial state
        self.model = elastic_model_of(scene) if elastic_model is None else elastic_model
        """The elastic model (:mod:`ngfrac.physics.elastic`)."""
        self.crack_model = crack_model_of(scene) if crack_model is None else crack_model
        """The phase-field functional (:mod:`ngfrac.physics.crack_models`)."""
        self.k = 0
        self.ticks = 0
        """Time as a count of ``time.dt``: t = ticks * dt, exact for any number of steps."""
        self.control = StepSizeControl(scene.time)
        self.context = StepContext(ngs.Parameter(0.0), ngs.Parameter(1.0 / scene.time.dt),
                                   ThreadPolicy(scene.discretization.threaded_solves,
                                                concurrent=self.comm.concurrent_substeps(
                                                    scene.discretization.concurrent_substeps)),
                                   PhaseTimer(), self.comm)
        """The step's time and 1/dt Parameters, the thread policy and the phase timer."""
        self.domain: Domain = domain_of(scene.geometry)
        """The domain (:mod:`ngfrac.geometry.domains`)."""
        self.adapter = (self.comm.mesh_adapter(scene, self.crack_model)
                        if scene.adaptivity.enabled else None)
        polylines = [crack.points for crack in scene.cracks]
        self.tracker = CrackTracker(
            polylines, initial_tip(polylines[0], self.domain.on_boundary) if polylines else None,
            self.crack_model, scene.phase_field.epsilon,
            self.adapter.sizes.h_band if self.adapter else None)
        self.forces: dict[str, float] = {}
        """Reaction columns of the last diagnosed u-solve (:mod:`ngfrac.post.reactions`)."""
        if state is not None:
            self._rebuild(state.mesh)
            self.load_state(state)
            return
        size = self.adapter.sizes.hmax if self.adapter else scene.mesh_size
        self._initial_z(mesh if mesh is not None else
                        self.comm.distribute(lambda: self.domain.build_mesh(size, polylines)))
        if self.adapter is not None and mesh is None:
            # the meshes of the initial passes follow z0 alone: u0 only on the last one
            self.fields = self.adapter.resolve_initial(self.fields, lambda f: self.tip(),
                                                       self._initial_z, self.threads.solves)
        self._initial_u()

    @classmethod
    def from_state(cls, scene: Scene, state: StepperState) -> "PhaseFieldStepper":
        """A stepper of ``scene`` continuing from ``state`` (no initial solve)."""
        return cls(scene, state=state)

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

    # -- the fields and sub-problems of one mesh ---------------------------------------------
    def _rebuild(self, mesh: ngs.Mesh) -> MeshFields:
        """New (zero) fields on ``mesh`` and the two sub-problems on them."""
        sc = self.scene
        self.fields = MeshFields.on(mesh, sc, self.model, self.crack_model)
        self.u_problem = DisplacementProblem(self.fields, sc, self.model, self.crack_model,
                                             self.context)
        f = self.fields
        u_drive = f.u_prev if sc.discretization.coupling == "paper" else f.u
        self.z_problem = PhaseFieldProblem(f, sc, self.crack_model, self.gamma,
                                           self.u_problem.drive(u_drive), self.context, u_drive)
        return self.fields

    def _initial_z(self, mesh: ngs.Mesh) -> MeshFields:
        """New fields on ``mesh`` with z0 = the crack model's optimal profile of the distance to
        the initial cracks at the nodes (AT2: exp(-dist/eps)); u is zero."""
        f = self._rebuild(mesh)
        polylines = self.tracker.polylines
        if polylines:
            distance = distance_to_cracks(f.nodes.points, polylines)
            f.nodes.assign(f.z, self.crack_model.profile(distance, self.scene.phase_field.epsilon))
            f.clear_damage_free()
        return f

    def _initial_u(self) -> None:
        """u0 = the elastic solution at t = 0 for z0 (the u-sub-step with 1/dt = 0), and its
        reaction forces."""
        self.time.Set(0.0)
        with self.threads.step(), self.u_problem.static():
            self.u_problem.solve("0 (the initial state)")
            self.fields.u_prev.vec.data = self.fields.u.vec
            self.forces = reaction_columns(self.u_problem, self.scene.loads)

    # -- state ------------------------------------------------------------------------------
    def state(self) -> StepperState:
        """The state after the current step: counters, mesh, copies of u, u_prev and z, the
        crack tracking and the adapter's state (:class:`~ngfrac.solve.state.StepperState`)."""
        adapter = None
        if self.adapter is not None:
            adapter = {**self.adapter.state(), "adaptations": list(self.adaptations)}
        tracker = self.tracker
        return StepperState(self.k, self.ticks, self.control.level, self.mesh,
                            {name: copy_of(getattr(self.fields, name)) for name in STATE_FIELDS},
                            None if tracker.nucleus is None else tracker.nucleus.copy(),
                            None if tracker.previous_tip is None else tracker.previous_tip.copy(),
                            adapter)

    def load_state(self, state: StepperState) -> None:
        """Continue from ``state`` (moving to its mesh when it is another one)."""
        if (self.adapter is None) != (state.adapter is None):
            raise ValueError("the state and the scene disagree on whether the mesh adapts")
        if state.mesh is not self.mesh:
            self._rebuild(state.mesh)
        for name in STATE_FIELDS:
            mine, stored = getattr(self.fields, name), state.fields[name]
            if stored.space.ndof != mine.space.ndof or stored.space.type != mine.space.type:
                raise ValueError(f"field {name!r} of the state has {stored.space.ndof} dofs of "
                                 f"{stored.space.type}, the scene's space {mine.space.ndof}")
            mine.vec.data = stored.vec
        self.k, self.ticks, self.control.level = state.k, state.ticks, state.level
        self.time.Set(self.t)
        self.tracker.nucleus = None if state.nucleus is None else np.array(state.nucleus)
        self.tracker.previous_tip = None if state.previous_tip is None else np.array(state.previous_tip)
        self.tracker.forget()
        if self.adapter is not None:
            self.adapter.restore(state.adapter)
        self.forces = reaction_columns(self.u_problem, self.scene.loads)  # the columns' names

    # -- the crack ----------------------------------------------------------------------------
    def crack(self) -> CrackSet:
        """The crack set of the current z: tip, ridge, grown length, other damage zones
        (:func:`ngfrac.post.crackset.find_crack`)."""
        return self.comm.crack(self.tracker, self.fields)

    def tip(self) -> np.ndarray:
        """The current crack tip: the end of the crack's ridge (:meth:`crack`)."""
        return self.crack().tip

    # -- mesh changes -------------------------------------------------------------------------
    def adapt(self, tip: np.ndarray | None = None, reason: str = "requested") -> Adaptation:
        """Change the mesh now and move u and z (with its non-repair bound) onto it."""
        if self.adapter is None:
            raise RuntimeError("adaptivity is not enabled in this scene ([adaptivity] enabled = true)")
        tip = self.tip() if tip is None else tip
        self.fields, record = self.adapter.change(self.fields, tip, self.k, reason, self._rebuild,
                                                  self._relaxing_step, self.threads.solves)
        for name in ("estimate_s", "mark_s", "remesh_s", "transfer_s"):
            self.timer.add(f"adapt: {name[:-2]}", getattr(record, name))
        return record

    def _relaxing_step(self, fields: MeshFields) -> np.ndarray:
        """One z-sub-step on the (just rebuilt) fields: z_trial at the nodes."""
        self.z_problem.solve(self._step_label())
        return self.z_problem.trial_values()

    def _check_due(self) -> bool:
        """Whether this step ends with the check for a new mesh (every ``adaptivity.every``)."""
        return self.adapter is not None and self.k % self.scene.adaptivity.every == 0

    def _adapt_if_wanted(self, z_values: np.ndarray) -> float:
        """Every ``adaptivity.every`` steps: a new mesh when the adapter wants one; returns
        the seconds spent."""
        if not self._check_due():
            return 0.0
        started = time.perf_counter()
        with self.timer.phase("adapt: check"), self.threads.solves():
            tip = self.tip()
            reason = self.adapter.wants_new_mesh(self.mesh, self.nodes, z_values, tip)
        if reason is not None:
            with self.threads.step():
                self.adapt(tip, reason)
        return time.perf_counter() - started

    # -- time -------------------------------------------------------------------------------
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

    def _step_label(self) -> str:
        return f"{self.k + 1} (t={self.time.Get():g})"

    # -- one step ---------------------------------------------------------------------------
    def solve_u(self) -> None:
        """The u-sub-step for the current z (z^{k-1} inside a step) and the current time."""
        self.u_problem.solve(self._step_label())

    def step(self, diagnose: bool = True) -> StepRecord:
        """Advance one time step (with adaptive time steps, redo it smaller if z jumped or its
        Newton u-solve failed).

        Parameters
        ----------
        diagnose : bool
            Compute energies, crack length, tip and reactions; else those are NaN.
        """
        if self.finished:
            raise RuntimeError(f"the run is at its end time t = {self.t:g} (time.t_end); "
                               "build a stepper of a scene with a later time.t_end to go on")
        started, dt, f = time.perf_counter(), self.scene.time.dt, self.fields
        with self.threads.step():
            f.u_prev.vec.data = f.u.vec
            saved_z = f.z.vec.CreateVector()
            saved_z.data = f.z.vec
            solve_s = 0.0
            while True:
                n = self.control.ticks(self.ticks)
                self.time.Set((self.ticks + n) * dt)
                self.inv_dt.Set(1.0 / (n * dt))
                solve_started = time.perf_counter()
                iterations = self._solve_both() if self._concurrent else None
                if iterations is None:
                    try:
                        self.solve_u()
                    except NewtonFailure:
                        if not self._halved_after_newton_failure():
                            raise  # at dt already: the clear error
                        solve_s += time.perf_counter() - solve_started
                        continue
                solve_s += time.perf_counter() - solve_started
                if diagnose:  # before z changes and before any new mesh: this solve's residual
                    with self.timer.phase("diagnostics: reactions"):
                        self.forces = reaction_columns(self.u_problem, self.scene.loads)
                if iterations is None:
                    solve_started = time.perf_counter()
                    iterations = self.z_problem.solve(self._step_label())
                    solve_s += time.perf_counter() - solve_started
                with self.timer.phase("z: bounds at nodes"):
                    old, new = self.z_problem.project()
                if self.scene.discretization.coupling == "alternate":
                    try:
                        new, alternate_s = self._alternate(saved_z, old, new, diagnose)
                    except NewtonFailure:  # in a later pass: z has changed
                        if not self._halved_after_newton_failure(saved_z):
                            raise
                        continue
                    solve_s += alternate_s
                dz_max = self.comm.max(float(np.max(new - old)) if len(new) else 0.0)
                if not self.control.rejects(dz_max):
                    break
                f.z.vec.data = saved_z  # z changed too much: redo the step smaller
                self.timer.add("time: rejected steps", 0.0)
            self.ticks += n
            self.k += 1
            self.control.accepted(self.ticks, dz_max)
        # the step's diagnostics on the mesh it was solved on: after a mesh change u is only
        # interpolated (not in equilibrium there), and its energy would jump for one row
        if diagnose and self._check_due():  # the check's crack set, which the diagnostics share
            with self.timer.phase("adapt: crack set"), self.threads.solves():
                self.crack()
        diagnosed = time.perf_counter()
        diagnostics = self._diagnostics() if diagnose else {}
        diagnostics_s = time.perf_counter() - diagnosed  # not part of step_s (the profile has it)
        changes = len(self.adaptations)
        adapt_s = self._adapt_if_wanted(new)
        if diagnose and len(self.adaptations) > changes:
            # the tip on the new mesh: the next step's tip is found relative to it
            # (CrackTracker.previous_tip), as it was when the diagnostics followed the change
            with self.timer.phase("adapt: crack set"), self.threads.solves():
                self.crack()
        return self.record(diagnose, diagnostics, dz_max=dz_max, z_iterations=iterations,
                           dt=n * dt, step_s=time.perf_counter() - started - diagnostics_s,
                           solve_s=solve_s, adapt_s=adapt_s)

    def _halved_after_newton_failure(self, z_start: ngs.BaseVector | None = None) -> bool:
        """After a failed Newton u-solve: halve the step and put back Newton's start u^{k-1}
        (and z^{k-1}, when given: a later pass's failure); False when the step is at dt
        already (the caller re-raises)."""
        if not self.control.halve():
            return False
        self.fields.u.vec.data = self.fields.u_prev.vec
        if z_start is not None:
            self.fields.z.vec.data = z_start
        self.timer.add("time: halved steps (Newton failed)", 0.0)
        return True

    def _alternate(self, z_start: ngs.BaseVector, old: np.ndarray, new: np.ndarray,
                   diagnose: bool) -> tuple[np.ndarray, float]:
        """``coupling = "alternate"``: after the step's first (staggered) pass, more u- and
        z-sub-steps from the last pass's fields until a pass changes z at no node by more than
        ``discretization.alternate_tolerance`` or ``alternate_passes`` passes are made. Each
        pass's z-step is linearized at the last pass's z (z_old of its forms), its non-repair
        bound is the step's z^{k-1}: z may fall back between passes, never below z^{k-1}.

        Parameters
        ----------
        z_start : ngsolve.BaseVector
            z^{k-1}, the coefficients of z at the step's start.
        old, new : array
            z at the nodes before and after the first pass.
        diagnose : bool
            Renew the reaction forces after each u-solve (the last one's are kept).

        Returns
        -------
        (z at the nodes after the last pass, seconds spent in the sub-steps)
        """
        d = self.scene.discretization
        spent, passes = 0.0, 1
        largest = self.comm.max(float(np.max(new - old)) if len(new) else 0.0)
        if largest <= d.alternate_tolerance or d.alternate_passes <= 1:
            return new, spent
        start = ngs.GridFunction(self.fields.fes_z)  # z^{k-1}, the non-repair bound of the passes
        start.vec.data = z_start
        self.z_problem.bound_by(start)
        try:
            while largest > d.alternate_tolerance and passes < d.alternate_passes:
                started = time.perf_counter()
                self.solve_u()
                if diagnose:
                    with self.timer.phase("diagnostics: reactions"):
                        self.forces = reaction_columns(self.u_problem, self.scene.loads)
                self.z_problem.solve(self._step_label())
                spent += time.perf_counter() - started
                with self.timer.phase("z: bounds at nodes"):
                    old, new = self.z_problem.project()
                largest = self.comm.max(float(np.max(np.abs(new - old))) if len(new) else 0.0)
                passes += 1
                self.timer.add("alternate: extra passes", 0.0)
        finally:
            self.z_problem.bound_by(None)
        if largest > d.alternate_tolerance:
            self.timer.add("alternate: steps ended by alternate_passes", 0.0)
            log.warning("step %s: %d alternate passes left z changing by %.3g (tolerance %.3g); "
                        "raise discretization.alternate_passes or lower time.dt",
                        self._step_label(), passes, largest, d.alternate_tolerance)
        return new, spent

    @property
    def _concurrent(self) -> bool:
        """Whether the two sub-steps run at the same time (``discretization.concurrent_substeps``;
        not with a split, whose Newton u-solve enters the TaskManager)."""
        return self.threads.concurrent and self.u_problem.split is None

    @cached_property
    def _substeps(self) -> ThreadPoolExecutor:
        """The thread the z-sub-step runs in while this one solves for u."""
        return ThreadPoolExecutor(max_workers=1, thread_name_prefix="ngfrac-z")

    def _solve_both(self) -> int:
        """The u- and the z-sub-step at once; returns the z-solve's iterations. With
        ``coupling = "paper"`` they share no output: u reads z^{k-1}, which the z-solve leaves
        as it is (it writes z_trial; :meth:`PhaseFieldProblem.project` comes after both), and
        z reads u_prev. NGSolve releases the GIL in assembly and factorization."""
        with self.threads.concurrently():
            z_step = self._substeps.submit(self.z_problem.solve, self._step_label())
            try:
                self.solve_u()
            except BaseException:
                wait([z_step])  # never leave the z-solve running on fields being given up
                raise
            return z_step.result()

    def record(self, diagnose: bool = True, diagnostics: dict[str, Any] | None = None,
               **step: Any) -> StepRecord:
        """A record of the current state; ``step`` holds the per-step columns (dz_max,
        z_iterations, dt, step_s, solve_s, adapt_s).

        Parameters
        ----------
        diagnose : bool
            Fill the diagnostic columns (energies, crack length, tip, reactions); else NaN.
        diagnostics : dict, optional
            Those columns as :meth:`step` computed them before a mesh change; by default they
            are computed now. nv, ndof, hmin and hmax always describe the current mesh.
        """
        f = self.fields
        nv, ndof = self.comm.counts(f)
        base = dict(step=self.k, t=self.t, wall_s=time.perf_counter() - self.timer.started,
                    dim=f.mesh.dim, nv=nv, ndof=ndof, n_adapt=len(self.adaptations),
                    eta_total=self.adapter.eta_total if self.adapter is not None else math.nan,
                    pressurized=self.scene.phase_field.pressurized, **step)
        if not diagnose:
            return StepRecord(**base)
        if diagnostics is None:
            diagnostics = self._diagnostics()
        hmin, hmax = self.comm.size_range(self.tracker, f)
        return StepRecord(**base, **diagnostics, hmin=hmin, hmax=hmax)

    def _diagnostics(self) -> dict[str, Any]:
        """The diagnostic columns of the current fields: reactions (of the last u-solve),
        energies, crack length, tip and path length, crack volume."""
        f = self.fields
        pf, body_force = self.scene.phase_field, self.u_problem.body_force
        with self.timer.phase("diagnostics: energies, tip"):
            e = energies(f.mesh, f.z, self.u_problem.elastic_density(), self.gamma,
                         pf.epsilon, pf.residual_stiffness, self.crack_model,
                         None if body_force is None else body_force * f.u,
                         order=f.integration_order,
                         surface=self.z_problem.surface_energy())
            crack = self.crack()  # cached when the mesh-change check has found it
        extra_work = self.u_problem.surface_work()
        if extra_work is not None:
            e = dataclasses.replace(e, work=e.work + extra_work)
        volume = (crack_volume(f.u, f.z, f.integration_order) if pf.pressurized
                  else math.nan)
        tip = crack.tip
        path_length = self._initial_length + crack.grown_length if f.mesh.dim == 2 else math.nan
        return dict(forces=dict(self.forces), E_el=e.E_el, E_surf=e.E_surf, E_total=e.E_total,
                    crack_length=e.crack_length, tip_x=float(tip[0]), tip_y=float(tip[1]),
                    path_length=path_length, n_damage_zones=crack.n_damage_zones,
                    tip_z=float(tip[2]) if len(tip) > 2 else math.nan, crack_volume=volume)

    def run(self, history_every: int | None = None) -> Iterator[StepRecord]:
        """Step to the end time, yielding one record per step.

        Diagnostics are computed every ``history_every`` steps (the scene's
        ``output.history_every`` by default) and at the last step.
        """
        every = history_every or self.scene.output.history_every
        with self.threads.step():
            while not self.finished:
                last = self.ticks + self.control.ticks(self.ticks) >= self.scene.time.n_ticks
                yield self.step(diagnose=last or (self.k + 1) % every == 0)

    # -- views --------------------------------------------------------------------------------
    @property
    def _initial_length(self) -> float:
        """Total length of the initial crack polylines (2D)."""
        return float(sum(np.linalg.norm(np.diff(np.asarray(line, dtype=float), axis=0), axis=1).sum()
                         for line in self.tracker.polylines))

    threads = property(lambda self: self.context.threads,
                       doc="Where NGSolve's threads are used (``discretization.threaded_solves``).")
    timer = property(lambda self: self.context.timer, doc="The wall time of each phase.")
    time = property(lambda self: self.context.time, doc="The time Parameter of the step.")
    inv_dt = property(lambda self: self.context.inv_dt, doc="The 1/dt Parameter of the step.")

    @cached_property
    def gamma(self) -> Any:
        """The toughness: a number when constant (no coefficient evaluation in the forms);
        built once (the forms of every mesh and the energies share it)."""
        gamma = self.scene.material.gamma
        return gamma.value() if gamma.is_constant else gamma.to_coefficient()

    @property
    def adaptations(self) -> list[Adaptation]:
        """The mesh changes so far (:class:`~ngfrac.mesh.adapter.Adaptation`)."""
        return self.adapter.adaptations if self.adapter is not None else []

    @property
    def level(self) -> int:
        """The step is dt * 2**level (adaptive time steps)."""
        return self.control.level

    @property
    def nucleus(self) -> np.ndarray | None:
        """With no initial crack: where z first reached 1/2 (the crack grows from there)."""
        return self.tracker.nucleus

    @property
    def previous_tip(self) -> np.ndarray | None:
        """The last tip found (a tip never moves back along the crack)."""
        return self.tracker.previous_tip

    @property
    def split(self) -> Any:
        """The tension/compression split (:mod:`ngfrac.physics.splits`), or None."""
        return self.u_problem.split

    mesh = property(lambda self: self.fields.mesh, doc="The current mesh.")
    u = property(lambda self: self.fields.u, doc="The displacement.")
    u_prev = property(lambda self: self.fields.u_prev, doc="The displacement of the last step.")
    z = property(lambda self: self.fields.z, doc="The phase field.")
    fes_u = property(lambda self: self.fields.fes_u, doc="The space of u.")
    fes_z = property(lambda self: self.fields.fes_z, doc="The space of z.")
    nodes = property(lambda self: self.fields.nodes, doc="The Lagrange nodes of z.")
    dx = property(lambda self: self.fields.dx, doc="dx with the forms' quadrature.")

    def z_node_values(self) -> np.ndarray:
        """z at the Lagrange nodes (vertices, then edge midpoints for P2)."""
        return self.fields.z_values()
