"""CAD domains (geometry.kind = "occ"): shapes, files, boundary selectors, cracks, a run."""
import math
import subprocess
import sys

import ngsolve as ngs
import numpy as np
import pytest

from ngfrac.geometry.cad import OccDomain
from ngfrac.geometry.domains import CRACK_BOUNDARY, Domain, domain_of
from ngfrac.scene import Geometry, Scene, SceneError

R = 0.2
PLATE = [{"type": "rectangle", "corner": [0, 0], "size": [2, 1]},
         {"type": "circle", "center": [1, 0.5], "radius": R, "op": "cut"}]
PLATE_NAMES = [{"name": "bottom", "normal": [0, -1]}, {"name": "top", "normal": [0, 1]},
               {"name": "hole", "point": [1 + R, 0.5]}]
L_SHAPE = [{"type": "rectangle", "corner": [0, 0], "size": [2, 1]},
           {"type": "rectangle", "corner": [0, 0], "size": [1, 2]}]


def plate(**keys):
    return Geometry(kind="occ", shapes=PLATE, boundaries=PLATE_NAMES, **keys)


def test_l_panel_meshes_with_its_boundaries_and_area():
    geometry = Geometry(kind="occ", shapes=L_SHAPE,
                        boundaries=[{"name": "bottom", "box": [[0, 0], [2, 0]]},
                                    {"name": "left", "normal": [-1, 0]}])
    domain = geometry.domain()
    assert isinstance(domain, Domain) and domain.dim == 2 and geometry.dim == 2
    assert set(domain.boundary_names) == {"bottom", "left", "free"}
    assert domain.measure == pytest.approx(3.0, rel=1e-12)
    assert domain.diameter == pytest.approx(math.sqrt(8)) and domain.shortest_side == pytest.approx(2)
    mesh = domain.build_mesh(0.25)
    assert set(mesh.GetBoundaries()) == {"bottom", "left", "free"}
    assert ngs.Integrate(1, mesh) == pytest.approx(3.0, rel=1e-12)
    assert domain.contains([[0.5, 1.5], [1.5, 1.5], [1.5, 0.5]]).tolist() == [True, False, True]
    assert domain.on_boundary([1.0, 1.5]) and not domain.on_boundary([0.5, 0.5])
    xs, ys = domain.boundary_points("bottom")
    assert np.allclose(ys, 0) and xs.min() == pytest.approx(0) and xs.max() == pytest.approx(2)
    xs, ys = domain.sample_points()
    assert not np.any((xs > 1 + 1e-9) & (ys > 1 + 1e-9))


def test_plate_with_hole_area_and_curved_mesh():
    domain = plate().domain()
    exact = 2 - math.pi * R ** 2
    assert domain.measure == pytest.approx(exact, rel=1e-12)
    assert set(domain.boundary_names) == {"bottom", "top", "hole", "free"}
    assert domain.curved
    mesh = domain.build_mesh(0.1)
    assert set(mesh.GetBoundaries()) == {"bottom", "top", "hole", "free"}
    straight = ngs.Integrate(1, mesh)
    mesh.Curve(3)
    curved = ngs.Integrate(1, mesh)
    assert abs(curved - exact) < 1e-4 < abs(straight - exact), (straight, curved, exact)
    hole = ngs.Integrate(1, mesh, definedon=mesh.Boundaries("hole"))
    assert hole == pytest.approx(2 * math.pi * R, rel=1e-4)
    assert not domain.contains([1.0, 0.5]) and domain.contains([1.0, 0.5 + R])


