"""Scene validation: every bad input gives one clear line naming key, value and fix."""
import copy
import dataclasses

import numpy as np
import pytest

from ngfrac import PhaseFieldStepper
from ngfrac.scene.expressions import Expression
from ngfrac.io.output import to_toml
from ngfrac.fem.threads import single_thread
from ngfrac.scene import (Components, Crack, Discretization, Geometry, Load, Material, Model, Output,
                          PhaseField, Scene, SceneError, TimeSettings, apply_overrides, load_scene)

from ngfrac.testing.scenes import DEMOS, demo_data, scene_from


def bad(data, match):
    with pytest.raises(SceneError, match=match) as info:
        Scene.from_dict(data)
    message = str(info.value)
    assert "\n" not in message
    return message


def test_demo_scenes_are_valid():
    import importlib.util
    import sys

    # the part of demos/notched_cylinder.toml: its script writes the STEP file if missing
    sys.path.insert(0, str(DEMOS))
    spec = importlib.util.spec_from_file_location("demo_notched_cylinder",
                                                  DEMOS / "notched_cylinder.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.write_step_file()
    for path in DEMOS.glob("*.toml"):
        load_scene(path)


def test_missing_key():
    data = demo_data()
    del data["phase_field"]["epsilon"]
    bad(data, r"missing key 'phase_field.epsilon'")


def test_missing_section():
    data = demo_data()
    del data["time"]
    bad(data, r"missing section \[time\]")


def test_unknown_key_suggests_the_closest():
    data = demo_data()
    data["phase_field"]["epsilom"] = data["phase_field"].pop("epsilon")
    message = bad(data, r"unknown key 'phase_field.epsilom'")
    assert "did you mean 'phase_field.epsilon'" in message


def test_unknown_top_level_section_suggests():
    data = demo_data()
    data["materail"] = data.pop("material")
    bad(data, r"unknown key 'materail'; did you mean 'material'")


def test_unknown_model():
    data = demo_data()
    data["model"]["kind"] = "mode4"
    bad(data, r"model.kind = 'mode4' is not a known model.*mode3")


@pytest.mark.parametrize("value", [0.0, -0.01])
def test_epsilon_not_positive(value):
    data = demo_data()
    data["phase_field"]["epsilon"] = value
    bad(data, r"phase_field.epsilon = .* must be > 0")


def test_unknown_size_field():
    data = demo_data()
    data["adaptivity"]["size_field"] = "metric"
    bad(data, r"adaptivity.size_field = 'metric' .*choose 'bands' or 'equidistributed'")


def test_concurrent_substeps_need_the_papers_coupling_and_no_threaded_solves():
    data = demo_data()
    data.setdefault("discretization", {}).update(concurrent_substeps=True, coupling="staggered")
    bad(data, r"discretization.concurrent_substeps = True .*needs coupling = 'paper'")
    data["discretization"].update(coupling="paper", threaded_solves=True)
    bad(data, r"discretization.concurrent_substeps = True .*threaded_solves = true excludes it")


@pytest.mark.parametrize("change, match", [
    ({"coupling": "iterated"}, r"discretization.coupling = 'iterated' .*'alternate'"),
    ({"coupling": "alternate", "alternate_tolerance": 0.0},
     r"discretization.alternate_tolerance = 0.0 .*must be > 0"),
    ({"coupling": "alternate", "alternate_passes": 0},
     r"discretization.alternate_passes = 0 .*must be an integer >= 1"),
])
def test_bad_alternate_coupling_is_one_line(change, match):
    data = demo_data()
    data.setdefault("discretization", {}).update(change)
    bad(data, match)


def test_gamma_negative_constant():
    data = demo_data()
    data["material"]["gamma"] = -1.0
    bad(data, r"material.gamma = .* <= 0 at")


def test_gamma_negative_somewhere_in_the_domain():
    data = demo_data()
    data["material"]["gamma"] = "0.5*(1 + 1.5*sin(20*(x+y)))"
    message = bad(data, r"material.gamma")
    assert "(x, y) =" in message and "> 0 everywhere" in message


@pytest.mark.parametrize("value", [0.0, -1e-3])
def test_time_step_not_positive(value):
    data = demo_data()
    data["time"]["dt"] = value
    bad(data, r"time.dt = .* must be > 0")


def test_crack_outside_domain():
    data = demo_data()
    data["cracks"][0]["points"] = [[0.0, 0.5], [1.3, 0.5]]
    bad(data, r"cracks\[0\].points: point \[1.3, 0.5\] lies outside the domain")


def test_expression_that_does_not_parse():
    data = demo_data()
    data["loads"][0]["value"] = "10*t +"
    bad(data, r"loads\[0\].value: cannot parse expression '10\*t \+'")


def test_expression_with_unknown_name():
    data = demo_data()
    data["material"]["gamma"] = "1 + foo(x)"
    bad(data, r"material.gamma: .*unknown function 'foo'")


def test_load_on_unknown_boundary():
    data = demo_data()
    data["loads"][0]["boundary"] = "topp"
    message = bad(data, r"loads\[0\].boundary = 'topp' is not a boundary")
    assert "did you mean 'top'" in message


def test_string_where_a_number_belongs():
    data = demo_data()
    data["time"]["t_end"] = "0.1"
    bad(data, r"time.t_end = '0.1' must be a number")


def test_bool_is_not_a_number():
    data = demo_data()
    data["material"]["mu"] = True
    bad(data, r"material.mu = True must be a number")


def test_order_z_three_is_refused_with_reason():
    data = demo_data()
    data["discretization"]["order_z"] = 3
    bad(data, r"order_z = 3 .*1 or 2")


def test_overrides_use_toml_values_and_dotted_keys():
    data = apply_overrides(demo_data(), ["time.t_end=0.05", "loads.0.value=\"3*t\"",
                                         "model.kind=mode3"])
    scene = Scene.from_dict(data)
    assert scene.time.t_end == 0.05
    assert scene.loads[0].value.text == "3*t"


def test_override_without_equals_sign():
    with pytest.raises(SceneError, match="write key=value"):
        apply_overrides(demo_data(), ["time.t_end"])


def test_resolved_scene_round_trips_through_toml(tmp_path):
    scene = scene_from(demo_data("mode3_stripes"))
    path = tmp_path / "scene.toml"
    path.write_text(to_toml(scene.to_dict()))
    again = load_scene(path)
    assert again == scene
    assert copy.deepcopy(again.to_dict()) == scene.to_dict()


# -- scenes built in code ----------------------------------------------------------------------

def code_scene(**changes):
    """The quick slit scene built in code from plain numbers, strings and lists."""
    parts = dict(
        name="code",
        model=Model(kind="mode3"),
        material=Material(mu=1, gamma=1),                                  # ints, a number
        phase_field=PhaseField(epsilon=0.08, alpha2=1e-3),
        geometry=Geometry(width=1, height=1, origin=[0, 0], mesh_size=0.04),  # a list
        cracks=[Crack(points=[[0, 0.5], [0.3, 0.5]])],                     # lists of lists
        loads=[Load(boundary="top", value="10*t"), Load(boundary="bottom", value="-10*t")],
        time=TimeSettings(dt=1e-3, t_end=3e-3),
        discretization=Discretization(order=1),
        output=Output(vtk_every=0),
    )
    parts.update(changes)
    return Scene(**parts)


CODE_TOML = """
name = "code"
[model]
kind = "mode3"
[material]
mu = 1.0
gamma = 1.0
[phase_field]
epsilon = 0.08
alpha2 = 1e-3
[geometry]
width = 1.0
height = 1.0
origin = [0.0, 0.0]
mesh_size = 0.04
[[cracks]]
points = [[0.0, 0.5], [0.3, 0.5]]
[[loads]]
boundary = "top"
value = "10*t"
[[loads]]
boundary = "bottom"
value = "-10*t"
[time]
dt = 1e-3
t_end = 3e-3
[discretization]
order = 1
[output]
vtk_every = 0
"""


def test_plain_values_are_coerced_into_the_field_types():
    material = Material(gamma=1, body_force="0.5*x")
    assert material.gamma == Expression("1.0") and material.body_force.text == "0.5*x"
    load = Load(boundary="top", value=["free", "10*t"])
    assert isinstance(load.value, Components) and load.value.free == (True, False)
    assert Load(boundary="top", value=2).value.value() == 2.0


@pytest.mark.parametrize("make, match", [
    (lambda: Material(gamma="1 +"), r"material.gamma: cannot parse expression"),
    (lambda: Material(mu="stiff"), r"material.mu = 'stiff' must be a number"),
    (lambda: Material(gamma=[1, 2]), r"material.gamma: expected a number or an expression string, got \[1, 2\]"),
    (lambda: Model(kind=3), r"model.kind = 3 must be a string"),
    (lambda: code_scene(loads=["top"]), r"loads\[0\] = 'top' must be a Load"),
    (lambda: code_scene(geometry=5), r"geometry = 5 must be a Geometry"),
])
def test_wrong_types_in_code_are_refused_in_one_line(make, match):
    with pytest.raises(SceneError, match=match) as info:
        make()
    assert "\n" not in str(info.value)


def test_sections_may_be_tables_in_code():
    scene = code_scene(time={"dt": 1e-3, "t_end": 3e-3}, cracks=[{"points": [[0, 0.5], [0.3, 0.5]]}])
    assert scene == code_scene()


def test_replace_revalidates():
    scene = code_scene()
    finer = dataclasses.replace(scene, phase_field=dataclasses.replace(scene.phase_field, epsilon=0.04))
    assert finer.phase_field.epsilon == 0.04 and scene.phase_field.epsilon == 0.08
    with pytest.raises(SceneError, match=r"phase_field.epsilon = -1.0 is not allowed"):
        dataclasses.replace(scene.phase_field, epsilon=-1.0)
    with pytest.raises(SceneError, match=r"cracks\[0\]: point 2 repeats point 1"):
        dataclasses.replace(scene, cracks=[{"points": [[0, 0.5], [0.3, 0.5], [0.3, 0.5]]}])


def test_scene_built_in_code_runs_like_the_same_scene_from_toml(tmp_path):
    """Equal scenes, and identical histories of three P1 steps on one thread (two threads
    may differ in the last bits, issue #10 item 11)."""
    path = tmp_path / "code.toml"
    path.write_text(CODE_TOML)
    from_toml, in_code = load_scene(path), code_scene()
    assert in_code == from_toml
    with single_thread():  # one thread, then the configured count again
        histories = [list(PhaseFieldStepper(scene).run()) for scene in (in_code, from_toml)]
    a, b = histories
    assert len(a) == len(b) == 3
    names = a[0].header()
    keep = [i for i, n in enumerate(names) if n not in ("wall_s", "step_s", "solve_s", "adapt_s")]
    rows_a = np.array([[r.row()[i] for i in keep] for r in a], dtype=float)
    rows_b = np.array([[r.row()[i] for i in keep] for r in b], dtype=float)
    np.testing.assert_array_equal(rows_a, rows_b)  # bitwise, NaN (no estimator) equal to NaN
    assert a[-1].E_el > 0 and a[-1].t == pytest.approx(3e-3)
