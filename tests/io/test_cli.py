"""The command line: exit codes, one-line errors without traceback, outputs.

Most commands run in this process (:func:`ngfrac_here`, ~0.05 s); those that only a new
process shows run as ``python -m ngfrac`` (:func:`ngfrac`, ~0.9 s, most of it importing
NGSolve): its exit status, nothing else on stderr, no crash (a run that segfaulted), a restart
that knows only the folder."""
import re
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import pytest

from ngfrac import cli, load_scene, runner
from ngfrac.geometry.domains import MeshingError, Rectangle
from ngfrac.io.checkpoint import CheckpointError
from ngfrac.io.hdf5 import ResultsError
from ngfrac.io.output import OutputError
from ngfrac.scene import SceneError
from ngfrac.solve.communicator import ParallelError
from ngfrac.solve.u_problem import SolverError

from ngfrac.testing.bad_inputs import ALL_CASES, bad_scene_file
from ngfrac.testing.command_line import ngfrac_here

ROOT = Path(__file__).resolve().parents[2]
SLIT = str(ROOT / "demos" / "mode3_slit.toml")
QUICK = ["--set", "phase_field.epsilon=0.08", "--set", "geometry.mesh_size=0.04",
         "--set", "time.t_end=0.002", "--no-progress"]


def ngfrac(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "ngfrac", *args], capture_output=True, text=True,
                          cwd=cwd)


def test_check_valid_scene(capfd):
    result = ngfrac_here(capfd, "check", SLIT)
    assert result.returncode == 0, result.stderr
    assert "is valid" in result.stdout


@pytest.mark.parametrize("override, fragment", [
    ("phase_field.epsilon=-1", "phase_field.epsilon"),
    ("time.dtt=1", "did you mean 'time.dt'"),
    ("loads.0.boundary=\"nowhere\"", "not a boundary"),
    ("time.t_end=\"soon\"", "must be a number"),
])
def test_bad_scene_exits_2_with_one_line(override, fragment, capfd):
    result = ngfrac_here(capfd, "check", SLIT, "--set", override)
    assert result.returncode == 2
    assert fragment in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
    assert "Traceback" not in result.stderr


def test_missing_scene_file(tmp_path):
    """In a new process: ``python -m ngfrac`` exits with main's status, without traceback."""
    result = ngfrac("run", str(tmp_path / "nope.toml"), "--out", str(tmp_path / "o"))
    assert result.returncode == 2 and "does not exist" in result.stderr
    assert "Traceback" not in result.stderr


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    """A finished run of the slit (QUICK, plots included) and its CompletedProcess (a new
    process: the exit status of a run that went well)."""
    out = tmp_path_factory.mktemp("quick") / "run"
    return out, ngfrac("run", SLIT, "--out", str(out), *QUICK)


def test_run_writes_outputs_and_refuses_to_overwrite(quick_run, capfd):
    out, result = quick_run
    assert result.returncode == 0, result.stderr
    for name in ("history.csv", "scene.toml", "history.png", "crack.png", "vtk/fields.pvd"):
        assert (out / name).exists(), name
    header = (out / "history.csv").read_text().splitlines()[0].split(",")
    contract = "step,t,wall_s,nv,ndof,hmin,hmax,E_el,E_surf,E_total,crack_length,tip_x,tip_y".split(",")
    assert header[: len(contract)] == contract
    before = (out / "history.csv").read_text()
    again = ngfrac_here(capfd, "run", SLIT, "--out", str(out), *QUICK)
    assert again.returncode == 2 and "--overwrite" in again.stderr
    assert (out / "history.csv").read_text() == before  # nothing lost
    # a run with --overwrite into it: tests/io/test_output_folder.py (what it keeps and removes)


