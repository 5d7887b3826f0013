"""Checkpoints: a restored stepper continues like the uninterrupted one, also after SIGKILL;
bad checkpoints give one clear error and stay as they were."""
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from ngfrac.io.checkpoint import (FORMAT_VERSION, CheckpointError, load_checkpoint, restore, resume,
                               save_checkpoint, save_state)
from ngfrac.io.results import MeshArrays
from ngfrac.solve.stepper import PhaseFieldStepper

from ngfrac.testing.scenes import quick_slit

ROOT = Path(__file__).resolve().parents[2]

SCENE = ("time.t_end=0.02",)
N_STEPS, CHECKPOINT_AT = 20, 10
COMPARED = ("E_total", "crack_length", "tip_x", "tip_y")


pytestmark = pytest.mark.usefixtures("one_thread")


@pytest.fixture(scope="module")
def scene():
    return quick_slit(*SCENE)


@pytest.fixture(scope="module")
def reference(scene, tmp_path_factory):
    """The uninterrupted run: its records, and a checkpoint written at step CHECKPOINT_AT."""
    folder = tmp_path_factory.mktemp("reference")
    stepper = PhaseFieldStepper(scene)
    records = {}
    for _ in range(N_STEPS):
        record = stepper.step()
        records[record.step] = record
        if record.step == CHECKPOINT_AT:
            save_checkpoint(stepper, folder / "checkpoint.h5")
    return records, folder / "checkpoint.h5"


def _assert_same_history(records, reference, first):
    """Records from step ``first`` to the end agree with the reference to round-off."""
    assert sorted(records) == list(range(first, N_STEPS + 1))
    for step, record in records.items():
        for name in COMPARED:
            got, want = getattr(record, name), getattr(reference[step], name)
            assert got == pytest.approx(want, rel=1e-10, abs=1e-14), \
                f"step {step}: {name} = {got!r} after restart, {want!r} uninterrupted"
        forces = getattr(reference[step], "forces", {})
        assert getattr(record, "forces", {}) == pytest.approx(forces, rel=1e-10, abs=1e-14), step


def _continue(stepper):
    records = {}
    while stepper.k < N_STEPS:
        record = stepper.step()
        records[record.step] = record
    return records


def test_restart_reproduces_the_uninterrupted_history(scene, reference):
    records, checkpoint = reference
    state = load_checkpoint(checkpoint, scene)
    assert state.k == CHECKPOINT_AT and state.t == pytest.approx(CHECKPOINT_AT * scene.time.dt)
    stepper = PhaseFieldStepper(scene, mesh=state.build_mesh())
    restore(stepper, state)
    assert stepper.k == CHECKPOINT_AT and stepper.time.Get() == stepper.t
    _assert_same_history(_continue(stepper), records, CHECKPOINT_AT + 1)


def test_restore_moves_a_stepper_to_the_checkpoint_mesh(scene, reference):
    """A stepper on another mesh is set up anew on the checkpoint's mesh (as after a remesh)."""
    records, checkpoint = reference
    coarse = quick_slit(*SCENE, "geometry.mesh_size=0.05")
    stepper = PhaseFieldStepper(scene, mesh=PhaseFieldStepper(coarse).mesh)
    state = load_checkpoint(checkpoint, scene)
    restore(stepper, state)
    assert MeshArrays.of(stepper.mesh).same_as(state.mesh_arrays)
    record = stepper.step()  # one step here; the full continuation is the test above
    for name in COMPARED:
        assert getattr(record, name) == pytest.approx(getattr(records[record.step], name),
                                                      rel=1e-10), name


def test_output_keys_and_end_time_may_change(scene, reference):
    _, checkpoint = reference
    longer = quick_slit("time.t_end=0.5", "output.vtk_every=3", "output.history_every=2")
    assert load_checkpoint(checkpoint, longer).k == CHECKPOINT_AT


def test_restart_after_a_mesh_change(tmp_path):
    """An adaptive run: the checkpoint holds a remeshed mesh and the adapter's memory."""
    scene = quick_slit(*SCENE, "adaptivity.enabled=true", "adaptivity.every=2",
                       "adaptivity.max_vertices=1500")
    stepper = PhaseFieldStepper(scene)
    reference = {}
    while stepper.k < 8:
        record = stepper.step()
        reference[record.step] = record
        if stepper.k == 3:
            before = stepper.mesh
            stepper.adapt()  # a mesh change between the start and the checkpoint
            assert stepper.mesh is not before
        if stepper.k == 5:
            save_checkpoint(stepper, tmp_path / "checkpoint.h5")
    restarted = resume(tmp_path / "checkpoint.h5", scene)
    assert restarted.k == 5 and len(restarted.adaptations) == len(stepper.adaptations) >= 1
    while restarted.k < 8:
        record = restarted.step()
        want = reference[record.step]
        assert (record.nv, record.n_adapt) == (want.nv, want.n_adapt)
        for name in (*COMPARED, "eta_total"):
            assert getattr(record, name) == pytest.approx(getattr(want, name), rel=1e-10), \
                f"step {record.step}: {name}"


