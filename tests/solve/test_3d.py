"""3D: box geometry, elasticity_3d, planar polygon cracks, Lagrange nodes on tets, the stepper."""
import copy
import math

import numpy as np
import ngsolve as ngs
import pytest

from ngfrac.physics.cracks import distance_to_polygons, initial_tip
from ngfrac.geometry.domains import build_mesh
from ngfrac.physics.elastic import Elasticity3D
from ngfrac.scene.build import elastic_model_of
from ngfrac.fem.nodal import LagrangeNodes
from ngfrac.post.reactions import reaction_forces
from ngfrac.scene import Scene, SceneError
from ngfrac.solve.stepper import PhaseFieldStepper, StepRecord

from ngfrac.testing.scenes import quick_slit

CRACK = [[0.0, 0.5, 0.0], [0.3, 0.5, 0.0], [0.3, 0.5, 0.5], [0.0, 0.5, 0.5]]
"""An edge crack through the depth of the 1 x 1 x 0.5 box, on y = 0.5, from the left face."""


def box_data(**changes):
    data = {
        "model": {"kind": "elasticity_3d"},
        "material": {"E": 50.0, "nu": 0.29, "gamma": 1.0},
        "phase_field": {"epsilon": 0.1, "alpha2": 1e-3},
        "geometry": {"kind": "box", "width": 1.0, "height": 1.0, "depth": 0.5, "mesh_size": 0.1},
        "cracks": [{"points": copy.deepcopy(CRACK)}],
        "loads": [{"boundary": "top", "value": ["0", "t", "0"]},
                  {"boundary": "bottom", "value": ["free", "0", "free"]}],
        "time": {"dt": 0.01, "t_end": 0.03},
        "discretization": {"order": 1},
    }
    for key, value in changes.items():
        section, name = key.split("__")
        if section == "loads":  # loads__0: a stronger pull on the top
            data["loads"][int(name)]["value"] = ["0", "40*t", "0"]
            continue
        data[section][name] = value
    return data


@pytest.fixture(scope="module")
def box_mesh():
    """The box with the crack face, h = 0.1 (about 650 vertices), shared by the runs below
    (meshing a box costs seconds)."""
    scene = Scene.from_dict(box_data())
    return build_mesh(scene.geometry, 0.1, [c.points for c in scene.cracks])


# -- scene ------------------------------------------------------------------------------------
def test_box_scene_is_valid_and_resolves_origin():
    scene = Scene.from_dict(box_data())
    assert scene.geometry.dim == 3 and scene.geometry.origin == (0.0, 0.0, 0.0)
    assert scene.geometry.boundary_names == ("left", "right", "bottom", "top", "back", "front")
    assert scene.model.n_components == 3
    assert scene.cracks[0].dim == 3


@pytest.mark.parametrize("change, words", [
    ({"geometry__depth": 0.0}, ["geometry.depth", "depth > 0"]),
    ({"geometry__origin": [1.0, 2.0]}, ["geometry.origin", "[x, y, z]"]),
    ({"geometry__kind": "cube"}, ["geometry.kind", "'box'"]),
    ({"model__kind": "plane_strain"}, ["geometry.kind", "3D", "elasticity_3d"]),
    ({"model__kind": "mode3"}, ["geometry.kind", "3D", "elasticity_3d"]),
])
def test_box_scene_errors_name_key_and_fix(change, words):
    with pytest.raises(SceneError) as err:
        Scene.from_dict(box_data(**change))
    message = str(err.value)
    assert "\n" not in message
    for word in words:
        assert word in message, message


def test_3d_model_on_a_rectangle_is_refused():
    data = box_data()
    data["geometry"] = {"kind": "rectangle", "width": 1.0, "height": 1.0}
    data["cracks"] = []
    data["loads"] = [{"boundary": "top", "value": ["0", "t", "0"]}]
    with pytest.raises(SceneError, match="model.kind = 'elasticity_3d' is 3D.*geometry.kind = 'box'"):
        Scene.from_dict(data)


def test_rectangle_with_depth_is_refused():
    with pytest.raises(SceneError, match="geometry.depth = 0.5.*only a box"):
        quick_slit("geometry.depth=0.5")


def test_3d_loads_need_three_components():
    data = box_data()
    data["loads"][0]["value"] = ["0", "t"]
    with pytest.raises(SceneError, match=r"loads\[0\].value .* needs 3: \[ux, uy, uz\]"):
        Scene.from_dict(data)
    data["loads"][0]["value"] = "t"
    with pytest.raises(SceneError, match=r"needs \[ux, uy, uz\]"):
        Scene.from_dict(data)