@pytest.mark.parametrize("selector, edges", [
    ({"box": [[-0.1, -0.1], [2.1, 0.1]]}, 1),      # the bottom edge only
    ({"point": [2.0, 0.3]}, 1),                      # the right edge
    ({"normal": [1, 0]}, 1),                         # the right edge (outward normal +x)
    ({"normal": [0, 1]}, 1),                         # the top edge
])
def test_selectors_pick_edges(selector, edges):
    domain = Geometry(kind="occ", shapes=PLATE, boundaries=[{"name": "picked", **selector}]).domain()
    mesh = domain.build_mesh(0.2)
    picked = [e for e in domain.shape.edges if e.name == "picked"]
    assert len(picked) == edges and "picked" in mesh.GetBoundaries()


@pytest.mark.parametrize("boundaries, fragment", [
    ([{"name": "x", "point": [5, 5]}], "matches no edge"),
    ([{"name": "x", "normal": [1, 1]}], "matches no edge"),
    ([{"name": "a", "normal": [0, -1]}, {"name": "b", "box": [[0, -1], [2, 0]]}], "claim the same edge"),
    ([{"name": "a", "point": [0, 0], "normal": [0, 1]}], "exactly one of"),
])
def test_bad_selectors_are_one_line_scene_errors(boundaries, fragment):
    with pytest.raises(SceneError, match=fragment) as info:
        Geometry(kind="occ", shapes=PLATE, boundaries=boundaries)
    assert len(str(info.value).splitlines()) == 1


def test_step_file_round_trip(tmp_path):
    domain = plate().domain()
    path = tmp_path / "plate.step"
    domain.shape.WriteStep(str(path))
    again = Geometry(kind="occ", file=str(path)).domain()
    assert again.measure == pytest.approx(domain.measure, rel=1e-9)
    assert set(again.boundary_names) == set(domain.boundary_names)
    renamed = Geometry(kind="occ", file=str(path), scale=2.0,
                       boundaries=[{"name": "ring", "named": "hole"}]).domain()
    assert set(renamed.boundary_names) == {"bottom", "top", "ring", "free"}
    assert renamed.measure == pytest.approx(4 * domain.measure, rel=1e-9)
    with pytest.raises(SceneError, match="geometry.file"):
        Geometry(kind="occ", file=str(tmp_path / "missing.step"))


def test_crack_polyline_becomes_interior_edges():
    domain = plate().domain()
    crack = [[0.0, 0.5], [0.4, 0.5], [0.6, 0.6]]
    mesh = domain.build_mesh(0.1, [crack])
    assert set(mesh.GetBoundaries()) == {*domain.boundary_names, CRACK_BOUNDARY}
    length = ngs.Integrate(1, mesh, definedon=mesh.Boundaries(CRACK_BOUNDARY))
    assert length == pytest.approx(0.4 + math.hypot(0.2, 0.1), rel=1e-12)
    points = np.array([mesh.vertices[v.nr].point for el in mesh.Elements(ngs.BND)
                       if mesh.GetBoundaries()[el.index] == CRACK_BOUNDARY for v in el.vertices])
    first = np.abs(points[:, 1] - 0.5) < 1e-12
    second = np.abs(points[:, 1] - 0.5 - 0.5 * (points[:, 0] - 0.4)) < 1e-12
    assert np.all(first | second)
    assert ngs.Integrate(1, mesh) == pytest.approx(ngs.Integrate(1, domain.build_mesh(0.1)), rel=1e-3)


def test_box_with_cylinder_hole_and_crack_face():
    geometry = Geometry(kind="occ", shapes=[
        {"type": "box", "corner": [0, 0, 0], "size": [1, 1, 0.5]},
        {"type": "cylinder", "center": [0.6, 0.5, 0], "axis": [0, 0, 1], "radius": 0.15,
         "height": 0.5, "op": "cut"}], boundaries=[{"name": "top", "normal": [0, 1, 0]},
                                                  {"name": "bottom", "box": [[0, 0, 0], [1, 0, 0.5]]}])
    domain = geometry.domain()
    assert domain.dim == 3 and set(domain.boundary_names) == {"top", "bottom", "free"}
    assert domain.measure == pytest.approx(0.5 - math.pi * 0.15 ** 2 * 0.5, rel=1e-9)
    crack = [[0, 0.5, 0], [0.3, 0.5, 0], [0.3, 0.5, 0.5], [0, 0.5, 0.5]]
    mesh = domain.build_mesh(0.2, [crack])
    assert set(mesh.GetBoundaries()) == {"top", "bottom", "free", CRACK_BOUNDARY}
    area = ngs.Integrate(1, mesh, definedon=mesh.Boundaries(CRACK_BOUNDARY))
    assert area == pytest.approx(0.15, rel=1e-9)
    assert domain.contains([[0.1, 0.1, 0.1], [0.6, 0.5, 0.25], [2, 0, 0]]).tolist() == [True, False, False]


