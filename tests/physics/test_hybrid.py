"""The hybrid formulation (Ambati, Gerasimov, De Lorenzis 2015, ``material.split_mode =
"hybrid"``) and a split run that survives a failed Newton u-solve (the step is halved).

A unit square in plane strain (E = 1, nu = 0.3) with u = s t (x, y) on its whole boundary
(s = -1: equibiaxial compression, s = +1: tension) is homogeneous, e = s t diag(1, 1, 0), and
P1 represents it exactly. In compression, Amor's psi+ = mu |dev e|^2 = 2/3 mu t^2 is below
psi- = K/2 (tr e)^2 = 2 K t^2, so the hybrid drive is 0 and z stays 0 exactly (AT2's z-step
then has no source), while the paper's model (no split) damages at any load. In tension
tr e > 0 and psi+ = psi, psi- = 0: the hybrid run is the no-split run (same u-step, same
drive sigma:e), to round-off.
"""
from __future__ import annotations

import numpy as np
import pytest

from ngfrac import PhaseFieldStepper, Scene
from ngfrac.scene import SceneError
from ngfrac.solve.u_problem import DisplacementProblem, SolverError

SIDES = ("left", "right", "bottom", "top")


def block_scene(sign: int, split: str = "none", split_mode: str = "full", *,
                adaptive: bool = False, steps: int = 3) -> Scene:
    value = [f"{sign}*t*x", f"{sign}*t*y"]
    return Scene.from_dict({
        "model": {"kind": "plane_strain"},
        "material": {"E": 1.0, "nu": 0.3, "gamma": 1.0, "split": split, "split_mode": split_mode},
        "phase_field": {"epsilon": 0.1, "alpha2": 1e-3},
        "geometry": {"width": 1.0, "height": 1.0, "mesh_size": 0.25},
        "loads": [{"boundary": side, "value": value} for side in SIDES],
        "time": {"dt": 0.25, "t_end": 0.25 * steps, "adaptive": adaptive, "max_doublings": 2},
        "adaptivity": {"enabled": False}, "output": {"vtk_every": 0},
        "discretization": {"order": 1}})


def run(scene: Scene) -> tuple[PhaseFieldStepper, list, list[np.ndarray]]:
    stepper = PhaseFieldStepper(scene)
    records, z = [], []
    for record in stepper.run():
        records.append(record)
        z.append(stepper.z_node_values().copy())
    return stepper, records, z


@pytest.mark.parametrize("split", ["amor", "miehe"])
def test_hybrid_holds_z_in_compression_where_the_paper_model_damages(split):
    _, _, z_none = run(block_scene(-1))
    stepper, _, z_hybrid = run(block_scene(-1, split, "hybrid"))
    assert z_none[-1].min() > 1e-3  # AT2 without a split: damage at any load
    assert all(np.all(z == 0.0) for z in z_hybrid)
    assert stepper.u_problem.split is None and stepper.u_problem.newton is None  # linear u-step


def test_hybrid_equals_no_split_in_tension():
    """psi+ = psi in equibiaxial tension (Amor, tr e > 0): u-step and drive are the paper's, so
    z and the reactions agree to 1e-12 relative (the same sums in another order)."""
    _, plain, z_plain = run(block_scene(+1))
    stepper, hybrid, z_hybrid = run(block_scene(+1, "amor", "hybrid"))
    assert z_plain[-1].min() > 1e-3
    for a, b, za, zb in zip(plain, hybrid, z_plain, z_hybrid):
        np.testing.assert_allclose(zb, za, rtol=1e-12, atol=1e-15)
        assert b.forces["Fx_right"] == pytest.approx(a.forces["Fx_right"], rel=1e-12)
        assert b.E_el == pytest.approx(a.E_el, rel=1e-12)
    assert stepper.u_problem.newton is None


def test_hybrid_needs_a_split():
    with pytest.raises(SceneError, match=r"^material\.split_mode = 'hybrid' is not allowed: "
                                         r"'hybrid' needs a split"):
        block_scene(1, "none", "hybrid")
    with pytest.raises(SceneError, match=r"^material\.split_mode = 'half' is not allowed"):
        block_scene(1, "amor", "half")


@pytest.fixture
def newton_fails_above(monkeypatch):
    """Newton gets ``max_iterations = 0`` on steps longer than ``limit["dt"]`` (it raises
    RuntimeError, as when it does not converge) and its default 30 otherwise: a forced failure
    on this small scene, where Newton converges in one iteration at any step size."""
    limit = {"dt": 0.25}
    steps: list[float] = []
    original = DisplacementProblem._solve_newton

    def solve(self, step):
        inv_dt = self.context.inv_dt.Get()
        dt = 1.0 / inv_dt if inv_dt > 0 else 0.0  # 0: the initial (static) solve
        steps.append(dt)
        self._newton.max_iterations = 0 if dt > limit["dt"] * (1 + 1e-12) else 30
        return original(self, step)

    monkeypatch.setattr(DisplacementProblem, "_solve_newton", solve)
    return limit, steps


def test_a_failed_newton_step_is_redone_with_half_the_step(newton_fails_above):
    """Adaptive steps of up to 4 dt (max_doublings = 2) with the full Amor split: every step
    longer than dt fails in Newton and is halved until it is dt; the run reaches t_end with
    each time of the grid once, and its z is that of a run with fixed steps dt."""
    limit, steps = newton_fails_above
    stepper = PhaseFieldStepper(block_scene(+1, "amor", adaptive=True, steps=6))
    records = list(stepper.run())
    assert [r.t for r in records] == pytest.approx([0.25 * k for k in range(1, 7)])
    assert all(r.dt == pytest.approx(0.25) for r in records)
    assert stepper.timer.calls["time: halved steps (Newton failed)"] >= 2
    assert max(steps) == pytest.approx(1.0)  # the first step was tried at 4 dt
    fixed = PhaseFieldStepper(block_scene(+1, "amor", steps=6))
    list(fixed.run())
    np.testing.assert_allclose(stepper.z_node_values(), fixed.z_node_values(), rtol=1e-12)


def test_newton_failing_at_dt_stops_the_run_with_the_clear_error(newton_fails_above):
    """At the smallest step (dt; fixed steps have no other) the run gives up: SolverError
    naming the split and what to change."""
    limit, _ = newton_fails_above
    limit["dt"] = 0.1
    for adaptive in (False, True):
        stepper = PhaseFieldStepper(block_scene(+1, "amor", adaptive=adaptive))
        with pytest.raises(SolverError, match=r"material\.split = 'amor'\) failed .*lower "
                                              r"time\.dt") as info:
            stepper.step()
        assert "\n" not in str(info.value)
    assert stepper.timer.calls["time: halved steps (Newton failed)"] == 2  # 4 dt -> 2 dt -> dt
