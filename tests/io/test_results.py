"""HDF5 results: meshes rebuilt with NGSolve's numbering, read-back of fields, bad files."""
import os
import subprocess
import sys

import h5py
import numpy as np
import ngsolve as ngs
import pytest

from ngfrac.geometry.domains import build_mesh, netgen_geometry
from ngfrac.mesh.remesh import remesh
from ngfrac.io.hdf5 import MeshArrays, ResultsError, StoredField
from ngfrac.io.results import FORMAT_VERSION, ResultsWriter, open_results
from ngfrac.solve.stepper import PhaseFieldStepper, StepRecord

from ngfrac.testing.scenes import quick_slit


pytestmark = pytest.mark.usefixtures("one_thread")


@pytest.fixture(scope="module")
def scene():
    return quick_slit("time.t_end=0.02")


@pytest.fixture(scope="module")
def stepper(scene):
    stepper = PhaseFieldStepper(scene)
    stepper.step()
    return stepper


def _graded_mesh(scene):
    """A Netgen mesh graded towards the crack tip, as adaptive remeshing makes them."""
    points = np.array([[0.3, 0.5], [0.1, 0.5], [0.9, 0.9]])
    geometry = netgen_geometry(scene.geometry, [c.points for c in scene.cracks])
    return remesh(geometry, points, np.array([0.01, 0.03, 0.1]), hmax=0.1, max_vertices=3000)


def _cube_mesh(scene):
    from netgen.csg import unit_cube
    return ngs.Mesh(unit_cube.GenerateMesh(maxh=0.35))


def _slit_mesh(scene):
    return build_mesh(scene.geometry, scene.mesh_size, [c.points for c in scene.cracks])


def _random_points(mesh, n=200, seed=1):
    rng = np.random.default_rng(seed)
    coords = np.array(mesh.ngmesh.Coordinates())
    lo, hi = coords.min(axis=0), coords.max(axis=0)
    return lo + (hi - lo) * rng.random((n, mesh.dim))


def _values(gf, mesh, points):
    return np.array([gf(mesh(*p)) for p in points])


@pytest.mark.parametrize("make_mesh", [_slit_mesh, _graded_mesh, _cube_mesh])
def test_rebuilt_mesh_keeps_ngsolve_numbering(scene, make_mesh):
    original = make_mesh(scene)
    rebuilt = MeshArrays.of(original).to_mesh()
    assert (rebuilt.nv, rebuilt.nedge, rebuilt.nface, rebuilt.ne) == \
        (original.nv, original.nedge, original.nface, original.ne)
    assert rebuilt.GetBoundaries() == original.GetBoundaries()
    assert rebuilt.GetMaterials() == original.GetMaterials()
    np.testing.assert_array_equal(np.array(rebuilt.ngmesh.Coordinates()),
                                  np.array(original.ngmesh.Coordinates()))
    for nodes in ("edges", "faces"):
        assert [tuple(v.nr for v in e.vertices) for e in getattr(rebuilt, nodes)] == \
               [tuple(v.nr for v in e.vertices) for e in getattr(original, nodes)], nodes
    # Boundary elements per region, and Dirichlet dofs, as in the original.
    for name in set(original.GetBoundaries()):
        count = len(list(original.Boundaries(name).Elements()))
        assert len(list(rebuilt.Boundaries(name).Elements())) == count, name
    boundary = original.GetBoundaries()[0]
    rng = np.random.default_rng(0)
    points = _random_points(original)
    for order in (1, 2, 3):
        spaces = [ngs.H1(m, order=order, dirichlet=boundary) for m in (original, rebuilt)]
        assert list(spaces[0].FreeDofs()) == list(spaces[1].FreeDofs())
        gfs = [ngs.GridFunction(fes) for fes in spaces]
        gfs[0].vec.FV().NumPy()[:] = rng.standard_normal(spaces[0].ndof)
        gfs[1].vec.data = gfs[0].vec  # the same dof vector must mean the same function
        np.testing.assert_array_equal(_values(gfs[1], rebuilt, points),
                                      _values(gfs[0], original, points), err_msg=f"order {order}")