def test_occ_domain_from_a_shape_in_code():
    from netgen import occ

    face = occ.WorkPlane().Rectangle(1, 1).Face() - occ.WorkPlane().MoveTo(0.5, 0).Rectangle(0.02, 0.3).Face()
    face.edges.Max(occ.Y).name = "top"
    domain = OccDomain(face)
    assert set(domain.boundary_names) == {"top", "free"}
    assert domain.measure == pytest.approx(1 - 0.006, rel=1e-12)
    assert domain_of(domain) is domain
    geometry = Geometry.of_domain(domain)
    assert geometry.domain() is domain and geometry.boundary_names == domain.boundary_names


def plate_scene(**adaptivity):
    return Scene.from_dict({
        "geometry": {"kind": "occ", "shapes": PLATE, "boundaries": PLATE_NAMES},
        "phase_field": {"epsilon": 0.05, "alpha2": 1e-3},
        "material": {"mu": 1.0, "gamma": 1.0},
        "cracks": [{"points": [[0.0, 0.5], [0.4, 0.5]]}],
        "loads": [{"boundary": "top", "value": "10*t"}, {"boundary": "bottom", "value": "-10*t"}],
        "time": {"dt": 5e-3, "t_end": 0.015},
        "discretization": {"order": 2},
        "adaptivity": {"enabled": True, "max_vertices": 1500, "hmin": 0.01, **adaptivity},
        "output": {"vtk_every": 0}})


def test_short_adaptive_run_on_the_plate_with_a_hole(one_thread):
    from ngfrac.solve.stepper import PhaseFieldStepper

    scene = plate_scene()
    stepper = PhaseFieldStepper(scene)
    records = list(stepper.run())
    assert len(records) == 3
    mesh = stepper.z.space.mesh
    assert mesh.nv <= 1500 and set(mesh.GetBoundaries()) >= {"top", "bottom", "hole", CRACK_BOUNDARY}
    z = stepper.nodes.values(stepper.z)  # at the Lagrange nodes (P2 coefficients are hierarchical)
    assert z.min() >= 0 and z.max() <= 1 + 1e-12
    assert ngs.Integrate(1, mesh) == pytest.approx(scene.geometry.domain().measure, rel=1e-4)  # curved
    change = stepper.adapt(reason="test")  # one more mesh change: the transfer on curved meshes
    assert change.nv_after <= 1500
    z = stepper.nodes.values(stepper.z)
    assert z.min() >= 0 and z.max() <= 1 + 1e-12
    assert change.crack_length_after == pytest.approx(change.crack_length_before, rel=0.01)