def test_restart_continues_a_killed_run_exactly(tmp_path, capfd):
    """A run of 6 steps killed after its last one (an error raised there: a finished run writes
    a checkpoint at its end), its last checkpoint at step 4; ``ngfrac run --restart`` in a new
    process (it knows only the folder) continues it to 8 steps: as 8 straight. The runs before
    the restart are made in this process (they were three processes: the killed run was a
    finished 6-step run given the step-4 checkpoint of a third, 4-step run)."""
    common = ["--set", "phase_field.epsilon=0.08", "--set", "geometry.mesh_size=0.04",
              "--set", "adaptivity.enabled=false", "--set", "output.checkpoint_every=4",
              "--no-progress", "--no-plots"]
    straight, broken = tmp_path / "straight", tmp_path / "broken"
    assert ngfrac_here(capfd, "run", SLIT, "--out", straight, "--set", "time.t_end=0.004",
                       *common).returncode == 0
    sets = [value for flag, value in zip(common, common[1:]) if flag == "--set"]

    def kill(stepper):
        if stepper.k == 6:  # its rows written, its checkpoints (step 4) too
            raise RuntimeError("killed")

    with pytest.raises(RuntimeError, match="killed"):
        runner.run_scene(load_scene(SLIT, [*sets, "time.t_end=0.003"]), broken, plots=False,
                         on_step=kill)
    with h5py.File(broken / "checkpoint.h5", "r") as f:
        assert int(f.attrs["k"]) == 4  # rows 5 and 6 come after it
    again = ngfrac("run", "--restart", str(broken), "--set", "time.t_end=0.004", *common[-2:])
    assert again.returncode == 0, again.stderr
    a = (straight / "history.csv").read_text().splitlines()
    b = (broken / "history.csv").read_text().splitlines()
    assert len(a) == len(b) == 10
    cols = a[0].split(",")
    keep = [i for i, c in enumerate(cols) if c not in ("wall_s", "step_s", "solve_s", "adapt_s")]
    for row_a, row_b in zip(a[1:], b[1:]):
        va, vb = row_a.split(","), row_b.split(",")
        for i in keep:
            x, y = float(va[i]), float(vb[i])
            assert x == pytest.approx(y, rel=1e-9, abs=1e-14, nan_ok=True), (cols[i], x, y)


def test_restart_without_checkpoint_is_a_clear_error(tmp_path, capfd):
    result = ngfrac_here(capfd, "run", "--restart", str(tmp_path))
    assert result.returncode == 2
    assert "Traceback" not in result.stderr


def test_plot_command(quick_run, tmp_path):
    """In a new process: the exit status of ``python -m ngfrac plot`` (tests/io/
    test_output_folder.py and tests/test_docs.py plot in theirs)."""
    assert quick_run[1].returncode == 0, quick_run[1].stderr
    out = tmp_path / "run"
    shutil.copytree(quick_run[0], out)  # the other tests read the original
    result = ngfrac("plot", str(out))
    assert result.returncode == 0, result.stderr
    assert (out / "plots" / "history.png").exists()
    assert list((out / "plots").glob("z_t*.png"))


# -- bad input is refused before anything is written --------------------------------------------


@pytest.fixture(scope="module")
def earlier_run(tmp_path_factory, quick_run):
    """A finished run folder, with a file of the user's in it: a copy of :func:`quick_run`'s
    (its plots included; it was a run of its own, the same without plots)."""
    assert quick_run[1].returncode == 0, quick_run[1].stderr
    out = tmp_path_factory.mktemp("earlier") / "run"
    shutil.copytree(quick_run[0], out)
    (out / "my_notes.txt").write_text("mine")
    return out


def snapshot(folder):
    return {str(p.relative_to(folder)): (p.stat().st_mtime_ns, p.read_bytes())
            for p in sorted(folder.rglob("*")) if p.is_file()}


def one_error_line(err, match):
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("ngfrac: error: ")
    assert re.search(match, lines[0]), lines[0]


@pytest.mark.parametrize("case", ALL_CASES)
def test_bad_input_is_refused_by_check_and_by_run_into_an_earlier_run(case, earlier_run, tmp_path,
                                                                      capfd):
    path, match = bad_scene_file(case, tmp_path)
    before = snapshot(earlier_run)
    assert cli.main(["check", str(path)]) == 2
    one_error_line(capfd.readouterr().err, match)
    for flags in ([], ["--overwrite"]):
        assert cli.main(["run", str(path), "--out", str(earlier_run), "--no-progress", *flags]) == 2
        one_error_line(capfd.readouterr().err, match)
        assert snapshot(earlier_run) == before, flags


def test_repeated_crack_point_no_longer_segfaults(earlier_run, tmp_path):
    """It was exit 139 and no message (Netgen, a line from a point to itself): in a new
    process, which a segfault ends."""
    before = snapshot(earlier_run)
    result = ngfrac("run", SLIT, "--out", str(earlier_run), "--overwrite", *QUICK,
                    "--set", "cracks.0.points=[[0.0, 0.5], [0.3, 0.5], [0.3, 0.5]]")
    assert result.returncode == 2
    one_error_line(result.stderr, r"cracks\[0\]: point 2 repeats point 1 \(0.3, 0.5\)")
    assert snapshot(earlier_run) == before