@pytest.mark.parametrize("points, words", [
    ([[0.0, 0.5], [0.3, 0.5]], ["cracks[0].points", "2D points", "[[x, y, z], ...]"]),
    ([[0.0, 0.5, 0.0], [0.3, 0.5, 0.0]], ["cracks[0].points", "at least three corners"]),
    ([[0.0, 0.5, 0.0], [0.3, 0.5, 0.0], [0.3, 0.6, 0.5], [0.0, 0.5, 0.5]], ["planar"]),
    ([[0.0, 0.5, 0.0], [0.3, 0.5, 0.0], [0.6, 0.5, 0.0]], ["no area"]),
    ([[0.0, 0.5, 0.0], [0.3, 0.5, 0.0], [0.3, 0.5, 0.9], [0.0, 0.5, 0.9]], ["outside the domain"]),
])
def test_3d_crack_errors(points, words):
    data = box_data()
    data["cracks"] = [{"points": points}]
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    for word in words:
        assert word in str(err.value), str(err.value)


def test_3d_expressions_may_use_z_and_gamma_is_checked_in_the_box():
    data = box_data()
    data["loads"][0]["value"] = ["0", "t*(1 + z)", "0"]
    Scene.from_dict(data)  # z is a coordinate in 3D
    data["material"]["gamma"] = "1 - 3*z"  # negative for z > 1/3, inside the box (depth 0.5)
    with pytest.raises(SceneError, match=r"material.gamma = '1 - 3\*z' is .* <= 0 at \(x, y, z\)"):
        Scene.from_dict(data)
    with pytest.raises(SceneError, match="uses z, but the domain is 2D"):
        quick_slit('loads.0.value="t*z"')


# -- geometry and cracks ------------------------------------------------------------------------
def test_box_mesh_has_named_faces_and_a_crack_face():
    data = box_data(geometry__origin=[1.0, 2.0, 3.0])
    data["cracks"][0]["points"] = [[x + 1.0, y + 2.0, z + 3.0] for x, y, z in CRACK]
    scene = Scene.from_dict(data)
    mesh = build_mesh(scene.geometry, 0.15, [c.points for c in scene.cracks])
    assert mesh.dim == 3
    areas = {name: ngs.Integrate(1.0, mesh, ngs.BND, definedon=mesh.Boundaries(name))
             for name in ("left", "right", "bottom", "top", "back", "front", "crack")}
    assert areas["left"] == pytest.approx(0.5) and areas["right"] == pytest.approx(0.5)
    assert areas["bottom"] == pytest.approx(0.5) and areas["top"] == pytest.approx(0.5)
    assert areas["back"] == pytest.approx(1.0) and areas["front"] == pytest.approx(1.0)
    assert areas["crack"] == pytest.approx(0.15)
    # which face is which: the centroid of each face
    centroid = {name: [ngs.Integrate(c, mesh, ngs.BND, definedon=mesh.Boundaries(name)) / areas[name]
                       for c in (ngs.x, ngs.y, ngs.z)] for name in ("left", "top", "front")}
    assert centroid["left"] == pytest.approx([1.0, 2.5, 3.25])
    assert centroid["top"] == pytest.approx([1.5, 3.0, 3.25])
    assert centroid["front"] == pytest.approx([1.5, 2.5, 3.5])
    assert ngs.Integrate(1.0, mesh) == pytest.approx(0.5)


def test_distance_to_a_filled_polygon_against_dense_sampling():
    triangle = [[0.1, 0.2, 0.3], [0.7, 0.1, 0.4], [0.3, 0.8, 0.6]]
    rng = np.random.default_rng(1)
    points = rng.uniform(-0.2, 1.0, size=(300, 3))
    a, b, c = np.asarray(triangle)
    s, t = np.meshgrid(np.linspace(0, 1, 201), np.linspace(0, 1, 201))
    keep = s + t <= 1
    samples = a + s[keep][:, None] * (b - a) + t[keep][:, None] * (c - a)
    brute = np.array([np.min(np.linalg.norm(samples - p, axis=1)) for p in points])
    exact = distance_to_polygons(points, [triangle])
    assert np.all(exact <= brute + 1e-12)
    assert np.max(brute - exact) < 4e-3  # the sampling's spacing
    # a point straight above the inside: the offset from the plane
    centre = (a + b + c) / 3
    normal = np.cross(b - a, c - a) / np.linalg.norm(np.cross(b - a, c - a))
    assert distance_to_polygons(centre[None] + 0.2 * normal, [triangle])[0] == pytest.approx(0.2)


def test_initial_tip_is_the_middle_of_the_crack_front():
    on_boundary = lambda p: abs(p[0]) < 1e-12 or abs(p[2]) < 1e-12 or abs(p[2] - 0.5) < 1e-12
    assert initial_tip(CRACK, on_boundary) == pytest.approx([0.3, 0.5, 0.25])
    assert initial_tip([[0, 0.5], [0.3, 0.5]]) == pytest.approx([0.3, 0.5])