def test_adaptivity_state_round_trip(scene, reference, tmp_path):
    """What decides the next mesh change (last tip, achieved sizes, eta, the learned vertex
    constant and size floor, the changes so far) and where a crack without an initial one
    started are restored."""
    import dataclasses

    from ngfrac.mesh.adapter import Adaptation

    state = load_checkpoint(reference[1], scene)
    source = PhaseFieldStepper(scene, mesh=state.build_mesh())
    restore(source, state)
    change = Adaptation(step=3, nv_before=100, nv_after=120, eta_total=0.2,
                        crack_length_before=1.0, crack_length_after=0.99, estimate_s=0.1,
                        mark_s=0.0, remesh_s=0.5, transfer_s=0.1, reason="tip moved")
    adapter = {"eta_total": 0.125, "last_tip": np.array([0.31, 0.5]), "achieved": (0.01, 0.004),
               "vertex_density": (1.37, True), "size_floor_ratio": 0.83, "adaptations": [change]}
    adaptive = dataclasses.replace(source.state(), adapter=adapter, nucleus=np.array([0.25, 0.75]))
    save_state(adaptive, scene, tmp_path / "adaptive.h5")
    restored = load_checkpoint(tmp_path / "adaptive.h5", scene).stepper_state()
    np.testing.assert_array_equal(restored.adapter["last_tip"], [0.31, 0.5])
    assert restored.adapter["achieved"] == (0.01, 0.004) and restored.adapter["eta_total"] == 0.125
    assert restored.adapter["vertex_density"] == (1.37, True)
    assert restored.adapter["size_floor_ratio"] == 0.83
    assert restored.adapter["adaptations"] == [change]
    np.testing.assert_array_equal(restored.nucleus, [0.25, 0.75])
    with pytest.raises(CheckpointError, match="disagree on whether the mesh adapts"):
        restore(PhaseFieldStepper(scene, mesh=state.build_mesh()),
                load_checkpoint(tmp_path / "adaptive.h5", scene))


# -- bad input ---------------------------------------------------------------------------------
def _expect_error(path, scene, fragment):
    before = path.read_bytes() if path.exists() else None
    with pytest.raises(CheckpointError, match=fragment) as info:
        load_checkpoint(path, scene)
    message = str(info.value)
    assert len(message.splitlines()) == 1, message
    assert (path.read_bytes() if path.exists() else None) == before  # left as it was
    return message


@pytest.fixture
def copy_of_checkpoint(reference, tmp_path):
    path = tmp_path / "checkpoint.h5"
    path.write_bytes(reference[1].read_bytes())
    return path


def test_checkpoint_of_another_scene_is_refused(copy_of_checkpoint):
    other = quick_slit(*SCENE, "phase_field.alpha2=2e-3")
    message = _expect_error(copy_of_checkpoint, other, "written for another scene")
    assert "phase_field.alpha2 = 0.001 there, 0.002 here" in message


def test_missing_checkpoint(tmp_path, scene):
    _expect_error(tmp_path / "nope.h5", scene, "does not exist")


def test_garbage_checkpoint(tmp_path, scene):
    path = tmp_path / "checkpoint.h5"
    path.write_bytes(os.urandom(10_000))
    _expect_error(path, scene, "is not an HDF5 file")


