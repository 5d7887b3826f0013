"""Scene validation: every bad input gives one clear line naming key, value and fix."""
import copy

import pytest

from ngfrac.output import to_toml
from ngfrac.scene import Scene, SceneError, apply_overrides, load_scene

from scenes import DEMOS, demo_data, scene_from


def bad(data, match):
    with pytest.raises(SceneError, match=match) as info:
        Scene.from_dict(data)
    message = str(info.value)
    assert "\n" not in message
    return message


def test_demo_scenes_are_valid():
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