# -- Lagrange nodes on tetrahedra ----------------------------------------------------------------
@pytest.mark.parametrize("order", [1, 2])
def test_lagrange_nodes_on_tets(order, box_mesh):
    mesh = box_mesh
    nodes = LagrangeNodes(ngs.H1(mesh, order=order))
    gf = ngs.GridFunction(nodes.fes)
    rng = np.random.default_rng(0)
    values = rng.uniform(0, 1, nodes.n_nodes)
    nodes.assign(gf, values)
    at_nodes = np.asarray(gf(mesh(*nodes.points.T))).ravel()
    assert np.max(np.abs(at_nodes - values)) < 1e-13
    assert np.all(nodes.values(gf) >= values)  # the round trip never lowers a node value
    if order == 2:
        assert nodes.beta == pytest.approx(-0.125)
        # P2 reproduces a quadratic from its node values
        x, y, z = nodes.points.T
        q = lambda x, y, z: x * y - 0.5 * z ** 2 + 0.3 * x
        nodes.assign(gf, q(x, y, z))
        error = ngs.Integrate((gf - q(ngs.x, ngs.y, ngs.z)) ** 2, mesh, order=6)
        assert math.sqrt(error) < 1e-12


# -- model and stepper ---------------------------------------------------------------------------
def test_elasticity_3d_model_and_uniaxial_reaction():
    """Uniaxial stress in a sound box (rollers on left, bottom, back; top pulled): P1 is exact,
    so Fy_top = (1 + eta) E delta A / H to round-off."""
    data = box_data()
    data["cracks"] = []
    data["loads"] = [{"boundary": "top", "value": ["free", "t", "free"]},
                     {"boundary": "bottom", "value": ["free", "0", "free"]},
                     {"boundary": "left", "value": ["0", "free", "free"]},
                     {"boundary": "back", "value": ["free", "free", "0"]}]
    scene = Scene.from_dict(data)
    model = elastic_model_of(scene)
    assert isinstance(model, Elasticity3D) and model.component_names == ("x", "y", "z")
    stepper = PhaseFieldStepper(scene)
    stepper.step()
    forces = reaction_forces(stepper.u_problem, stepper.scene.loads)
    eta, E = scene.phase_field.residual_stiffness, scene.material.E
    expected = (1 + eta) * E * 0.01 * (1.0 * 0.5) / 1.0
    assert forces["top"][1] == pytest.approx(expected, rel=1e-9)
    assert forces["bottom"][1] == pytest.approx(-expected, rel=1e-9)
    assert forces["left"][0] == pytest.approx(0.0, abs=1e-9)
    record = stepper.record()
    assert {"Fx_top", "Fy_top", "Fz_top", "uy_top"} <= set(record.header())
    assert record.forces["uy_top"] == pytest.approx(0.01)


def test_history_has_tip_z_only_in_3d():
    assert "tip_z" not in StepRecord.columns()
    header_2d = StepRecord(step=0, t=0.0, wall_s=0.0, nv=1, ndof=1).header()
    assert "tip_z" not in header_2d
    header_3d = StepRecord(step=0, t=0.0, wall_s=0.0, nv=1, ndof=1, dim=3).header()
    assert header_3d[header_3d.index("tip_y") + 1] == "tip_z"
    record = StepRecord(step=0, t=0.0, wall_s=0.0, nv=1, ndof=1, dim=3, tip_z=0.25)
    assert record.row()[record.header().index("tip_z")] == 0.25


def test_initial_crack_area_on_the_aligned_mesh(box_mesh):
    """P2 z0 = exp(-d/eps) on a mesh with faces on the crack: the Gamma-limit measure is the
    area plus pi eps/4 per unit length of the crack front (the faces on the boundary add
    nothing): 0.3 * 0.5 + 0.5 * pi * 0.1 / 4 = 0.18927."""
    stepper = PhaseFieldStepper(Scene.from_dict(box_data(discretization__order=2)), mesh=box_mesh)
    expected = 0.3 * 0.5 + 0.5 * math.pi * 0.1 / 4
    record = stepper.record()
    assert record.crack_length == pytest.approx(expected, rel=2e-3), record.crack_length
    assert (record.tip_x, record.tip_y, record.tip_z) == pytest.approx((0.3, 0.5, 0.25))


@pytest.mark.parametrize("order", [1, 2])
def test_3d_run_keeps_z_bounds_and_non_repair(order, box_mesh):
    # a load of 0.4 per step: the band around the crack front damages within the run
    scene = Scene.from_dict(box_data(discretization__order=order, time__t_end=0.03,
                                     time__dt=0.01, loads__0=None))
    stepper = PhaseFieldStepper(scene, mesh=box_mesh)
    previous = stepper.z_node_values()
    records = []
    for record in stepper.run():
        values = stepper.z_node_values()
        assert values.min() >= 0.0 and values.max() <= 1.0
        assert np.all(values >= previous), f"z decreased by {np.max(previous - values)}"
        previous = values
        records.append(record)
    assert len(records) == 3
    assert records[-1].dz_max > 0  # z did grow: the non-repair check above was not empty
    last = records[-1]
    assert np.isfinite(last.E_total) and last.E_el > 0
    assert last.forces["Fy_top"] > 0 and last.forces["Fy_top"] == pytest.approx(-last.forces["Fy_bottom"])
    assert np.isfinite(last.tip_z)
