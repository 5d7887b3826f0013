"""The stability stress cases (issue 6, item 5), shared by tests/stress and
benchmarks/stress_table.py.

Every case is a small scene run step by step while :class:`StabilityMonitor` checks, after
every step: u and z finite; z in [0, 1] at the Lagrange nodes; z not below its previous value
at any node while the mesh is unchanged; and, on steps where the mesh is unchanged and the
load (every load expression and the body force at sample points of the boundary and domain)
is the same at t_{k-1} and t_k, ``E_total`` not above its previous value by more than
``TOL`` of it (the scheme is a discrete gradient flow only for a held load on a fixed mesh).
Each case then checks one physical fact of its own.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
import ngsolve as ngs

from ..io.checkpoint import load_checkpoint
from ..physics.cracks import optimal_profile
from ..runner import CHECKPOINT, run_scene
from ..scene import Components, Scene
from ..solve.stepper import PhaseFieldStepper, SolverError
from ..solve.u_problem import DisplacementProblem
from ..solve.z_system import AssembledSystem

from .scenes import demo_data, scene_from

TOL = 1e-12
"""Round-off allowed in the bounds, in the monotonicity of z and (relative) in the energy."""

DEMO_DT = 5e-4
"""The time step of the demo scenes (demos/mode3_slit.toml)."""

SLIT = ["phase_field.epsilon=0.08", "geometry.mesh_size=0.04", "output.vtk_every=0",
        "adaptivity.enabled=false", "output.checkpoint_every=0"]
"""The slit demo made coarse: epsilon 0.08, h 0.04 (about 760 vertices), no output."""


def slit(*overrides: str) -> Scene:
    """The mode III slit of Fig. 2 on the coarse stress mesh (loads +-g on top and bottom)."""
    return scene_from(demo_data(), *SLIT, *overrides)


def mode3_load(expression: str) -> list[str]:
    """Top +g(t), bottom -g(t)."""
    return [f'loads.0.value="{expression}"', f'loads.1.value="-({expression})"']


def plane_strain(expression: str, *overrides: str) -> Scene:
    """A plane-strain plate (E = 50, nu = 0.29) with the edge slit from (0, 0.5) to (0.3, 0.5),
    pulled at the top by uy = g(t), the bottom on rollers."""
    data = demo_data()
    data["model"] = {"kind": "plane_strain"}
    data["material"] = {"E": 50.0, "nu": 0.29, "gamma": 1.0}
    data["loads"] = [{"boundary": "top", "value": ["0", expression]},
                     {"boundary": "bottom", "value": ["free", "0"]}]
    return scene_from(data, *SLIT, *overrides)


# -- the checks ---------------------------------------------------------------------------
def load_sampler(scene: Scene) -> Callable[[float], np.ndarray]:
    """The values of every load and body-force expression at points of the rectangle's four
    sides, at time t."""
    g = scene.geometry
    x0, y0 = g.origin
    s = np.linspace(0.0, 1.0, 17)
    xs = np.concatenate([x0 + s * g.width, np.full_like(s, x0 + g.width), x0 + s * g.width,
                         np.full_like(s, x0)])
    ys = np.concatenate([np.full_like(s, y0), y0 + s * g.height, np.full_like(s, y0 + g.height),
                         y0 + s * g.height])
    expressions = _load_expressions(scene)

    def sample(t: float) -> np.ndarray:
        return np.concatenate([np.broadcast_to(e.evaluate_numpy({"x": xs, "y": ys, "t": t}),
                                               xs.shape) for e in expressions])
    return sample


def _load_expressions(scene: Scene) -> list:
    """Every load component and the body force that is an expression (not ``free``)."""
    expressions = []
    for value in [load.value for load in scene.loads] + [scene.material.body_force]:
        entries = value if isinstance(value, Components) else (value,)
        expressions += [e for e in entries if not isinstance(e, str)]
    return expressions


def box_load_sampler(scene: Scene) -> Callable[[float], np.ndarray]:
    """Every load expression at points of the box's six faces, at time t (the 3D version of
    :func:`load_sampler`)."""
    g = scene.geometry
    s = np.linspace(0.0, 1.0, 7)
    u, v = (a.ravel() for a in np.meshgrid(s, s))
    points = []
    for axis in range(3):
        for end in (0.0, 1.0):
            p = np.empty((len(u), 3))
            others = [i for i in range(3) if i != axis]
            p[:, axis] = end
            p[:, others[0]], p[:, others[1]] = u, v
            points.append(np.asarray(g.origin) + p * np.asarray(g.extent))
    xs, ys, zs = np.vstack(points).T
    expressions = _load_expressions(scene)

    def sample(t: float) -> np.ndarray:
        return np.concatenate([np.broadcast_to(e.evaluate_numpy({"x": xs, "y": ys, "z": zs, "t": t}),
                                               xs.shape) for e in expressions])

    return sample


@dataclass
class StabilityMonitor:
    """Watches a stepper step by step; call :meth:`observe` after every step."""

    stepper: PhaseFieldStepper
    sampler: Callable[[Scene], Callable[[float], np.ndarray]] = load_sampler
    """Makes the load sampler of the stepper's scene (:func:`box_load_sampler` for a box)."""
    z_outside: float = 0.0
    """Largest violation of 0 <= z <= 1 at a node."""
    z_decrease: float = 0.0
    """Largest decrease of z at a node from one step to the next on an unchanged mesh."""
    energy_rise: float = -math.inf
    """Largest ``(E_k - E_{k-1}) / |E_{k-1}|`` over held-load steps on an unchanged mesh."""
    held_steps: int = 0
    first_nonfinite: int | None = None
    max_nv: int = 0
    records: list = field(default_factory=list)

    def __post_init__(self) -> None:
        self._sample = self.sampler(self.stepper.scene)
        self._previous = self.stepper.record()
        self._values = self._check_state(self._previous)
        self._solved_on = self._previous.n_adapt
        """The mesh (count of changes) the previous row's energies were computed on."""
        self.records.append(self._previous)

    def _check_state(self, record) -> np.ndarray:
        s = self.stepper
        finite = (np.all(np.isfinite(s.u.vec.FV().NumPy())) and np.all(np.isfinite(s.z.vec.FV().NumPy())))
        if not finite and self.first_nonfinite is None:
            self.first_nonfinite = record.step
        values = s.z_node_values()
        self.z_outside = max(self.z_outside, float(values.max()) - 1.0, -float(values.min()))
        self.max_nv = max(self.max_nv, record.nv)
        return values

    def observe(self, record) -> None:
        previous, values = self._previous, self._check_state(record)
        same_mesh = record.n_adapt == previous.n_adapt and len(values) == len(self._values)
        if same_mesh:
            self.z_decrease = max(self.z_decrease, float(np.max(self._values - values)))
        # a row's energies are of its step's solution on the mesh it was solved on, the mesh
        # of the row before (a step that ends with a mesh change reports them before it)
        same_energy_mesh = previous.n_adapt == self._solved_on
        self._solved_on = previous.n_adapt
        held = np.array_equal(self._sample(previous.t), self._sample(record.t))
        if same_energy_mesh and held and record.has_diagnostics and previous.has_diagnostics:
            self.held_steps += 1
            rise = (record.E_total - previous.E_total) / max(abs(previous.E_total), 1e-300)
            self.energy_rise = max(self.energy_rise, rise)
        self._previous, self._values = record, values
        self.records.append(record)

    def problems(self) -> list[str]:
        """What failed, one line each (empty when the run was stable)."""
        found = []
        if self.first_nonfinite is not None:
            found.append(f"non-finite u or z at step {self.first_nonfinite}")
        if self.z_outside > TOL:
            found.append(f"z left [0, 1] by {self.z_outside:.3e}")
        if self.z_decrease > TOL:
            found.append(f"z decreased by {self.z_decrease:.3e} on an unchanged mesh")
        if self.energy_rise > TOL:
            found.append(f"E_total rose by {self.energy_rise:.3e} (relative) with the load held")
        return found


