"""Adaptive time steps: exact output times, long steps while z rests, short ones while it runs."""
import numpy as np
import pytest

from ngfrac.solve.stepper import PhaseFieldStepper

from ngfrac.testing.scenes import quick_slit

DT = 2.5e-4
ADAPTIVE = [f"time.dt={DT}", "time.adaptive=true", "time.max_doublings=4"]


def run(*overrides):
    stepper = PhaseFieldStepper(quick_slit(*overrides))
    return stepper, list(stepper.run())


@pytest.fixture(scope="module")
def adaptive():
    return run(*ADAPTIVE)


def test_output_times_are_hit_exactly(adaptive):
    stepper, records = adaptive
    times = {r.t for r in records}
    big = DT * 16
    expected = [m * big for m in range(1, int(stepper.scene.time.t_end / big) + 1)]
    missing = [t for t in expected if t not in times]  # exact: times are products n * dt
    assert not missing, missing[:5]
    assert records[-1].t == stepper.scene.time.n_ticks * DT


def test_steps_grow_while_z_rests_and_shrink_while_it_runs(adaptive):
    _, records = adaptive
    dt = np.array([r.dt for r in records])
    t = np.array([r.t for r in records])
    tip = np.array([r.tip_x for r in records])
    running = (tip > 0.35) & (tip < 0.95)
    assert dt[t < 0.03].max() == DT * 16  # early loading: z barely changes
    assert dt[running].max() < DT * 16 and dt[running].min() <= DT * 2
    assert len(records) < 0.5 * round(0.15 / DT)


def test_bounds_hold(adaptive):
    stepper, _ = adaptive
    z = stepper.z_node_values()
    assert z.min() >= 0 and z.max() <= 1


@pytest.mark.slow
def test_same_crack_history_as_fixed_steps_with_fewer_steps():
    fixed_stepper, fixed = run(f"time.dt={DT}")
    _, adaptive_records = run(*ADAPTIVE)
    t = np.array([r.t for r in fixed])
    length = np.array([r.crack_length for r in fixed])
    t2 = np.array([r.t for r in adaptive_records])
    length2 = np.array([r.crack_length for r in adaptive_records])
    error = np.max(np.abs(np.interp(t, t2, length2) - length) / length)
    message = f"{len(adaptive_records)} adaptive steps against {len(fixed)}, max rel error {error:.4f}"
    print(message)
    assert error < 0.02, message
    assert len(adaptive_records) < 0.5 * len(fixed), message
