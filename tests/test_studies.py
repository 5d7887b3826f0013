"""ngfrac.studies.convergence_study: the manufactured u-solve study, rate fitting on synthetic
data, and clear errors for bad keys and values."""
import math

import numpy as np
import ngsolve as ngs
import pytest

from ngfrac.geometry.domains import build_mesh
from ngfrac.scene import SceneError
from ngfrac.solve.stepper import PhaseFieldStepper
from ngfrac.studies import StudyRun, convergence_study, fit_rate, scene_with

from ngfrac.testing.manufactured import u_scene as u_solve_scene
from ngfrac.testing.scenes import quick_slit

EXACT = ngs.sin(ngs.pi * ngs.x) * ngs.sin(ngs.pi * ngs.y)
GRAD_EXACT = ngs.CoefficientFunction((ngs.pi * ngs.cos(ngs.pi * ngs.x) * ngs.sin(ngs.pi * ngs.y),
                                      ngs.pi * ngs.sin(ngs.pi * ngs.x) * ngs.cos(ngs.pi * ngs.y)))


def frozen_z_u_solve(scene):
    """One u-solve with z = (x + y)/4 frozen (the manufactured problem of ngfrac.testing.manufactured), on
    the uniform mesh of ``geometry.mesh_size`` (the demo scene it starts from is adaptive)."""
    stepper = PhaseFieldStepper(scene, mesh=build_mesh(scene.geometry, scene.mesh_size))
    points = stepper.nodes.points
    stepper.nodes.assign(stepper.z, 0.25 * (points[:, 0] + points[:, 1]))
    stepper.solve_u()
    return stepper


def l2_error(stepper, reference):
    order = 2 * stepper.scene.discretization.order + 6
    return math.sqrt(ngs.Integrate((stepper.u - EXACT) ** 2, stepper.mesh, order=order))


def h1_error(stepper, reference):
    order = 2 * stepper.scene.discretization.order + 6
    diff = ngs.grad(stepper.u) - GRAD_EXACT
    return math.sqrt(ngs.Integrate(ngs.InnerProduct(diff, diff), stepper.mesh, order=order))


def test_manufactured_u_solve_order_2():
    table = convergence_study(u_solve_scene(2), "geometry.mesh_size", [0.2, 0.1, 0.05, 0.025],
                              {"L2": l2_error, "H1": h1_error}, run=frozen_z_u_solve)
    print(table)
    table.assert_rate("L2", 3.0, tol=0.2)
    table.assert_rate("H1", 2.0, tol=0.2)
    assert [row.value for row in table.rows] == [0.2, 0.1, 0.05, 0.025]
    assert all(row.ndof is not None for row in table.rows)  # read from the stepper's spaces


def test_against_ndof_the_rate_is_negative_and_halved():
    table = convergence_study(u_solve_scene(2), "geometry.mesh_size", [0.2, 0.1, 0.05],
                              {"L2": l2_error}, run=frozen_z_u_solve, abscissa="ndof")
    table.assert_rate("L2", -1.5, tol=0.15)


# -- synthetic data: the table and the fit ---------------------------------------------------
def power_law(scene):
    """A fake run: the "result" is the mesh size itself."""
    return scene.geometry.mesh_size


SYNTHETIC = {"two": lambda h, ref: 3.0 * h ** 2, "three": lambda h, ref: 0.5 * h ** 3}


def test_exact_power_laws_give_exact_rates():
    table = convergence_study(quick_slit(), "geometry.mesh_size", [0.4, 0.2, 0.1, 0.05],
                              SYNTHETIC, run=power_law)
    assert table.rates["two"] == pytest.approx(2.0, abs=1e-12)
    assert table.rates["three"] == pytest.approx(3.0, abs=1e-12)
    np.testing.assert_allclose(table.local_rates("two")[1:], 2.0)
    table.assert_rate("two", 2.0, tol=0.01)
    table.assert_rate("three", 2.5, tol=0.1, at_least=True)
    assert len(table.rows) == 4 and table.rows[0].errors["two"] == pytest.approx(0.48)


