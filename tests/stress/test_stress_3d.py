"""The 3D stress case (issue 6, item 5): a unit cube pulled apart, P1, ramp and hold.

The monitor of :mod:`stress_cases` checks after every step: u and z finite, z in [0, 1] and
non-decreasing at the nodes, E_total non-increasing while the load is held. Its load sampler
walks the four sides of a rectangle, so this case gives it one on the six faces of the box.
"""
import math

import numpy as np
import pytest

from ngfrac.scene import Components, Scene

from scenes import demo_data

pytestmark = pytest.mark.stress


def box_scene_data():
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


def box_load_sampler(scene):
    """Every load expression at points of the six faces, at time t (the 3D version of
    ``stress_cases._load_sampler``)."""
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
    expressions = []
    for value in [load.value for load in scene.loads] + [scene.material.body_force]:
        entries = value if isinstance(value, Components) else (value,)
        expressions += [e for e in entries if not isinstance(e, str)]

    def sample(t):
        return np.concatenate([np.broadcast_to(e.evaluate_numpy({"x": xs, "y": ys, "z": zs, "t": t}),
                                               xs.shape) for e in expressions])

    return sample


def test_3d_case_is_stable(monkeypatch):
    import stress_cases as sc

    monkeypatch.setattr(sc, "_load_sampler", box_load_sampler)
    case = sc.StressCase("box_3d", "unit cube, P1, ramp and hold",
                         lambda: Scene.from_dict(box_scene_data()), min_held=20)
    result = sc.run_case(case)
    found = sc.problems(result)
    assert not found, sc.summary(result) + "\n" + "\n".join(found)
    # the load did something: the cube damaged and carries less than its sound stiffness
    last = result.records[-1]
    assert last.dz_max >= 0 and last.crack_length > 0.01, sc.summary(result)
    sound = 50.0 * 0.1 * 1.0  # E * strain * area, the uniaxial estimate of the force
    assert 0 < last.forces["Fy_top"] < 2 * sound and math.isfinite(last.E_total)
