"""Adaptive 3D meshes: regenerated from a size field, never above the vertex cap."""
import copy

import numpy as np
import pytest

from ngfrac.physics.cracks import distance_to_polygons
from ngfrac.geometry.domains import build_mesh, netgen_geometry
from ngfrac.fem.elements import ElementGeometry
from ngfrac.fem import threads
from ngfrac.mesh.remesh import adapt_mesh
from ngfrac.scene import Scene
from ngfrac.solve.stepper import PhaseFieldStepper

from .test_adapter import counting_new_meshes

CRACK = [[0.0, 0.25, 0.0], [0.2, 0.25, 0.0], [0.2, 0.25, 0.1], [0.0, 0.25, 0.1]]


def small_box(**adaptivity):
    """A 0.5 x 0.5 x 0.1 plate with an edge crack through its depth, pulled in y."""
    return Scene.from_dict({
        "model": {"kind": "elasticity_3d"},
        "material": {"E": 1.0, "nu": 0.3, "gamma": 1.0},
        "phase_field": {"epsilon": 0.04, "alpha2": 1e-3},
        "geometry": {"kind": "box", "width": 0.5, "height": 0.5, "depth": 0.1},
        "cracks": [{"points": copy.deepcopy(CRACK)}],
        "loads": [{"boundary": "top", "value": ["0", "4*t", "0"]},
                  {"boundary": "bottom", "value": ["free", "0", "free"]}],
        "time": {"dt": 0.05, "t_end": 0.2},
        "discretization": {"order": 1},
        "adaptivity": {"enabled": True, "hmin": 0.005, **adaptivity},
    })


def adapted_box(scene):
    """The box meshed at 0.08 and adapted toward the crack under an 800-vertex cap."""
    mesh = build_mesh(scene.geometry, 0.08, [CRACK])
    geom = ElementGeometry.of(mesh)
    # asks for ~100,000 vertices: h = 0.005 at the crack, growing by 0.3 per unit distance
    sizes = np.clip(0.005 + 0.3 * distance_to_polygons(geom.centroids, [CRACK]), 0.005, 0.08)
    return adapt_mesh(mesh, netgen_geometry(scene.geometry, [CRACK]), sizes, hmax=0.08,
                      max_vertices=800)


def test_adapt_mesh_in_3d_meets_the_cap_and_refines_at_the_crack():
    scene = small_box()
    new = adapted_box(scene)
    assert 400 < new.nv <= 800, new.nv  # the cap holds and is used
    fine = ElementGeometry.of(new)
    distance = distance_to_polygons(fine.centroids, [CRACK])
    near, far = fine.diameters[distance < 0.02], fine.diameters[distance > 0.15]
    assert np.median(near) < 0.6 * np.median(far), (np.median(near), np.median(far))
    assert set(new.GetBoundaries()) == {"left", "right", "bottom", "top", "back", "front", "crack"}


def test_netgen_meshes_3d_alike_on_one_thread_and_on_four():
    """Netgen meshes volumes on NGSolve's configured thread count (its own default was 4,
    whatever NGFRAC_THREADS said: ngfrac.fem.threads.meshing_threads); the mesh is the same
    vertex for vertex and element for element on one thread and on four."""
    configured = threads.configured_threads()
    meshes = []
    try:
        for n in (1, 4):
            threads.note_threads(n)
            assert threads.meshing_threads() == {"parallel_meshing": n > 1, "nthreads": n}
            meshes.append(adapted_box(small_box()).ngmesh)
    finally:
        threads.note_threads(configured)
    one, four = meshes
    assert np.array_equal(np.array(one.Coordinates()), np.array(four.Coordinates()))
    assert np.array_equal(one.Elements3D().NumPy()["nodes"], four.Elements3D().NumPy()["nodes"])


def test_short_adaptive_3d_run_respects_cap_and_bounds():
    scene = small_box(max_vertices=700)
    stepper = PhaseFieldStepper(scene)
    assert stepper.mesh.nv <= 700
    assert stepper.adapter.sizes.hmax > 0.05  # the start mesh is coarse, not a tenth of the depth
    previous, mesh = stepper.z_node_values(), stepper.mesh
    for record in stepper.run():
        assert record.nv <= 700
        values = stepper.z_node_values()
        assert values.min() >= 0.0 and values.max() <= 1.0
        if stepper.mesh is mesh:
            assert np.all(values >= previous)
        previous, mesh = values, stepper.mesh
    stepper.adapt()  # a forced mesh change: cap, bounds, crack kept
    assert stepper.mesh.nv <= 700
    values = stepper.z_node_values()
    assert values.min() >= 0.0 and values.max() <= 1.0
    assert stepper.adaptations and stepper.adaptations[-1].crack_length_after == pytest.approx(
        stepper.adaptations[-1].crack_length_before, rel=0.05)


def test_3d_adaptive_restart_continues_exactly(tmp_path):
    """Checkpoints hold 3D meshes: a run stopped after two steps and restarted ends with the
    same history row as the uninterrupted run. (No mesh changes in these four steps: 443
    vertices throughout, n_adapt 0, measured in session 14; a restart across a mesh change is
    tests/io/test_checkpoint.py's, in 2D.)"""
    from ngfrac.io.plotting import read_history
    from ngfrac.runner import run_scene

    def scene(t_end):
        data = small_box(max_vertices=700)
        return Scene.from_dict({**_as_dict(data), "time": {"dt": 0.05, "t_end": t_end},
                                "output": {"checkpoint_every": 1, "vtk_every": 0}})

    run_scene(scene(0.2), tmp_path / "full", plots=False)
    run_scene(scene(0.1), tmp_path / "part", plots=False)
    run_scene(scene(0.2), tmp_path / "part", restart=True, plots=False)
    full, part = read_history(tmp_path / "full" / "history.csv"), read_history(tmp_path / "part" / "history.csv")
    assert list(full) == list(part) and "tip_z" in full
    for column in ("step", "nv", "n_adapt"):  # the same steps on the same meshes
        assert part[column][-1] == full[column][-1], column
    # To round-off: with two or more NGSolve threads the parallel assembly sums element
    # contributions in varying order (seen: E_total 0.04688722963559155 vs ...154).
    for column in ("E_total", "crack_length", "tip_z", "Fy_top"):
        assert part[column][-1] == pytest.approx(full[column][-1], rel=1e-10, abs=1e-14), column


def _as_dict(scene):
    data = scene.to_dict()
    data.pop("name")
    return data


def test_3d_makes_two_initial_passes_unless_the_scene_says(monkeypatch):
    """A 3D pass is a Netgen run of the whole volume; the third one changed the cube's z0
    crack area by 0.05 % (docs/benchmarks.md, "Two initial passes in 3D")."""
    calls = counting_new_meshes(monkeypatch)
    PhaseFieldStepper(small_box(max_vertices=400))
    assert calls == [3, 3]
    calls.clear()
    PhaseFieldStepper(small_box(max_vertices=400, initial_passes=3))
    assert calls == [3, 3, 3]
