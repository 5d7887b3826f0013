"""Every VTK and HDF5 file a run writes is read back by independent readers (meshio, h5py)."""
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pytest

from ngfrac.io.output import VTKSeries
from ngfrac.io.results import ResultsWriter
from ngfrac.runner import write_snapshot
from ngfrac.solve.stepper import PhaseFieldStepper

from ngfrac.testing.scenes import demo_data, scene_from


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """Snapshots of an adaptive run with a mesh change between them."""
    out = tmp_path_factory.mktemp("vtk")
    scene = scene_from(demo_data(), "phase_field.epsilon=0.08", "time.t_end=0.002",
                       "adaptivity.max_vertices=800")
    stepper = PhaseFieldStepper(scene)
    series = VTKSeries(out / "vtk", subdivision=1)
    results = ResultsWriter(out / "results.h5", scene)
    results.append(stepper.record())
    write_snapshot(series, stepper)
    results.write_snapshot(stepper)
    for record in stepper.run():
        results.append(record)
        stepper.adapt()  # force a new mesh before every snapshot
        write_snapshot(series, stepper)
        results.write_snapshot(stepper)
    results.close()
    return out, stepper


def test_pvd_lists_readable_files_in_time_order(written):
    out, _ = written
    root = ET.parse(out / "vtk" / "fields.pvd").getroot()
    entries = [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]
    assert len(entries) >= 3
    times = [t for t, _ in entries]
    assert times == sorted(times)
    sizes = set()
    for _, name in entries:
        mesh = meshio.read(out / "vtk" / name)
        assert {"u", "z", "gamma", "energy_density", "stress", "estimator", "h"} <= set(mesh.point_data)
        assert mesh.point_data["stress"].shape == (len(mesh.points), 2)  # mode III: (s_xz, s_yz)
        for values in mesh.point_data.values():
            assert np.all(np.isfinite(values))
        assert mesh.points.shape[0] > 0
        sizes.add(mesh.points.shape[0])
    assert len(sizes) > 1, "the mesh changed between snapshots, the files must show it"


def test_results_file_read_by_plain_h5py(written):
    out, stepper = written
    with h5py.File(out / "results.h5", "r") as f:
        columns = [str(c) for c in f["history"].attrs["columns"]]
        history = f["history"][()]
        assert history.shape == (stepper.k + 1, len(columns))
        assert "scene" in f and "snapshots" in f
        snaps = sorted(f["snapshots"])
        assert len(snaps) == stepper.k + 1
        last = f["snapshots"][snaps[-1]]
        coords = last["mesh"]["coordinates"][()]
        assert coords.shape == (stepper.mesh.nv, 2)
        z = last["fields"]["z"][()]
        assert z.shape == (stepper.fes_z.ndof,)
        assert np.allclose(z, stepper.z.vec.FV().NumPy())
        # what a reader without NGSolve needs: vertices, 0-based triangles, values at the vertices
        assert last["mesh"]["coordinates"].attrs["units"] == "scene units"
        cells = last["mesh"]["cells"][()]
        assert cells.shape == (stepper.mesh.ne, 3) and cells.min() == 0
        assert cells.max() == stepper.mesh.nv - 1
        z_vertices = last["vertex_values"]["z"][()]
        np.testing.assert_array_equal(z_vertices, stepper.z_node_values()[: stepper.mesh.nv])
        u_vertices = last["vertex_values"]["u"][()]
        assert last["vertex_values"]["u"].attrs["units"] == "scene units"
        at = stepper.mesh(coords[:, 0], coords[:, 1])
        # P2 point evaluation against the stored vertex dofs: round-off only
        np.testing.assert_allclose(u_vertices, np.asarray(stepper.u(at)).ravel(), rtol=0, atol=1e-12)


def test_xdmf_index_points_at_the_snapshots(written):
    out, stepper = written
    root = ET.parse(out / "results.xdmf").getroot()
    grids = root.find("Domain").find("Grid").findall("Grid")
    with h5py.File(out / "results.h5", "r") as f:
        assert len(grids) == len(f["snapshots"])
        times = [float(g.find("Time").get("Value")) for g in grids]
        assert times == sorted(times)
        for grid in grids:
            for item in grid.iter("DataItem"):
                file, path = item.text.split(":")
                assert file == "results.h5"
                dims = tuple(int(n) for n in item.get("Dimensions").split())
                assert f[path].shape == dims, path
    # meshio's XDMF time-series reader gets the first mesh and each step's vertex values
    with meshio.xdmf.TimeSeriesReader(out / "results.xdmf") as reader:
        points, cells = reader.read_points_cells()
        assert cells[0].type == "triangle"
        t, point_data, _ = reader.read_data(0)
        assert point_data["z"].shape == (len(points),)