def test_snapshots_and_history_read_back(tmp_path, scene, stepper):
    path = tmp_path / "results.h5"
    record = stepper.record()
    with ResultsWriter(path, scene) as writer:
        writer.append(record)
        writer.write_snapshot(stepper)
        writer.append([float(i) for i in range(len(record.header()))])
        writer.write_snapshot(stepper)
    results = open_results(path)
    assert results.scene.to_dict() == scene.to_dict()
    assert list(results.history) == record.header()
    assert set(StepRecord.columns()) <= set(results.history)
    np.testing.assert_array_equal(results.history["step"], [stepper.k, 0.0])
    assert results.history["ndof"][1] == record.header().index("ndof")
    assert results.history["E_total"][0] == record.E_total
    np.testing.assert_array_equal(results.snapshot_times(), [stepper.t, stepper.t])
    with h5py.File(path) as f:  # an unchanged mesh is stored once and linked
        assert f["snapshots/00000/mesh"] == f["snapshots/00001/mesh"]
    snap = results.snapshot(-1)
    assert snap.step == stepper.k
    points = _random_points(stepper.mesh, 100)
    for name in ("u", "z"):
        original = getattr(stepper, name)
        restored = snap.fields[name]
        assert restored.space.globalorder == original.space.globalorder
        np.testing.assert_array_equal(_values(restored, snap.mesh, points),
                                      _values(original, stepper.mesh, points), err_msg=name)
    arrays = snap.arrays()
    np.testing.assert_array_equal(arrays.coordinates, np.array(stepper.mesh.ngmesh.Coordinates()))
    assert arrays.cells.shape == (stepper.mesh.ne, 3)
    np.testing.assert_array_equal(arrays.z, stepper.z_node_values()[: stepper.mesh.nv])
    vertices = arrays.coordinates[:20]
    np.testing.assert_allclose(arrays.u[:20], _values(stepper.u, stepper.mesh, vertices), atol=1e-12)


def test_snapshot_of_a_changed_mesh_has_its_own_mesh(tmp_path, scene, stepper):
    path = tmp_path / "results.h5"
    graded = _graded_mesh(scene)
    z = ngs.GridFunction(ngs.H1(graded, order=2), "z")
    z.Set(ngs.x * ngs.y)
    with ResultsWriter(path, scene) as writer:
        writer.write_snapshot(stepper)
        writer.write_fields(graded, {"z": z}, t=1.0, step=7)
    snap = open_results(path).snapshot(1)
    assert snap.mesh.nv == graded.nv != stepper.mesh.nv
    assert snap.field_names == ["z"]
    assert abs(snap.z(snap.mesh(0.3, 0.7)) - 0.21) < 1e-12


def test_vector_field_read_back(tmp_path, scene, stepper):
    """A vector-valued u (plane models) is rebuilt in its own space type."""
    fes = ngs.VectorH1(stepper.mesh, order=2, dirichlet="top")
    u = ngs.GridFunction(fes, "u")
    u.Set(ngs.CF((ngs.x, ngs.x * ngs.y)))
    path = tmp_path / "results.h5"
    with ResultsWriter(path, scene) as writer:
        writer.write_fields(stepper.mesh, {"u": u, "z": stepper.z}, t=0.0, step=0)
    snap = open_results(path).snapshot(0)
    assert snap.u.space.type == fes.type and snap.u.space.ndof == fes.ndof
    assert snap.u(snap.mesh(0.5, 0.25)) == pytest.approx((0.5, 0.125), abs=1e-12)
    arrays = snap.arrays()
    assert arrays.u.shape == (stepper.mesh.nv, 2)
    np.testing.assert_allclose(arrays.u[:, 1], arrays.coordinates[:, 0] * arrays.coordinates[:, 1],
                               atol=1e-12)


def test_resume_drops_rows_and_snapshots_after_the_step(tmp_path, scene, stepper):
    path = tmp_path / "results.h5"
    with ResultsWriter(path, scene, columns=["step", "E_total"]) as writer:
        for step in range(6):
            writer.append([float(step), 0.0])
            if step % 2 == 0:
                writer.write_fields(stepper.mesh, {"z": stepper.z}, t=step * 0.1, step=step)
    with ResultsWriter.resume(path, scene, step=3) as writer:
        writer.append([4.0, 1.0])
        writer.write_fields(stepper.mesh, {"z": stepper.z}, t=0.4, step=4)
    results = open_results(path)
    np.testing.assert_array_equal(results.history["step"], [0, 1, 2, 3, 4])
    np.testing.assert_array_equal(results.snapshot_steps(), [0, 2, 4])
    other = quick_slit("time.t_end=0.02", "phase_field.alpha2=2e-3")
    with pytest.raises(ResultsError, match="another scene .*phase_field.alpha2"):
        ResultsWriter.resume(path, other, step=3)