# -- the cases ----------------------------------------------------------------------------
@dataclass(frozen=True)
class CaseResult:
    """A finished case: its scene, stepper and monitor, and the wall time of the run."""

    case: "StressCase"
    scene: Scene
    stepper: PhaseFieldStepper
    monitor: StabilityMonitor
    wall_s: float

    @property
    def records(self) -> list:
        """Every record, the initial state first."""
        return self.monitor.records

    @property
    def steps(self) -> int:
        """The number of steps run."""
        return self.records[-1].step

    def last(self, name: str) -> float:
        """A field of the last record."""
        return getattr(self.records[-1], name)

    def series(self, name: str) -> np.ndarray:
        """A field of every record as an array."""
        return np.array([getattr(r, name) for r in self.records], dtype=float)


@dataclass(frozen=True)
class StressCase:
    """A scene, how to start it, and the physical fact it must show.

    ``check(result)`` returns a list of problems (empty: the fact holds); ``min_held`` is the
    number of held-load steps the energy check must have seen.
    """

    name: str
    description: str
    scene: Callable[[], Scene]
    check: Callable[[CaseResult], list[str]] = lambda result: []
    slow: bool = False
    min_held: int = 0
    prepare: Callable[[PhaseFieldStepper], None] | None = None
    energy_known: str | None = None
    """Why E_total is known to rise in this case (a library weakness); :func:`problems`
    then leaves the energy out and :func:`energy_problems` reports it."""
    sampler: Callable[[Scene], Callable[[float], np.ndarray]] = load_sampler
    """Makes the sampler that tells whether the load is held (:func:`box_load_sampler` for a box)."""