def test_meshing_failure_during_the_run_exits_3_in_one_line(tmp_path, monkeypatch, capfd):
    """A Netgen failure (here forced: a crack that runs back, behind the scene's checks) is a
    MeshingError: one line, exit 3."""
    original = Rectangle.build_mesh

    def failing(self, maxh, cracks=()):
        return original(self, maxh, [[[0.0, 0.5], [0.3, 0.5], [0.1, 0.5]]])

    monkeypatch.setattr(Rectangle, "build_mesh", failing)
    code = cli.main(["run", SLIT, "--out", str(tmp_path / "run"), *QUICK, "--no-plots",
                     "--set", "adaptivity.enabled=false"])
    assert code == 3
    one_error_line(capfd.readouterr().err, r"Netgen could not mesh the rectangle .*; run ngfrac check")


def _raising(error):
    def run_scene(*args, **kwargs):
        raise error
    return run_scene


@pytest.mark.parametrize("error, status", [
    (CheckpointError("checkpoint 'x.h5' was written for another scene"), 2),
    (ResultsError("results file 'results.h5' was written for another scene"), 2),
    (OutputError("the run folder is not empty"), 2), (SceneError("time.dt must be > 0"), 2),
    (ParallelError("an MPI run needs 3 or more processes"), 2),
    (SolverError("the z-solve failed"), 3), (MeshingError("Netgen could not mesh it"), 3),
    (RuntimeError("an unforeseen error"), 1)], ids=lambda value: type(value).__name__)
def test_an_mpi_job_ends_with_the_exit_code_of_one_process(error, status, tmp_path, monkeypatch,
                                                           capfd):
    """An MPI job's guard ends it with runner.exit_code(error) (checked here without mpirun):
    the status ngfrac run gives for the same error on one process (2 for a bad checkpoint)."""
    assert runner.exit_code(error) == status
    monkeypatch.setattr(runner, "run_scene", _raising(error))
    arguments = ["run", SLIT, "--out", str(tmp_path / "run"), *QUICK, "--no-plots"]
    if status == 1:  # not the CLI's to name: a traceback, and Python's status 1
        with pytest.raises(RuntimeError, match="unforeseen"):
            cli.main(arguments)
        return
    assert cli.main(arguments) == status
    one_error_line(capfd.readouterr().err, re.escape(str(error)))

# -- resolution warnings ------------------------------------------------------------------------

CAP_100 = ["--set", "adaptivity.max_vertices=100"]
WARNING_100 = "ngfrac: warning: adaptivity.max_vertices = 100 is below the ~"


def test_check_warns_in_one_line_and_strict_exits_2(capfd):
    assert cli.main(["check", SLIT, *CAP_100]) == 0
    captured = capfd.readouterr()
    assert captured.err.strip().splitlines() == [captured.err.strip()]
    assert captured.err.startswith(WARNING_100) and "is valid" in captured.out
    assert cli.main(["check", SLIT, *CAP_100, "--strict"]) == 2
    lines = capfd.readouterr().err.strip().splitlines()
    assert lines[0].startswith(WARNING_100)
    assert lines[1] == "ngfrac: error: --strict: 1 resolution warning(s) above; fix the scene or drop --strict"
    assert cli.main(["check", SLIT, "--strict"]) == 0  # the demo resolves its crack


def test_run_warns_once_and_strict_writes_nothing(tmp_path, capfd):
    coarse = [*QUICK, "--set", "geometry.mesh_size=0.05", "--set", "adaptivity.enabled=false",
              "--no-plots"]  # above epsilon/2 = 0.04
    assert cli.main(["run", SLIT, "--out", str(tmp_path / "strict"), *coarse, "--strict"]) == 2
    assert not (tmp_path / "strict").exists()
    assert "ngfrac: error: --strict" in capfd.readouterr().err
    assert cli.main(["run", SLIT, "--out", str(tmp_path / "run"), *coarse]) == 0
    err = capfd.readouterr().err
    assert err.count("ngfrac: warning: geometry.mesh_size = 0.05 is above epsilon/2 = 0.04") == 1
    assert (tmp_path / "run" / "history.csv").exists()


def test_progress_bar_counts_the_time_steps(tmp_path, capfd):
    """The bar (the Progress writer) ends at the scene's last tick, on stderr."""
    overrides = [arg for arg in QUICK if arg != "--no-progress"]
    result = ngfrac_here(capfd, "run", SLIT, "--out", str(tmp_path / "run"), *overrides,
                         "--set", "adaptivity.enabled=false", "--set", "discretization.order=1",
                         "--no-plots")
    assert result.returncode == 0, result.stderr
    assert re.search(r"mode3_slit: 100%.*\b4/4 \[", result.stderr), result.stderr
    assert "tip_x=" in result.stderr
