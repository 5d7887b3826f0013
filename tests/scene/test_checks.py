"""Scene checks beyond single keys: crack geometry Netgen cannot mesh, non-finite expressions,
resolution warnings (API side; tests/io/test_cli.py has the command line)."""
import warnings

import pytest

from ngfrac import MeshingError, ResolutionWarning, resolution_warnings, run_scene
from ngfrac.mesh.resolution import estimated_vertices
from ngfrac.geometry.domains import build_mesh
from ngfrac.scene import Geometry, SceneError

from ngfrac.testing.bad_inputs import BAD_2D, BAD_3D, BAD_EXPRESSIONS, BOX_CRACK, SLIT
from ngfrac.testing.scenes import demo_data, quick_slit, scene_from

def refused(data, match):
    with pytest.raises(SceneError, match=match) as info:
        scene_from(data)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("case", BAD_2D)
def test_bad_2d_crack_is_refused_in_one_line(case):
    cracks, match = BAD_2D[case]
    data = demo_data()
    data["cracks"] = [{"points": c} for c in cracks]
    refused(data, match)


@pytest.mark.parametrize("case", BAD_3D)
def test_bad_3d_crack_is_refused_in_one_line(case):
    cracks, match = BAD_3D[case]
    data = demo_data("box3d")
    data["cracks"] = [{"points": c} for c in cracks]
    refused(data, match)


@pytest.mark.parametrize("case", BAD_EXPRESSIONS)
def test_non_finite_expression_is_refused_with_key_and_point(case):
    override, match = BAD_EXPRESSIONS[case]
    with pytest.raises(SceneError, match=match):
        quick_slit("time.t_end=0.03", override)


def test_good_cracks_pass():
    data = demo_data()
    data["cracks"] = [{"points": SLIT}, {"points": [[0.6, 0.2], [0.6, 0.8]]},  # apart
                      {"points": [[0.8, 0.0], [0.8, 0.3], [0.9, 0.4]]},        # mouth on an edge, kinked
                      {"points": [[0.0, 0.9], [1.0, 0.9]]}]                    # edge to edge
    assert len(scene_from(data).cracks) == 4
    data = demo_data("box3d")
    data["cracks"] = [{"points": BOX_CRACK},
                      {"points": [[0.5, 0.3, 0.05], [0.5, 0.7, 0.05], [0.5, 0.7, 0.08], [0.5, 0.3, 0.08]]}]
    assert len(scene_from(data).cracks) == 2


def test_meshing_failure_is_a_meshing_error_not_a_netgen_exception():
    geometry = Geometry(width=1.0, height=1.0)
    with pytest.raises(MeshingError, match="Netgen could not mesh the rectangle") as info:
        build_mesh(geometry, 0.1, [[[0.0, 0.5], [0.3, 0.5], [0.1, 0.5]]])  # runs back: not validated here
    assert "\n" not in str(info.value)
    # a zero-length segment made Netgen segfault; it is refused before Netgen sees it
    zero = r"^a crack segment from \[0.3, 0.5\] to \[0.3, 0.5\] has zero length"
    with pytest.raises(MeshingError, match=zero):
        build_mesh(geometry, 0.1, [[[0.0, 0.5], [0.3, 0.5], [0.3, 0.5]]])


def test_3d_meshing_failures_are_meshing_errors():
    """OCC segfaulted on a crack polygon with a repeated corner (an edge from a point to
    itself); Netgen fails on a self-intersecting one. Both reach the user as one line."""
    box = Geometry(kind="box", width=1.0, height=1.0, depth=0.1)
    zero = r"^a crack polygon has a zero-length edge at corner 4 \[0.0, 0.5, 0.0\]"
    with pytest.raises(MeshingError, match=zero):
        build_mesh(box, 0.1, [BOX_CRACK + [BOX_CRACK[0]]])
    with pytest.raises(MeshingError, match="Netgen could not mesh the box") as info:
        build_mesh(box, 0.1, [[[0.0, 0.5, 0.0], [0.3, 0.5, 0.0], [0.0, 0.5, 0.1], [0.2, 0.5, 0.1]]])
    assert "\n" not in str(info.value)


# -- resolution --------------------------------------------------------------------------------

def test_demo_scenes_in_2d_resolve_their_cracks():
    for name in ("mode3_slit", "mode3_stripes", "mode12_kink", "mode12_stripes", "sent", "sens"):
        scene = scene_from(demo_data(name))
        assert resolution_warnings(scene) == [], name


def test_box3d_demo_is_honestly_under_resolved():
    """3,000 vertices cannot give h_tip = 5e-3 in the tip ball nor epsilon = 0.04 fit the
    0.1-deep block ten times; the demo relies on the cap (its comment says so)."""
    found = resolution_warnings(scene_from(demo_data("box3d")))
    assert [m.split(" ", 1)[0] for m in found] == ["adaptivity.max_vertices", "phase_field.epsilon"]


@pytest.mark.parametrize("overrides, start", [
    (["adaptivity.enabled=false", "geometry.mesh_size=0.02"], "geometry.mesh_size = 0.02 is above epsilon/2 = 0.01"),
    (["adaptivity.h_band=0.02"], "adaptivity.h_band = 0.02 is above epsilon/2 = 0.01"),
    (["adaptivity.hmin=0.012"], "adaptivity.h_crack = 0.012 (derived, at least adaptivity.hmin) is above"),
    (["adaptivity.max_vertices=100"], "adaptivity.max_vertices = 100 is below the ~"),
    (["phase_field.epsilon=0.15", "adaptivity.enabled=false", "geometry.mesh_size=0.05"],
     "phase_field.epsilon = 0.15 is above a tenth of the smallest extent of the domain (1)"),
])
def test_resolution_warning_lines(overrides, start):
    found = resolution_warnings(scene_from(demo_data(), *overrides))
    assert any(m.startswith(start) for m in found), found
    assert all("\n" not in m for m in found)


def test_vertex_estimate_is_a_lower_bound_and_finds_the_issue_case():
    """The issue's case: max_vertices = 100 ran at h = 0.075 for epsilon = 0.02, silently.
    The estimate leaves out grading halos: the slit demo's uncapped first mesh had 5,990
    vertices against 2,908 estimated (measured with max_vertices = 50000), so it only warns
    when even the lower bound is above the cap."""
    scene = scene_from(demo_data())
    assert 2000 < estimated_vertices(scene) < 5000
    # the band's vertices grow like 1/epsilon in 2D (width ~ epsilon, h ~ epsilon)
    finer = scene_from(demo_data(), "phase_field.epsilon=0.005", "adaptivity.hmin=5e-4")
    assert estimated_vertices(finer) > 5000
    assert resolution_warnings(finer)[0].startswith("adaptivity.max_vertices = 5000 is below")


def test_run_scene_warns_before_writing(tmp_path):
    scene = quick_slit("time.t_end=0.001", "geometry.mesh_size=0.05")  # > epsilon/2 = 0.02
    with pytest.warns(ResolutionWarning, match="geometry.mesh_size = 0.05 is above epsilon/2"):
        run_scene(scene, tmp_path / "run", plots=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ResolutionWarning)
        run_scene(quick_slit("time.t_end=0.001"), tmp_path / "quiet", plots=False)  # none