def test_failed_rate_prints_the_table():
    table = convergence_study(quick_slit(), "geometry.mesh_size", [0.4, 0.2, 0.1],
                              SYNTHETIC, run=power_law)
    with pytest.raises(AssertionError) as info:
        table.assert_rate("two", 3.0, tol=0.2)
    message = str(info.value)
    assert "two rate 2.000" in message and "expected 3 +- 0.2" in message
    assert "geometry.mesh_size" in message and "1.200e-01" in message  # the row of h = 0.2
    assert str(table) in message
    with pytest.raises(KeyError, match="no error named 'four'"):
        table.assert_rate("four", 4.0, tol=0.1)


def test_reference_last_is_passed_and_gets_no_row():
    seen = []

    def against_reference(h, reference):
        seen.append(reference)
        return abs(h - reference)

    table = convergence_study(quick_slit(), "geometry.mesh_size", [0.4, 0.2, 0.1, 0.0],
                              {"diff": against_reference}, run=power_law, reference="last")
    assert seen == [0.0, 0.0, 0.0]
    assert [row.value for row in table.rows] == [0.4, 0.2, 0.1]
    assert table.rates["diff"] == pytest.approx(1.0)


def test_fit_rate_ignores_zero_and_non_finite_errors():
    assert fit_rate([1, 0.5, 0.25], [1, 0.25, 0.0625]) == pytest.approx(2.0)
    assert fit_rate([1, 0.5, 0.25], [1, 0.25, 0.0]) == pytest.approx(2.0)
    assert math.isnan(fit_rate([1, 0.5], [1, math.nan]))


def test_default_run_steps_the_scene():
    table = convergence_study(quick_slit("time.t_end=0.002", "geometry.mesh_size=0.1",
                                         "phase_field.epsilon=0.2"),
                              "time.dt", [2e-3, 1e-3], {"steps": lambda run, ref: len(run.records) - 1})
    assert [row.errors["steps"] for row in table.rows] == [1, 2]
    assert table.rates["steps"] == pytest.approx(-1.0)
    assert all(row.ndof > 0 for row in table.rows)


# -- clear errors ----------------------------------------------------------------------------
def test_unknown_key_fails_before_any_run():
    calls = []
    with pytest.raises(SceneError, match=r"unknown key 'geometry.mesh_sise'.*did you mean "
                                         r"'geometry.mesh_size'"):
        convergence_study(quick_slit(), "geometry.mesh_sise", [0.1, 0.05],
                          {"e": lambda r, ref: 1.0}, run=calls.append)
    assert calls == []
    with pytest.raises(SceneError, match="unknown key 'geom'"):
        scene_with(quick_slit(), "geom.mesh_size", 0.1)


def test_value_out_of_range_names_the_key():
    with pytest.raises(SceneError, match=r"over 'phase_field.epsilon'.*phase_field.epsilon = -0.1"):
        convergence_study(quick_slit(), "phase_field.epsilon", [0.1, -0.1],
                          {"e": lambda r, ref: 1.0}, run=power_law)


def test_string_and_integer_values_are_written_as_toml():
    assert scene_with(quick_slit(), "discretization.coupling", "staggered").discretization.coupling == "staggered"
    assert scene_with(quick_slit(), "discretization.order", 3).discretization.order == 3
    assert scene_with(quick_slit(), "material.gamma", "1 + 0.5*x").material.gamma.text == "1 + 0.5*x"


def test_non_numeric_values_need_another_abscissa():
    with pytest.raises(TypeError, match="abscissa='ndof'"):
        convergence_study(quick_slit(), "discretization.coupling", ["paper", "staggered"],
                          {"e": lambda r, ref: 1.0}, run=power_law)
    with pytest.raises(ValueError, match="at least two values"):
        convergence_study(quick_slit(), "time.dt", [1e-3], {"e": lambda r, ref: 1.0})


def test_study_run_reports_ndof():
    run = StudyRun(scene=None, stepper=None, records=[type("R", (), {"ndof": 7})()])
    assert run.ndof == 7