def test_cli_check_bad_selector_exits_2_with_one_line(tmp_path):
    path = tmp_path / "plate.toml"
    path.write_text("""
[geometry]
kind = "occ"
[[geometry.shapes]]
type = "rectangle"
corner = [0, 0]
size = [2, 1]
[[geometry.boundaries]]
name = "top"
point = [5, 5]
[phase_field]
epsilon = 0.05
alpha2 = 1e-3
[[loads]]
boundary = "top"
value = "t"
[time]
dt = 0.01
t_end = 0.1
""")
    result = subprocess.run([sys.executable, "-m", "ngfrac", "check", str(path)],
                            capture_output=True, text=True)
    assert result.returncode == 2, result.stderr
    assert "matches no edge" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_scene_checks_work_through_the_occ_domain():
    data = plate_scene().to_dict()
    assert Scene.from_dict(data).geometry.boundary_names == plate().boundary_names  # round trip
    along = {**data, "cracks": [{"points": [[0.2, 0.0], [0.8, 0.0]]}]}
    with pytest.raises(SceneError, match="lies on the boundary 'bottom'"):
        Scene.from_dict(along)
    into_hole = {**data, "cracks": [{"points": [[0.0, 0.5], [1.0, 0.5]]}]}
    with pytest.raises(SceneError, match="lies outside the domain"):
        Scene.from_dict(into_hole)
    across = {**data, "cracks": [{"points": [[0.5, 0.5], [1.5, 0.5]]}]}
    with pytest.raises(SceneError, match="leaves the domain near"):
        Scene.from_dict(across)
    unknown = {**data, "loads": [{"boundary": "left", "value": "t"}]}
    with pytest.raises(SceneError, match="boundaries are bottom, .*hole"):
        Scene.from_dict(unknown)
    nucleation = Scene.from_dict({**data, "cracks": []})
    assert nucleation.geometry.domain().build_mesh(0.2).GetBoundaries()


@pytest.mark.parametrize("shapes, measure", [
    ([{"type": "ellipse", "center": [0, 0], "radii": [0.5, 0.2]}], math.pi * 0.1),
    ([{"type": "ellipse", "center": [1, 1], "radii": [0.2, 0.5]}], math.pi * 0.1),
    ([{"type": "polygon", "points": [[0, 0], [1, 0], [0, 1]]}], 0.5),
    ([{"type": "rectangle", "corner": [0, 0], "size": [1, 1]},
      {"type": "circle", "center": [0, 0], "radius": 1, "op": "intersect"}], math.pi / 4),
    ([{"type": "rectangle", "corner": [0, 0], "size": [1, 1]},   # a V-notch from the left edge
      {"type": "polygon", "points": [[0, 0.4], [0.3, 0.5], [0, 0.6]], "op": "cut"}], 1 - 0.03),
    ([{"type": "rectangle", "corner": [0, 0], "size": [1, 1]},   # one crossing the edge, clockwise
      {"type": "polygon", "points": [[-0.1, 0.6], [0.3, 0.5], [-0.1, 0.4]], "op": "cut"}], 1 - 0.0225),
    ([{"type": "sphere", "center": [0, 0, 0], "radius": 0.5}], math.pi / 6),
])
def test_shape_types_and_ops_have_their_measure(shapes, measure):
    domain = Geometry(kind="occ", shapes=shapes).domain()
    assert domain.measure == pytest.approx(measure, rel=1e-9)
    mesh = domain.build_mesh(0.25)
    assert mesh.dim == domain.dim and set(mesh.GetBoundaries()) == {"free"}


def test_bad_shapes_are_scene_errors():
    with pytest.raises(SceneError, match=r"geometry.shapes\[0\].radius .* a rectangle takes corner, size"):
        Geometry(kind="occ", shapes=[{"type": "rectangle", "corner": [0, 0], "size": [1, 1], "radius": 1}])
    with pytest.raises(SceneError, match="mix no plane shapes"):
        Geometry(kind="occ", shapes=[{"type": "rectangle", "corner": [0, 0], "size": [1, 1]},
                                     {"type": "sphere", "center": [0, 0, 0], "radius": 1, "op": "cut"}])
    with pytest.raises(SceneError, match="not both"):
        Geometry(kind="occ")
    with pytest.raises(SceneError, match="only geometry.kind = 'occ' takes it"):
        Geometry(width=1, height=1, shapes=PLATE)


