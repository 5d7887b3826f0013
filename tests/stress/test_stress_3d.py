"""The 3D stress case waits for 3D support: ngfrac's geometry is a rectangle only."""
import pytest

from ngfrac.scene import Scene, SceneError

from scenes import demo_data

pytestmark = pytest.mark.stress

REASON = ("the library is 2D only: geometry.kind allows only 'rectangle' and the models are "
          "mode3, plane_strain and plane_stress")


def box_scene_data():
    """A unit cube slit from one face, pulled apart in z: the 3D twin of the Fig. 2 scene."""
    data = demo_data()
    data["model"] = {"kind": "elasticity_3d"}
    data["material"] = {"E": 50.0, "nu": 0.29, "gamma": 1.0}
    data["geometry"] = {"kind": "box", "width": 1.0, "height": 1.0, "depth": 1.0, "mesh_size": 0.1}
    data["cracks"] = []
    data["loads"] = [{"boundary": "top", "value": ["0", "0", "10*min(t, 0.1)"]},
                     {"boundary": "bottom", "value": ["0", "0", "0"]}]
    data["phase_field"]["epsilon"] = 0.2
    data["time"] = {"dt": 2e-3, "t_end": 0.2}
    data["adaptivity"] = {"enabled": False}
    data["discretization"] = {"order": 1}
    return data


@pytest.mark.skip(reason=REASON)
def test_3d_case_is_stable():
    import stress_cases as sc

    case = sc.StressCase("box_3d", "unit cube, P1, ramp and hold",
                         lambda: Scene.from_dict(box_scene_data()), min_held=40)
    result = sc.run_case(case)
    found = sc.problems(result)
    assert not found, sc.summary(result) + "\n" + "\n".join(found)


def test_3d_is_still_refused():
    """When this fails, 3D has arrived: remove the skip above."""
    with pytest.raises(SceneError):
        Scene.from_dict(box_scene_data())