def run_case(case: StressCase) -> CaseResult:
    """Run a case to its end time with diagnostics at every step."""
    scene = case.scene()
    started = time.perf_counter()
    stepper = PhaseFieldStepper(scene)
    if case.prepare is not None:
        case.prepare(stepper)
    monitor = StabilityMonitor(stepper, case.sampler)
    for record in stepper.run(history_every=1):
        monitor.observe(record)
    return CaseResult(case, scene, stepper, monitor, time.perf_counter() - started)


def problems(result: CaseResult) -> list[str]:
    """Every failed check of a finished case: stability, then the case's own fact (without
    the energy when the case has a known energy rise; see :func:`energy_problems`)."""
    found = result.monitor.problems()
    if result.case.energy_known:
        found = [line for line in found if not line.startswith("E_total rose")]
    if result.monitor.held_steps < result.case.min_held:
        found.append(f"only {result.monitor.held_steps} held-load steps on an unchanged mesh "
                     f"were checked (expected >= {result.case.min_held})")
    return found + result.case.check(result)


def energy_problems(result: CaseResult) -> list[str]:
    """The energy check alone."""
    return [line for line in result.monitor.problems() if line.startswith("E_total rose")]


def summary(result: CaseResult) -> str:
    """One line on a finished case, for assertion messages."""
    m = result.monitor
    return (f"{result.case.name}: {result.steps} steps in {result.wall_s:.1f} s, "
            f"z outside [0,1] {m.z_outside:.2e}, z decrease {m.z_decrease:.2e}, "
            f"energy rise {m.energy_rise:.2e} over {m.held_steps} held steps, max nv {m.max_nv}, "
            f"final tip_x {result.last('tip_x'):.3f}, crack length {result.last('crack_length'):.3f}")


def _cracked_fraction(stepper: PhaseFieldStepper, level: float = 0.99) -> float:
    """Area fraction where z >= level."""
    mesh = stepper.mesh
    with ngs.TaskManager():
        area = ngs.Integrate(ngs.CoefficientFunction(1.0), mesh)
        return float(ngs.Integrate(ngs.IfPos(stepper.z - level, 1.0, 0.0), mesh, order=6) / area)


def _expect(condition: bool, text: str) -> list[str]:
    return [] if condition else [text]


def check_crosses(result: CaseResult) -> list[str]:
    """The tip reached x > 0.95: the crack crossed the plate."""
    tip = np.nanmax(result.series("tip_x"))
    return _expect(tip > 0.95, f"the crack did not cross the plate (tip_x max {tip:.3f})")


def check_cut_and_cracked(result: CaseResult) -> list[str]:
    """The plate is cut, a large region is fully cracked, and the cut plate carries no load."""
    fraction = _cracked_fraction(result.stepper)
    found = check_crosses(result)
    found += _expect(fraction > 0.1, f"only {fraction:.1%} of the plate has z >= 0.99")
    first = result.records[0]
    found += _expect(result.last("E_el") < 0.01 * first.E_el,
                     f"the cut plate still stores {result.last('E_el'):.3g} elastic energy "
                     f"(start {first.E_el:.3g})")
    return found