def test_brep_file_keeps_the_shape_not_the_names(tmp_path):
    domain = plate().domain()
    path = tmp_path / "plate.brep"
    domain.shape.WriteBrep(str(path))
    again = Geometry(kind="occ", file=str(path), boundaries=PLATE_NAMES).domain()
    assert again.measure == pytest.approx(domain.measure, rel=1e-9)
    assert set(again.boundary_names) == set(domain.boundary_names)  # named again by selectors


def test_nucleation_run_without_cracks(one_thread):
    from ngfrac.solve.stepper import PhaseFieldStepper

    scene = Scene.from_dict({**plate_scene().to_dict(), "cracks": []})
    stepper = PhaseFieldStepper(scene)
    for _ in stepper.run():
        pass
    z = stepper.nodes.values(stepper.z)
    assert 0 <= z.min() and z.max() <= 1
    assert CRACK_BOUNDARY not in stepper.z.space.mesh.GetBoundaries()


def test_copies_of_an_occ_geometry_build_their_own_domain():
    import copy
    import pickle

    geometry = plate()
    for again in (copy.deepcopy(geometry), pickle.loads(pickle.dumps(geometry))):
        assert again.to_dict() == geometry.to_dict() and again.domain() is not geometry.domain()
        assert again.boundary_names == geometry.boundary_names


@pytest.mark.slow
def test_3d_adaptive_run_on_a_box_with_a_cylindrical_hole(one_thread):
    from ngfrac.solve.stepper import PhaseFieldStepper

    scene = Scene.from_dict({
        "model": {"kind": "elasticity_3d"}, "material": {"E": 1.0, "nu": 0.3},
        "geometry": {"kind": "occ", "shapes": [
            {"type": "box", "corner": [0, 0, 0], "size": [1, 1, 0.2]},
            {"type": "cylinder", "center": [0.6, 0.5, 0], "axis": [0, 0, 1], "radius": 0.1,
             "height": 0.2, "op": "cut"}],
            "boundaries": [{"name": "top", "normal": [0, 1, 0]}, {"name": "bottom", "normal": [0, -1, 0]}]},
        "phase_field": {"epsilon": 0.08, "alpha2": 1e-3},
        "cracks": [{"points": [[0, 0.5, 0], [0.3, 0.5, 0], [0.3, 0.5, 0.2], [0, 0.5, 0.2]]}],
        "loads": [{"boundary": "top", "value": ["0", "t", "0"]},
                  {"boundary": "bottom", "value": ["0", "0", "0"]}],
        "time": {"dt": 0.01, "t_end": 0.02}, "discretization": {"order": 2},
        "adaptivity": {"enabled": True, "max_vertices": 1500, "hmin": 0.02},
        "output": {"vtk_every": 0}})
    stepper = PhaseFieldStepper(scene)
    for _ in stepper.run():
        pass
    change = stepper.adapt(reason="test")
    mesh = stepper.z.space.mesh
    z = stepper.nodes.values(stepper.z)
    assert change.nv_after <= 1500 and 0 <= z.min() and z.max() <= 1 + 1e-12
    assert CRACK_BOUNDARY in mesh.GetBoundaries()
    assert ngs.Integrate(1, mesh) == pytest.approx(scene.geometry.domain().measure, rel=1e-4)


BOX_WITH_HOLE = [{"type": "box", "corner": [0, 0, 0], "size": [1, 1, 0.5]},
                 {"type": "cylinder", "center": [0.6, 0.5, 0], "axis": [0, 0, 1], "radius": 0.15,
                  "height": 0.5, "op": "cut"}]
BOX_NAMES = [{"name": "top", "normal": [0, 1, 0]}, {"name": "bottom", "box": [[0, 0, 0], [1, 0, 0.5]]},
             {"name": "hole", "point": [0.75, 0.5, 0.25]}]


def measure_by_name(domain):
    """Length (2D) or area (3D) of the boundary parts of each name, from OCC (exact)."""
    parts = domain.shape.edges if domain.dim == 2 else domain.shape.faces
    total = {}
    for part in parts:
        total[part.name] = total.get(part.name, 0.0) + part.mass
    return total