# -- bad input ---------------------------------------------------------------------------------
@pytest.fixture
def valid_file(tmp_path, scene, stepper):
    path = tmp_path / "good.h5"
    with ResultsWriter(path, scene) as writer:
        writer.append(stepper.record(diagnose=False))
        writer.write_snapshot(stepper)
    return path


def _expect_error(path, fragment):
    before = path.read_bytes() if path.exists() else None
    with pytest.raises(ResultsError, match=fragment) as info:
        open_results(path)
    message = str(info.value)
    assert len(message.splitlines()) == 1, message
    assert (path.read_bytes() if path.exists() else None) == before  # left as it was
    return message


def test_refuses_to_clobber(valid_file, scene):
    before = valid_file.read_bytes()
    with pytest.raises(ResultsError, match="exists; pass overwrite"):
        ResultsWriter(valid_file, scene)
    assert valid_file.read_bytes() == before
    ResultsWriter(valid_file, scene, overwrite=True).close()
    assert open_results(valid_file).history == {}


def test_missing_file(tmp_path):
    _expect_error(tmp_path / "nope.h5", "does not exist")


def test_garbage_is_not_hdf5(tmp_path):
    path = tmp_path / "garbage.h5"
    path.write_bytes(os.urandom(4096))
    _expect_error(path, "is not an HDF5 file")


def test_truncated_file(valid_file, tmp_path):
    path = tmp_path / "truncated.h5"
    data = valid_file.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    _expect_error(path, "truncated or corrupt")


def test_file_of_another_program(tmp_path):
    path = tmp_path / "foreign.h5"
    with h5py.File(path, "w") as f:
        f["data"] = np.arange(3)
    _expect_error(path, "not an ngfrac results file")


def test_newer_format_version(valid_file):
    with h5py.File(valid_file, "a") as f:
        f.attrs["format_version"] = FORMAT_VERSION + 1
    _expect_error(valid_file, "newer than this ngfrac reads")


def test_missing_group(valid_file):
    with h5py.File(valid_file, "a") as f:
        del f["history"]
    _expect_error(valid_file, "lacks .*history")


def test_corrupt_mesh(valid_file):
    with h5py.File(valid_file, "a") as f:
        f["snapshots/00000/mesh/cells"][0] = [0, 1, 10**8]
    results = open_results(valid_file)
    with pytest.raises(ResultsError, match="inconsistent: cells refer to missing vertices"):
        results.snapshot(0)


def test_flipped_bytes_in_a_field_are_detected(valid_file):
    with h5py.File(valid_file) as f:
        offset = f["snapshots/00000/fields/u"].id.get_chunk_info(0).byte_offset
    data = bytearray(valid_file.read_bytes())
    data[offset + 64] ^= 0xFF
    valid_file.write_bytes(bytes(data))
    results = open_results(valid_file)  # the damage is in the field, not in the metadata
    with pytest.raises(ResultsError, match="truncated or corrupt .*filter returned failure"):
        results.snapshot(0)


def test_changed_scene_text_is_detected(valid_file):
    with h5py.File(valid_file, "a") as f:
        text = f["scene"].asstr()[()].replace("epsilon = 0.04", "epsilon = 0.05")
        checksum = f["scene"].attrs["sha256"]
        del f["scene"]
        f.create_dataset("scene", data=text, dtype=h5py.string_dtype())
        f["scene"].attrs["sha256"] = checksum
    _expect_error(valid_file, "scene text does not match its checksum")


def test_file_open_in_a_running_writer(valid_file, scene):
    """HDF5 locks a file being written; the reader says so instead of 'corrupt'."""
    with ResultsWriter(valid_file, scene, overwrite=True):
        code = ("from ngfrac.io.hdf5 import ResultsError\n"
                "from ngfrac.io.results import open_results\n"
                f"try:\n    open_results({str(valid_file)!r})\n"
                "except ResultsError as err:\n    print(err)\n")
        result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert "is open for writing in another process" in result.stdout, result.stderr


def test_write_failure_is_a_results_error(tmp_path, scene, stepper, monkeypatch):
    def disk_full(self, group, name):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(StoredField, "write", disk_full)
    with ResultsWriter(tmp_path / "results.h5", scene) as writer:
        with pytest.raises(ResultsError, match="cannot write to results file .*No space left"):
            writer.write_snapshot(stepper)