def test_truncated_checkpoint(copy_of_checkpoint, scene):
    data = copy_of_checkpoint.read_bytes()
    copy_of_checkpoint.write_bytes(data[: len(data) // 2])
    _expect_error(copy_of_checkpoint, scene, "truncated or corrupt")


def test_flipped_bytes_in_a_field_are_detected(copy_of_checkpoint, scene):
    with h5py.File(copy_of_checkpoint) as f:
        offset = f["fields/z"].id.get_chunk_info(0).byte_offset
    data = bytearray(copy_of_checkpoint.read_bytes())
    data[offset + 64] ^= 0xFF
    copy_of_checkpoint.write_bytes(bytes(data))
    _expect_error(copy_of_checkpoint, scene, "truncated or corrupt")


def test_newer_checkpoint_format(copy_of_checkpoint, scene):
    with h5py.File(copy_of_checkpoint, "a") as f:
        f.attrs["format_version"] = FORMAT_VERSION + 1
    _expect_error(copy_of_checkpoint, scene, "newer than this ngfrac reads")


def test_results_file_is_not_a_checkpoint(tmp_path, scene):
    from ngfrac.io.results import ResultsWriter
    path = tmp_path / "results.h5"
    ResultsWriter(path, scene).close()
    _expect_error(path, scene, "not an ngfrac checkpoint")


def test_failed_write_keeps_the_previous_checkpoint(copy_of_checkpoint, scene, monkeypatch):
    """A full disk: the write fails with a clear error; the old checkpoint stays usable."""
    before = copy_of_checkpoint.read_bytes()

    def disk_full(self, group):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(MeshArrays, "write", disk_full)
    stepper = PhaseFieldStepper(scene)
    with pytest.raises(CheckpointError, match="No space left on device.*previous checkpoint is "
                                              "unchanged"):
        save_checkpoint(stepper, copy_of_checkpoint)
    assert copy_of_checkpoint.read_bytes() == before
    assert not copy_of_checkpoint.with_suffix(".tmp").exists()


# -- SIGKILL -----------------------------------------------------------------------------------
CHILD = textwrap.dedent("""
    import ngsolve as ngs
    ngs.SetNumThreads(1)
    from ngfrac.testing.scenes import quick_slit
    from ngfrac.io.checkpoint import save_checkpoint
    from ngfrac.solve.stepper import PhaseFieldStepper

    stepper = PhaseFieldStepper(quick_slit(*{scene!r}))
    while True:  # killed by the test; would run on to the scene's end time
        stepper.step(diagnose=False)
        if stepper.k % 2 == 0:
            save_checkpoint(stepper, {path!r})
            print(stepper.k, flush=True)
""")


def test_sigkill_leaves_a_checkpoint_that_restarts_exactly(tmp_path, scene, reference):
    records, _ = reference
    path = tmp_path / "checkpoint.h5"
    code = CHILD.format(scene=SCENE, path=str(path))
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True,
                             cwd=ROOT)
    try:
        for line in child.stdout:
            if int(line) >= 6:
                break
        else:
            pytest.fail(f"the child run ended early with status {child.wait()}")
        # Kill at some moment of the following steps: often while a checkpoint is written.
        time.sleep(0.05 + 0.3 * np.random.default_rng().random())
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait()
    assert child.returncode == -signal.SIGKILL
    stepper = resume(path, scene)
    restarted_at = stepper.k
    assert 6 <= restarted_at < N_STEPS and restarted_at % 2 == 0
    _assert_same_history(_continue(stepper), records, restarted_at + 1)


def test_restart_on_a_curved_mesh_is_curved_again(tmp_path):
    """Plate with a hole (OCC, P2: a curved mesh): the mesh restored from a checkpoint is curved
    again (the Netgen geometry numbers of its boundaries are stored), so the restart gives the
    next steps of the uninterrupted run. Restored straight (before), its area was 4.8e-3 too
    large (the hole's chords) and E_el differed at the first step after the restart."""
    from ngfrac.scene import Scene
    import ngsolve as ngs

    plate = [{"type": "rectangle", "corner": [0, 0], "size": [2, 1]},
             {"type": "circle", "center": [1, 0.5], "radius": 0.2, "op": "cut"}]
    scene = Scene.from_dict({
        "geometry": {"kind": "occ", "shapes": plate, "mesh_size": 0.1,
                     "boundaries": [{"name": "bottom", "normal": [0, -1]},
                                    {"name": "top", "normal": [0, 1]}]},
        "phase_field": {"epsilon": 0.1, "alpha2": 1e-3}, "material": {"mu": 1.0, "gamma": 1.0},
        "cracks": [{"points": [[0.0, 0.5], [0.5, 0.5]]}],
        "loads": [{"boundary": "top", "value": "2*t"}, {"boundary": "bottom", "value": "-2*t"}],
        "time": {"dt": 0.05, "t_end": 0.2}, "discretization": {"order": 2},
        "output": {"vtk_every": 0}})
    stepper = PhaseFieldStepper(scene)
    reference = {}
    while stepper.k < 4:
        record = stepper.step()
        reference[record.step] = record
        if stepper.k == 2:
            save_checkpoint(stepper, tmp_path / "checkpoint.h5")
    area = ngs.Integrate(1, stepper.mesh)
    assert abs(area - (2 - np.pi * 0.2 ** 2)) < 1e-4  # curved (straight: 4.8e-3 more)
    restarted = resume(tmp_path / "checkpoint.h5", scene)
    assert restarted.mesh.GetCurveOrder() == 2
    assert ngs.Integrate(1, restarted.mesh) == pytest.approx(area, rel=1e-13)
    while restarted.k < 4:
        record = restarted.step()
        want = reference[record.step]
        for name in ("E_el", "E_surf", "E_total", "crack_length", "tip_x", "tip_y"):
            assert getattr(record, name) == pytest.approx(getattr(want, name), rel=1e-10,
                                                          abs=1e-14), f"step {record.step}: {name}"