@pytest.mark.parametrize("shapes, selectors", [(PLATE, PLATE_NAMES), (BOX_WITH_HOLE, BOX_NAMES)],
                         ids=["2d plate", "3d box with hole"])
@pytest.mark.parametrize("suffix, writer", [(".step", "WriteStep"), (".brep", "WriteBrep")])
def test_cad_file_round_trip_by_selectors(shapes, selectors, suffix, writer, tmp_path):
    """A shape written to STEP (BREP) and read back as geometry.file, its boundaries named by
    the same selectors, has the same measure and the same boundaries, each of the same size
    (OCC's lengths and areas; 1e-9: the file's printed digits, measured 1e-15)."""
    domain = Geometry(kind="occ", shapes=shapes, boundaries=selectors).domain()
    path = tmp_path / f"part{suffix}"
    getattr(domain.shape, writer)(str(path))
    again = Geometry(kind="occ", file=str(path), boundaries=selectors).domain()
    assert again.dim == domain.dim
    assert again.measure == pytest.approx(domain.measure, rel=1e-9)
    assert set(again.boundary_names) == set(domain.boundary_names) == {
        *(s["name"] for s in selectors), "free"}
    expected, found = measure_by_name(domain), measure_by_name(again)
    assert found == pytest.approx(expected, rel=1e-9)
    if suffix == ".step":  # STEP keeps the names: no selectors needed
        named = Geometry(kind="occ", file=str(path)).domain()
        assert measure_by_name(named) == pytest.approx(expected, rel=1e-9)


def test_split_points_make_two_arcs_of_a_hole():
    # geometry.split_points: the hole's circle (one edge) becomes two arcs a box selects apart
    # (UnifySameDomain would join arcs made as shapes). Each arc's length is pi R: exact on
    # the curved P3 mesh to its geometric error (measured 7e-5 relative at h = 0.1; 1e-3
    # asserted).
    geometry = Geometry(kind="occ", shapes=PLATE, split_points=[[1 - R, 0.5], [1 + R, 0.5]],
                        boundaries=[{"name": "upper", "box": [[1 - R, 0.5], [1 + R, 0.5 + R]]},
                                    {"name": "lower", "box": [[1 - R, 0.5 - R], [1 + R, 0.5]]}])
    domain = geometry.domain()
    assert set(domain.boundary_names) == {"upper", "lower", "free"}
    assert domain.measure == pytest.approx(2 - math.pi * R ** 2, rel=1e-12)
    mesh = domain.build_mesh(0.1)
    mesh.Curve(3)
    for name in ("upper", "lower"):
        length = ngs.Integrate(1, mesh, definedon=mesh.Boundaries(name))
        assert length == pytest.approx(math.pi * R, rel=1e-3), (name, length)
    # The same with a crack glued in (the remeshing path) keeps both arcs.
    cracked = domain.build_mesh(0.1, cracks=[[(0.2, 0.5), (0.5, 0.5)]])
    assert {"upper", "lower", CRACK_BOUNDARY} <= set(cracked.GetBoundaries())


@pytest.mark.parametrize("keys, fragment", [
    ({"shapes": PLATE, "split_points": [[0.5, 0.5]]}, "split_points[0] = [0.5, 0.5] lies on no"),
    ({"shapes": PLATE, "split_points": [[0.5, 0.5, 0.0]]}, "give points [x, y]"),
    ({"shapes": [{"type": "box", "corner": [0, 0, 0], "size": [1, 1, 1]}],
      "split_points": [[1.0, 0.5]]}, "the shape is 3D"),
])
def test_bad_split_points_are_one_line_scene_errors(keys, fragment):
    with pytest.raises(SceneError, match=None) as err:
        Geometry(kind="occ", **keys)
    assert fragment in str(err.value) and "\n" not in str(err.value), str(err.value)
