"""Every VTK and HDF5 file a run writes is read back by independent readers (meshio, h5py)."""
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pytest

from ngfrac.output import VTKSeries
from ngfrac.results import ResultsWriter
from ngfrac.runner import write_snapshot
from ngfrac.stepper import PhaseFieldStepper

from scenes import demo_data, scene_from


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
        assert {"u", "z", "gamma"} <= set(mesh.point_data)
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
