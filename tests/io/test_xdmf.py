"""results.xdmf and the per-mesh results_mesh_NNN.xdmf of a run whose mesh changes (issue 28,
item 5): ParaView reads each snapshot's own grid from results.xdmf; meshio's TimeSeriesReader
reads one mesh per file, so each mesh gets a file of the snapshots on it."""
import json
import shutil
import warnings
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

from ngfrac import ResolutionWarning
from ngfrac.io.results import ResultsWriter, open_results
from ngfrac.runner import run_scene
from ngfrac.testing.scenes import quick_slit

pytestmark = pytest.mark.usefixtures("one_thread")


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """5 steps, a snapshot each; the mesh changes after step 2 (stepper.adapt()) and after
    step 4, so three meshes hold snapshots 0-2, 3-4 and 5."""
    scene = quick_slit("phase_field.epsilon=0.08", "geometry.mesh_size=0.04",
                       "discretization.order=1", "adaptivity.enabled=true",
                       "adaptivity.max_vertices=600", "adaptivity.hmin=0.01",
                       "time.t_end=0.0025", "output.vtk_every=1")
    out = tmp_path_factory.mktemp("xdmf") / "run"

    def change_mesh(stepper):
        if stepper.k in (2, 4):
            before = stepper.mesh.nv
            stepper.adapt()
            assert stepper.mesh.nv != before

    with warnings.catch_warnings():  # the cap is below what the band needs: a small run
        warnings.simplefilter("ignore", ResolutionWarning)
        run_scene(scene, out, plots=False, on_step=change_mesh)
    return out


def test_meshio_reads_every_snapshot_on_its_own_mesh(run):
    results = open_results(run / "results.h5")
    files = sorted(run.glob("results_mesh_*.xdmf"))
    assert [f.name for f in files] == [f"results_mesh_{i:03d}.xdmf" for i in range(3)]
    seen = []
    for path in files:
        with meshio.xdmf.TimeSeriesReader(path) as reader:
            points, cells = reader.read_points_cells()
            for k in range(reader.num_steps):
                t, point_data, _ = reader.read_data(k)
                snapshot = results.snapshot(len(seen)).arrays()
                assert t == snapshot.t
                assert len(point_data["z"]) == len(points) == len(snapshot.coordinates)
                np.testing.assert_array_equal(points, snapshot.coordinates)
                np.testing.assert_array_equal(cells[0].data, snapshot.cells)
                np.testing.assert_array_equal(point_data["z"], snapshot.z)
                np.testing.assert_array_equal(point_data["u"], snapshot.u)
                seen.append(t)
    assert len(seen) == len(results) == 6
    assert len({len(results.snapshot(i).arrays().coordinates) for i in (0, 3, 5)}) == 3


def test_results_xdmf_gives_each_snapshot_its_own_grid(run):
    """Each grid of the temporal collection has its mesh and node data of that mesh's size."""
    results = open_results(run / "results.h5")
    collection = ET.parse(run / "results.xdmf").getroot().find("Domain/Grid")
    assert collection.get("CollectionType") == "Temporal"
    grids = collection.findall("Grid")
    assert len(grids) == len(results)
    for i, grid in enumerate(grids):
        nv = len(results.snapshot(i).arrays().coordinates)
        points = grid.find("Geometry/DataItem").get("Dimensions").split()
        assert int(points[0]) == nv
        for attribute in grid.findall("Attribute"):
            assert int(attribute.find("DataItem").get("Dimensions").split()[0]) == nv


def test_per_mesh_files_are_in_the_manifest(run):
    files = json.loads((run / "manifest.json").read_text())["files"]
    assert {f"results_mesh_{i:03d}.xdmf" for i in range(3)} <= set(files)


def test_a_restart_removes_the_files_of_dropped_meshes(run, tmp_path):
    """Continuing from step 2 drops snapshots 3-5 and with them the files of meshes 1 and 2."""
    copy = tmp_path / "run"
    shutil.copytree(run, copy)
    ResultsWriter.resume(copy / "results.h5", open_results(copy / "results.h5").scene, 2).close()
    assert [f.name for f in copy.glob("results_mesh_*.xdmf")] == ["results_mesh_000.xdmf"]
    with meshio.xdmf.TimeSeriesReader(copy / "results_mesh_000.xdmf") as reader:
        assert reader.num_steps == 3