def check_arrest(result: CaseResult) -> list[str]:
    """The crack runs from the slit tip (0.3) and stops before the tough part (x = 0.7)."""
    tip = result.series("tip_x")
    arrested = tip[-1] == tip[len(tip) // 2]
    return (_expect(0.45 < tip.max() < 0.7, f"tip_x max {tip.max():.3f}: expected 0.45 .. 0.7")
            + _expect(arrested, f"the tip still moved in the second half ({tip[len(tip) // 2]:.3f} "
                                f"-> {tip[-1]:.3f})"))


def check_no_healing(result: CaseResult) -> list[str]:
    """Crack length and tip never decrease; the crack grows in the first loading, not at all
    from 60% of the peak down to 0 and back up to 50%, and again beyond the old peak."""
    t = result.series("t")
    length = result.series("crack_length")
    tip = result.series("tip_x")
    found = []
    # The Gamma-length 1/2 int (eps|grad z|^2 + z^2/eps) is not monotone in z (a rising z can
    # flatten its gradient): it fell by up to 3e-10 while z rose at every node.
    drop = float(np.max(length[:-1] - length[1:]))
    found += _expect(drop <= 1e-6 * length.max(), f"the crack length decreased by {drop:.3e}")
    found += _expect(bool(np.all(np.diff(tip) >= 0)), "the tip moved back")
    peak, low, high = (int(np.searchsorted(t, v - 1e-9)) for v in (0.1, 0.14, 0.3))
    found += _expect(length[peak] > length[0] + 0.1, "no growth in the first loading")
    change = length[high] - length[low]
    found += _expect(change < 1e-3 * length[low], f"the crack grew by {change:.3e} below the old "
                                                   "peak load (unloading, zero load, reloading)")
    found += _expect(length[-1] > length[high] + 0.3, "no growth when reloaded past the old peak")
    return found


def check_cap(limit: int) -> Callable[[CaseResult], list[str]]:
    """The check of a capped adaptive run: at most ``limit`` vertices, at least three mesh
    changes, and the crack crossed the plate."""
    def check(result: CaseResult) -> list[str]:
        found = _expect(result.monitor.max_nv <= limit,
                        f"{result.monitor.max_nv} vertices, above the cap {limit}")
        found += _expect(len(result.stepper.adaptations) >= 3,
                         f"only {len(result.stepper.adaptations)} mesh changes")
        return found + check_crosses(result)
    return check


def cracked_annulus(stepper: PhaseFieldStepper) -> None:
    """z = 1 on the annulus ``0.12 <= |x - (0.65, 0.5)| <= 0.25`` (14% of the plate), with the
    optimal profile outside: the island inside is held by the residual stiffness alone."""
    points = stepper.nodes.points
    r = np.hypot(points[:, 0] - 0.65, points[:, 1] - 0.5)
    distance = np.maximum(0.0, np.maximum(0.12 - r, r - 0.25))
    profile = optimal_profile(distance, stepper.scene.phase_field.epsilon)
    stepper.nodes.assign(stepper.z, np.maximum(stepper.z_node_values(), profile))


TOUGHNESS_JUMP = "1 + 99*(0.5 + 0.5*tanh((x - 0.7)/0.04))"
"""gamma 1 for x < 0.7, 100 beyond: contrast 100:1, the jump smoothed over h = 0.04 each side."""

UNLOAD_RELOAD = "10*max(max(0.1 - abs(t - 0.1), t - 0.25), 0)"
"""Up to 1 at t = 0.1, down to 0 at t = 0.2, held at 0 until t = 0.25, up again (1.5 at 0.4)."""

RAMP_HOLD = "10*min(t, 0.1)"
"""Up to 1 (about 1.4 times the critical load) at t = 0.1, then held."""

ENERGY_PROJECTION = ("E_total rises with the load held on a fixed mesh: the nodal projection "
                     "z = min(1, max(z_trial, z_old)) after the unconstrained z-solve is not a "
                     "descent step. Once the crack rests (arrested, or the plate cut) the z-solve "
                     "lowers E by healing (4e-3 .. 6e-2 of E), the projection adds that back and "
                     "up to 1e-7 .. 6e-7 of E more. discretization.z_update = 'descent' with "
                     "coupling = 'staggered' does not (the *_descent cases)")

CASES: list[StressCase] = [
    StressCase("dt_100x", f"tau = 0.05 (100 x the demo's {DEMO_DT:g}), mode III, ramp to 1 then "
               "held, P2",
               lambda: slit(*mode3_load(RAMP_HOLD), f"time.dt={100 * DEMO_DT}", "time.t_end=3.0"),
               check_crosses, min_held=50),
    StressCase("dt_adaptive_128x", f"adaptive time steps from {DEMO_DT:g} up to 128 x (max_doublings "
               "7), ramp and hold until cut, P2",
               lambda: slit(*mode3_load(RAMP_HOLD), f"time.dt={DEMO_DT}", "time.adaptive=true",
                            "time.max_doublings=7", "time.t_end=0.5"),
               check_crosses, min_held=25, energy_known=ENERGY_PROJECTION),
    StressCase("alpha1_0_cracked", "alpha1 = 0, z = 1 on an annulus (14% of the plate, a "
               "floating island inside), load 2.5 (3.5 x critical) held until the plate is cut, P1",
               lambda: slit(*mode3_load("2.5"), "phase_field.alpha1=0.0", "discretization.order=1",
                            "time.dt=1e-3", "time.t_end=0.15"),
               check_cut_and_cracked, min_held=140, prepare=cracked_annulus),
    StressCase("epsilon_2hmin", "epsilon = 0.07 on the uniform h = 0.04 mesh (smallest element "
               "0.0345: epsilon = 2 hmin), ramp and hold, P2",
               lambda: slit(*mode3_load(RAMP_HOLD), "phase_field.epsilon=0.07", "time.dt=1e-3",
                            "time.t_end=0.2"),
               check_crosses, min_held=90),
    StressCase("epsilon_1.2hmin", "epsilon = 0.04 on the uniform h = 0.04 mesh (epsilon = 1.16 "
               "hmin, below the range), ramp and hold, P2",
               lambda: slit(*mode3_load(RAMP_HOLD), "phase_field.epsilon=0.04", "time.dt=1e-3",
                            "time.t_end=0.2"),
               check_crosses, slow=True, min_held=90),
    StressCase("toughness_100to1", "gamma 1 : 100 across x = 0.7 (tanh over h), ramp and hold: "
               "the crack runs, then arrests, P1",
               lambda: slit(*mode3_load(RAMP_HOLD), f'material.gamma="{TOUGHNESS_JUMP}"',
                            "discretization.order=1", "time.dt=1e-3", "time.t_end=0.3"),
               check_arrest, min_held=190, energy_known=ENERGY_PROJECTION),
    StressCase("toughness_100to1_descent", "as toughness_100to1 with z_update = 'descent' and "
               "coupling = 'staggered': the energy-descent variant of the scheme",
               lambda: slit(*mode3_load(RAMP_HOLD), f'material.gamma="{TOUGHNESS_JUMP}"',
                            "discretization.order=1", "time.dt=1e-3", "time.t_end=0.3",
                            'discretization.z_update="descent"', 'discretization.coupling="staggered"'),
               check_arrest, min_held=190),
    StressCase("dt_adaptive_128x_descent", "as dt_adaptive_128x with z_update = 'descent' and "
               "coupling = 'staggered'",
               lambda: slit(*mode3_load(RAMP_HOLD), f"time.dt={DEMO_DT}", "time.adaptive=true",
                            "time.max_doublings=7", "time.t_end=0.5",
                            'discretization.z_update="descent"', 'discretization.coupling="staggered"'),
               check_crosses, min_held=10),
    StressCase("unload_reload", "load 0 -> 1 -> 0 (held) -> 1.5, P1",
               lambda: slit(*mode3_load(UNLOAD_RELOAD), "discretization.order=1", "time.dt=2e-3",
                            "time.t_end=0.4"),
               check_no_healing, min_held=20),
    StressCase("plane_strain_tension", "plane strain (E 50, nu 0.29), slit, uy = 0.3 on top "
               "(ramp and hold), rollers below, until cut, P1",
               lambda: plane_strain("3*min(t, 0.1)", "discretization.order=1", "time.dt=2e-3",
                                    "time.t_end=0.3"),
               check_crosses, min_held=90),
    StressCase("vertex_cap_500", "adaptive, max_vertices 500, epsilon 0.04, hmin 2e-3, ramp and "
               "hold, P2",
               lambda: slit(*mode3_load(RAMP_HOLD), "adaptivity.enabled=true",
                            "adaptivity.max_vertices=500", "phase_field.epsilon=0.04",
                            "time.dt=1e-3", "time.t_end=0.4"),
               check_cap(500)),
    StressCase("epsilon_2hmin_adaptive", "adaptive, epsilon = 2 hmin = 0.02 (h_crack = h_band = "
               "hmin = 0.01), ramp and hold, P2",
               lambda: slit(*mode3_load(RAMP_HOLD), "adaptivity.enabled=true",
                            "adaptivity.hmin=0.01", "phase_field.epsilon=0.02", "time.dt=1e-3",
                            "time.t_end=0.3"),
               check_crosses, slow=True),
    StressCase("steps_5000", "5,000 steps on a 130-vertex mesh (h 0.1, epsilon 0.2, P1), ramp "
               "and hold",
               lambda: slit(*mode3_load("10*min(t, 0.2)"), "phase_field.epsilon=0.2",
                            "geometry.mesh_size=0.1", "discretization.order=1", "time.dt=1e-4",
                            "time.t_end=0.5"),
               check_crosses, slow=True, min_held=2500),
]
CASE_BY_NAME = {case.name: case for case in CASES}


# -- the 3D case --------------------------------------------------------------------------
def box_scene_data() -> dict:
    """A unit cube pulled apart in y (top face y = 1 up, bottom face y = 0 clamped), the
    load ramped to t = 0.1 and then held: the 3D twin of the held-load stress cases."""
    data = demo_data()
    data["model"] = {"kind": "elasticity_3d"}
    data["material"] = {"E": 50.0, "nu": 0.29, "gamma": 1.0}
    data["geometry"] = {"kind": "box", "width": 1.0, "height": 1.0, "depth": 1.0, "mesh_size": 0.2}
    data["cracks"] = []
    data["loads"] = [{"boundary": "top", "value": ["0", "10*min(t, 0.1)", "0"]},
                     {"boundary": "bottom", "value": ["0", "0", "0"]}]
    data["phase_field"]["epsilon"] = 0.2
    data["time"] = {"dt": 4e-3, "t_end": 0.2}
    data["adaptivity"] = {"enabled": False}
    data["discretization"] = {"order": 1}
    data["output"] = {"vtk_every": 0, "checkpoint_every": 0}
    return data


def check_box_damaged(result: CaseResult) -> list[str]:
    """The cube damaged and carries less than twice its sound stiffness (E strain area)."""
    last = result.records[-1]
    sound = 50.0 * 0.1 * 1.0
    return (_expect(last.dz_max >= 0 and last.crack_length > 0.01,
                    f"no damage: crack length {last.crack_length:.3g}")
            + _expect(0 < last.forces["Fy_top"] < 2 * sound and math.isfinite(last.E_total),
                      f"force on the top {last.forces['Fy_top']:.3g} outside (0, {2 * sound:g})"))


BOX_3D = StressCase("box_3d", "unit cube pulled apart in y (E 50, nu 0.29, h 0.2), P1, ramp "
                    "and hold", lambda: Scene.from_dict(box_scene_data()), check_box_damaged,
                    min_held=20, sampler=box_load_sampler)
"""The 3D case of tests/stress/test_stress_3d.py; its sampler walks the six faces."""


# -- a forced solver failure with checkpoints ---------------------------------------------
FAIL_AT = 5
FAILURE_SCENE = ("output.checkpoint_every=2", "time.dt=1e-3", "time.t_end=0.01")
"""Ten steps, a checkpoint every two: the failure at step 5 leaves the one of step 4."""


def failure_scene() -> Scene:
    """The slit, ramped and held, ten steps with a checkpoint every two."""
    return slit(*mode3_load(RAMP_HOLD), *FAILURE_SCENE)


def _failing(time: Any) -> bool:
    """Whether the step being solved is step FAIL_AT (the step's time Parameter is t_FAIL_AT)."""
    dt = failure_scene().time.dt
    return abs(time.Get() - FAIL_AT * dt) < 0.5 * dt


def poison(sub_step: str) -> tuple[type, str, Callable]:
    """(class, method name, replacement) making the u- or z-solve of step FAIL_AT produce NaN.

    The NaN goes in below the sub-problem's own finiteness check, so the error raised is the
    library's: a Dirichlet value (u) or the z-solve's result (z).
    """
    if sub_step == "u":
        original = DisplacementProblem.apply_boundary_values

        def apply_boundary_values(self):
            original(self)
            if _failing(self.context.time):
                fixed = ~np.array(self.fields.fes_u.FreeDofs(), dtype=bool)
                self.fields.u.vec.FV().NumPy()[fixed] = math.nan
        return DisplacementProblem, "apply_boundary_values", apply_boundary_values
    original_system = AssembledSystem.solve_system

    def solve_system(self, z_trial, step):
        iterations = original_system(self, z_trial, step)
        if _failing(self.context.time):
            z_trial.vec[:] = math.nan
        return iterations
    return AssembledSystem, "solve_system", solve_system


@dataclass(frozen=True)
class FailureResult:
    """What :func:`run_failure` saw: the error, the checkpoint's step, the restart's last
    step and whether it matched the uninterrupted run, and the wall time."""

    error: SolverError | None
    checkpoint_step: int | None
    restarted_step: int | None
    restart_matches: bool
    wall_s: float


def run_failure(sub_step: str, folder: Path,
                patch: Callable[[type, str, Callable], Callable[[], None]]) -> FailureResult:
    """Run the failure scene with ``run_scene`` and the poisoned sub-step, then restart it.

    ``patch(cls, name, function)`` installs the replacement on the sub-problem's class and
    returns an undo (pytest's monkeypatch in the tests, a plain setattr in the benchmark).
    """
    scene = failure_scene()
    started = time.perf_counter()
    undo = patch(*poison(sub_step))
    error = None
    try:
        run_scene(scene, folder, plots=False)
    except SolverError as err:
        error = err
    finally:
        undo()
    checkpoint = folder / CHECKPOINT
    k = load_checkpoint(checkpoint, scene).k if checkpoint.exists() else None
    summary = run_scene(scene, folder, plots=False, restart=True) if k is not None else None
    reference = PhaseFieldStepper(scene)
    for _ in range(scene.time.n_steps):
        expected = reference.step()
    matches = summary is not None and math.isclose(summary.last.E_total, expected.E_total,
                                                   rel_tol=1e-10)
    return FailureResult(error, k, None if summary is None else summary.last.step, matches,
                         time.perf_counter() - started)


def failure_problems(result: FailureResult, sub_step: str) -> list[str]:
    """The error is a SolverError saying which sub-step failed and what to change; the
    checkpoint of step FAIL_AT - 1 loads and a restart from it reproduces the run."""
    fix = "raise phase_field.residual_stiffness or lower time.dt" if sub_step == "u" else "lower time.dt"
    found = []
    if result.error is None:
        found.append("no SolverError was raised")
    else:
        text = str(result.error)
        found += _expect(f"the {sub_step}-solve gave non-finite values" in text and fix in text,
                         f"unclear message: {text!r}")
    found += _expect(result.checkpoint_step == FAIL_AT - 1,
                     f"checkpoint at step {result.checkpoint_step}, expected {FAIL_AT - 1}")
    found += _expect(result.restart_matches, "the restart did not reproduce the uninterrupted run")
    return found


def failing_step_problems(result: FailureResult) -> list[str]:
    """The message names the step and time that failed (step FAIL_AT, t = FAIL_AT dt)."""
    where = f"at step {FAIL_AT} (t={FAIL_AT * failure_scene().time.dt:g})"
    text = str(result.error)
    return _expect(where in text, f"the message does not say {where!r}: {text!r}")


FAILING_STEP = ("since 825735c (adaptive time steps) PhaseFieldStepper.step() advances k and "
                "ticks only after both solves, so solve_u/_solve_z report the last finished step: "
                "a NaN in step 5 (t=0.005) says 'at step 4 (t=0.004)'")
