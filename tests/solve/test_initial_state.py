"""u0, the elastic state at t = 0: a scene unloaded at t = 0 skips the factorization.

With u = 0 on the boundary, no load form and no alpha1 term the u0-system's right-hand side
is exactly 0, so u0 = 0 and its reactions are 0 without assembling or factorizing (what a
solve would give: a direct solve of a zero right-hand side returns exact zeros); the first
factorization moves into step 1, whose matrix is the same. A scene loaded at t = 0 still
solves.
"""
import numpy as np
import pytest

from ngfrac import PhaseFieldStepper
from ngfrac.testing.scenes import QUICK, demo_data, quick_slit, scene_from

SHORT = ("time.t_end=4e-3", "time.dt=4e-3")


def test_an_unloaded_initial_state_is_zero_without_a_factorization():
    stepper = PhaseFieldStepper(quick_slit(*SHORT))
    assert stepper.u_problem.linear.inverse is None
    assert not stepper.fields.u.vec.FV().NumPy().any()
    assert stepper.forces and all(value == 0.0 for value in stepper.forces.values())
    for _ in stepper.run():
        pass
    assert stepper.u_problem.linear.inverse is not None  # step 1 factorized
    assert np.abs(stepper.fields.u.vec.FV().NumPy()).max() > 0.0


def test_a_scene_loaded_at_t0_still_solves_u0():
    data = demo_data()
    data["loads"][0]["value"] = "1e-3 + 10*t"  # top: u = 1e-3 at t = 0
    stepper = PhaseFieldStepper(scene_from(data, *QUICK, *SHORT))
    problem = stepper.u_problem
    assert problem.linear.inverse is not None
    free = ~problem.dirichlet.fixed
    residual = problem.residual().FV().NumPy()
    u = stepper.fields.u.vec.FV().NumPy()
    assert np.abs(u[free]).max() > 1e-4  # the interior moved with the top edge
    assert np.abs(residual[free]).max() < 1e-10 * np.abs(residual).max()
    # equilibrium: the free edges carry nothing, so the two reactions balance
    assert stepper.forces["Fz_top"] == pytest.approx(-stepper.forces["Fz_bottom"], rel=1e-9)
    assert stepper.forces["Fz_top"] > 0.0
