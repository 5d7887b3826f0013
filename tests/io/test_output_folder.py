"""Run folders: the manifest (--overwrite removes only ngfrac's files), run.json and the
results.h5 metadata, restarts, read-only and missing folders, ngfrac --version.

Most commands run in this process (:func:`ngfrac_here`); a new process (:func:`ngfrac`, ~0.9
s, most of it importing NGSolve) where it shows more: the run whose run.json records its
command line and thread count, the restart that knows only the folder, and one refusal each
of ``run`` and ``plot`` (the exit status, nothing else on stderr)."""
import configparser
import contextlib
import datetime
import importlib.metadata
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import pytest

from ngfrac import cli
from ngfrac.io.output import Manifest, OutputError, git_revision, run_metadata
from ngfrac.io.results import open_results
from ngfrac.testing.command_line import ngfrac_here

ROOT = Path(__file__).resolve().parents[2]
SLIT = str(ROOT / "demos" / "mode3_slit.toml")
# P1 on a coarse uniform mesh, 4 steps: the outputs, not the physics, are under test
TINY = ["--set", "phase_field.epsilon=0.08", "--set", "geometry.mesh_size=0.04",
        "--set", "adaptivity.enabled=false", "--set", "discretization.order=1",
        "--set", "time.t_end=0.002", "--set", "output.checkpoint_every=2",
        "--set", "output.vtk_every=2", "--no-progress"]


def ngfrac(*args):
    env = {**os.environ, "NGFRAC_THREADS": "1"}
    return subprocess.run([sys.executable, "-m", "ngfrac", *map(str, args)], capture_output=True,
                          text=True, env=env)


def assert_one_line_error(result, fragment):
    assert result.returncode == 2, (result.returncode, result.stderr)
    assert "Traceback" not in result.stderr, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert fragment in result.stderr, result.stderr


def user_files(folder):
    """Plant a user's files (top level, inside vtk/ and plots/); returns their state."""
    planted = {folder / "notes.txt": "my notes", folder / "vtk" / "mine.vtu": "my own vtu",
               folder / "plots" / "sketch.png": "not a png"}
    for path, text in planted.items():
        path.parent.mkdir(exist_ok=True)
        path.write_text(text)
    return state_of(planted)


def state_of(paths):
    return {path: (path.read_bytes(), path.stat().st_mtime_ns) for path in paths}


def assert_untouched(state):
    for path, (data, mtime) in state.items():
        assert path.exists(), f"{path} was removed"
        assert (path.read_bytes(), path.stat().st_mtime_ns) == (data, mtime), f"{path} changed"


@pytest.fixture(scope="module")
def base_run(tmp_path_factory):
    """One tiny run (with a checkpoint, results.h5, VTK, plots and `ngfrac plot`); the run in
    a new process (run.json records its command line and NGFRAC_THREADS), the plot in this
    one."""
    out = tmp_path_factory.mktemp("base") / "run"
    result = ngfrac("run", SLIT, "--out", out, *TINY)
    assert result.returncode == 0, result.stderr
    assert cli.main(["plot", str(out)]) == 0
    return out


@pytest.fixture
def run_copy(base_run, tmp_path):
    out = tmp_path / "run"
    shutil.copytree(base_run, out)
    return out


@contextlib.contextmanager
def read_only(folder):
    """Make ``folder`` unwritable; root ignores permission bits, so then it is made immutable."""
    def writable():
        probe = folder / ".probe"
        try:
            probe.write_text("")
        except OSError:
            return False
        probe.unlink()
        return True

    immutable = False
    folder.chmod(0o555)
    try:
        if writable():
            immutable = subprocess.run(["chattr", "+i", str(folder)],
                                       capture_output=True).returncode == 0
            if not immutable or writable():
                pytest.skip("cannot make a folder read-only here (root, and no chattr)")
        yield
    finally:
        if immutable:
            subprocess.run(["chattr", "-i", str(folder)], capture_output=True)
        folder.chmod(0o755)


# -- version ----------------------------------------------------------------------------------
def test_version_comes_from_the_package_metadata(capfd):
    import ngfrac as package

    setup = configparser.ConfigParser()
    setup.read(ROOT / "setup.cfg")
    version = setup["metadata"]["version"]
    assert importlib.metadata.version("ngfrac") == package.__version__ == version
    result = ngfrac_here(capfd, "--version")
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"ngfrac {version} (NGSolve ")


# -- metadata ---------------------------------------------------------------------------------
def test_run_json_records_the_environment(base_run):
    text = (base_run / "run.json").read_text()
    info = json.loads(text, parse_constant=lambda name: pytest.fail(f"run.json holds {name}"))
    assert info["format"] == "ngfrac-run"
    assert info["ngfrac_version"] == importlib.metadata.version("ngfrac")
    import ngsolve
    assert info["ngsolve_version"] == ngsolve.__version__
    assert info["python_version"] == ".".join(map(str, sys.version_info[:3]))
    assert info["threads"] == 1  # NGFRAC_THREADS=1 in ngfrac()
    assert info["command_line"][1:] == ["run", SLIT, "--out", str(base_run), *TINY]
    started = datetime.datetime.fromisoformat(info["started"])
    assert started.utcoffset() == datetime.timedelta(0)
    age = datetime.datetime.now(datetime.timezone.utc) - started
    assert datetime.timedelta(0) <= age < datetime.timedelta(hours=1)
    assert info["restarts"] == []
    from ngfrac import load_scene, resolution_warnings
    overrides = [value for flag, value in zip(TINY[:-1], TINY[1:]) if flag == "--set"]
    assert info["resolution_warnings"] == resolution_warnings(load_scene(SLIT, overrides))
    commit, dirty = git_revision()
    assert (info["git_commit"], info["git_dirty"]) == (commit, dirty)
    with h5py.File(base_run / "results.h5", "r") as f:
        assert f.attrs["format"] == "ngfrac-results"  # not replaced by run.json's marker
        for key in ("ngfrac_version", "ngsolve_version", "python_version", "started", "threads"):
            assert f.attrs[key] == info[key], key
        assert json.loads(f.attrs["resolution_warnings"]) == info["resolution_warnings"]
        assert json.loads(f.attrs["command_line"]) == info["command_line"]


def test_git_revision_of_this_checkout():
    try:
        head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout, or no git")
    commit, dirty = git_revision()
    assert commit == head and isinstance(dirty, bool)


def test_metadata_without_git(monkeypatch):
    monkeypatch.setenv("PATH", "/nonexistent")  # no git executable
    info = run_metadata(["ngfrac", "run"])
    assert info["git_commit"] is None and info["git_dirty"] is None
    assert info["command_line"] == ["ngfrac", "run"]
    json.dumps(info, allow_nan=False)


def test_restart_updates_the_scene_and_logs_itself(run_copy):
    """In a new process: it knows only the folder, and run.json records its command line."""
    result = ngfrac("run", "--restart", run_copy, "--set", "time.t_end=0.003", "--no-progress",
                    "--no-plots")
    assert result.returncode == 0, result.stderr
    assert 't_end = 0.003' in (run_copy / "scene.toml").read_text()
    assert open_results(run_copy / "results.h5").scene.time.t_end == 0.003
    with h5py.File(run_copy / "checkpoint.h5", "r") as f:  # written again at step 6
        assert int(f.attrs["k"]) == 6 and "t_end = 0.003" in f["scene"].asstr()[()]
    info = json.loads((run_copy / "run.json").read_text())
    assert info["command_line"][1] == "run" and "--restart" not in info["command_line"]
    (restart,) = info["restarts"]
    assert restart["changed"] == {"time.t_end": [0.002, 0.003]}
    assert restart["from_step"] == 4 and restart["from_t"] == 0.002
    assert restart["command_line"][1:3] == ["run", "--restart"]
    with h5py.File(run_copy / "results.h5", "r") as f:
        assert json.loads(f.attrs["restarts"]) == info["restarts"]
    assert "vtk/fields_00003.vtu" in Manifest.load(run_copy).entries  # t = 0.003: a new file


# -- the manifest -----------------------------------------------------------------------------
def test_manifest_lists_every_file_written(base_run):
    manifest = Manifest.load(base_run)
    written = {p.relative_to(base_run).as_posix() + ("/" if p.is_dir() else "")
               for p in base_run.rglob("*")} - {"manifest.json"}
    assert set(manifest.entries) == written


def test_overwrite_keeps_the_users_files(run_copy, capfd):
    mine = user_files(run_copy)
    longer = {p.name for p in (run_copy / "vtk").glob("fields_*.vtu")}
    result = ngfrac_here(capfd, "run", SLIT, "--out", run_copy, *TINY,
                         "--set", "time.t_end=0.001", "--overwrite", "--no-plots")
    assert result.returncode == 0, result.stderr
    assert_untouched(mine)
    shorter = {p.name for p in (run_copy / "vtk").glob("fields_*.vtu")}
    assert shorter < longer  # the earlier run's later snapshots are gone
    for name in ("history.png", "crack.png", "plots/history.png"):
        assert not (run_copy / name).exists(), name
    assert (run_copy / "plots").is_dir()  # ngfrac made it, but it holds a user's file
    assert "t_end = 0.001" in (run_copy / "scene.toml").read_text()


def test_without_overwrite_nothing_changes(run_copy):
    """In a new process: the refusal is its exit status 2 and one line on stderr."""
    mine = user_files(run_copy)
    ours = state_of(p for p in run_copy.rglob("*") if p.is_file())
    result = ngfrac("run", SLIT, "--out", run_copy, *TINY)
    assert_one_line_error(result, "--overwrite")
    assert_untouched(mine)
    assert_untouched(ours)


def test_folder_of_an_older_run_without_manifest(run_copy, capfd):
    """No manifest: ngfrac's names count as the earlier run's, everything else stays."""
    (run_copy / "manifest.json").unlink()
    for name in ("run.json", "crack_path.csv", "results.xdmf", "results_mesh_000.xdmf"):
        (run_copy / name).unlink()  # older runs wrote none of these
    mine = user_files(run_copy)
    assert_one_line_error(ngfrac_here(capfd, "run", SLIT, "--out", run_copy, *TINY),
                          "--overwrite")
    result = ngfrac_here(capfd, "run", SLIT, "--out", run_copy, *TINY, "--overwrite",
                         "--no-plots")
    assert result.returncode == 0, result.stderr
    assert_untouched(mine)
    assert not (run_copy / "plots" / "history.png").exists()
    assert "run.json" in Manifest.load(run_copy).entries


def test_users_file_at_an_ngfrac_name_is_refused(run_copy, capfd):
    """A results.h5 the manifest does not list is the user's: refused before anything goes."""
    manifest = Manifest.load(run_copy)
    manifest.entries.remove("results.h5")
    manifest.save()
    mine = state_of([run_copy / "results.h5"])
    history = (run_copy / "history.csv").read_text()
    result = ngfrac_here(capfd, "run", SLIT, "--out", run_copy, *TINY, "--overwrite")
    assert_one_line_error(result, "results.h5")
    assert_untouched(mine)
    assert (run_copy / "history.csv").read_text() == history


def test_writing_refuses_an_unlisted_file_and_forgets_unmade_ones(tmp_path):
    manifest = Manifest(tmp_path)
    (tmp_path / "history.csv").write_text("mine")
    with pytest.raises(OutputError, match="not written by ngfrac"):
        with manifest.writing("history.csv"):
            pass
    with manifest.writing("a.txt", "b.txt", "sub/"):
        (tmp_path / "a.txt").write_text("")
        assert set(Manifest.load(tmp_path).entries) == {"a.txt", "b.txt", "sub/"}  # listed first
    assert Manifest.load(tmp_path).entries == ["a.txt"]
    (tmp_path / "sub").mkdir()
    with manifest.writing("sub/"):  # it existed: not ngfrac's
        pass
    assert manifest.entries == ["a.txt"]


# -- unusable folders -------------------------------------------------------------------------
def test_read_only_folder_is_one_line(tmp_path, capfd):
    out = tmp_path / "ro"
    out.mkdir()
    mine = user_files(out)
    with read_only(out):
        result = ngfrac_here(capfd, "run", SLIT, "--out", out, *TINY)
    assert_one_line_error(result, "cannot write")
    assert_untouched(mine)
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "plots", "vtk"]


def test_overwrite_in_a_read_only_folder_removes_nothing(run_copy, capfd):
    before = {p: p.stat().st_mtime_ns for p in run_copy.rglob("*")}
    with read_only(run_copy):
        result = ngfrac_here(capfd, "run", SLIT, "--out", run_copy, *TINY, "--overwrite")
        restart = ngfrac_here(capfd, "run", "--restart", run_copy, "--set", "time.t_end=0.003",
                              "--no-progress")
    assert_one_line_error(result, "cannot write")
    assert_one_line_error(restart, "cannot write")
    assert {p: p.stat().st_mtime_ns for p in run_copy.rglob("*")} == before


def test_plot_into_a_read_only_run_folder(run_copy, capfd):
    shutil.rmtree(run_copy / "plots")
    manifest = Manifest.load(run_copy)
    manifest.entries = [e for e in manifest.entries if not e.startswith("plots/")]
    manifest.save()
    before = {p: p.stat().st_mtime_ns for p in run_copy.rglob("*")}
    with read_only(run_copy):
        result = ngfrac_here(capfd, "plot", run_copy)
    assert_one_line_error(result, "cannot write")
    assert {p: p.stat().st_mtime_ns for p in run_copy.rglob("*")} == before


def test_plot_keeps_users_plots_and_lists_its_own(run_copy, capfd):
    mine = user_files(run_copy)
    result = ngfrac_here(capfd, "plot", run_copy)
    assert result.returncode == 0, result.stderr
    assert_untouched(mine)
    entries = Manifest.load(run_copy).entries
    assert "plots/history.png" in entries and "plots/sketch.png" not in entries


def test_plot_of_a_missing_folder(tmp_path, capfd):
    # the first in a new process: the refusal is its exit status 2 and one line on stderr
    assert_one_line_error(ngfrac("plot", tmp_path / "nowhere"), "does not exist")
    (tmp_path / "empty").mkdir()
    assert_one_line_error(ngfrac_here(capfd, "plot", tmp_path / "empty"), "not a run folder")


def test_resolution_warnings_are_recorded_in_the_run_folder(tmp_path, capfd):
    """A vertex cap far below what the sizes need: the warning goes to stderr, run.json and
    results.h5 (the run itself goes on)."""
    out = tmp_path / "coarse"
    result = ngfrac_here(capfd, "run", SLIT, "--out", out, *TINY[:-1],
                         "--set", "adaptivity.enabled=true", "--set", "adaptivity.max_vertices=100",
                         "--set", "time.t_end=0.001", "--no-plots", "--no-progress")
    assert result.returncode == 0, result.stderr
    assert "ngfrac: warning: adaptivity.max_vertices = 100" in result.stderr
    info = json.loads((out / "run.json").read_text())
    assert any("max_vertices = 100" in line for line in info["resolution_warnings"])
    with h5py.File(out / "results.h5", "r") as f:
        assert json.loads(f.attrs["resolution_warnings"]) == info["resolution_warnings"]


# -- writers: the run's files from a script's own loop ------------------------------------------
TIMING = {"wall_s", "step_s", "solve_s", "adapt_s"}


def tiny_scene():
    from ngfrac import load_scene

    return load_scene(SLIT, [value for flag, value in zip(TINY[:-1:2], TINY[1::2])
                             if flag == "--set"])


def history_without_timings(folder):
    import csv

    with open(folder / "history.csv", newline="") as handle:
        return [{k: v for k, v in row.items() if k not in TIMING} for row in csv.DictReader(handle)]


def test_a_script_loop_with_the_default_writers_writes_what_run_scene_writes(tmp_path):
    """The user guide's example (Python API): the same files, manifest and history."""
    from ngfrac import PhaseFieldStepper, run_scene
    from ngfrac.io.writers import RunFolder, Writers, default_writers

    scene = tiny_scene()
    run_scene(scene, tmp_path / "run", plots=False)
    folder = RunFolder.create(tmp_path / "script", scene, overwrite=True)
    stepper = PhaseFieldStepper(scene)
    with Writers(default_writers(folder, scene, plots=False)) as writers:
        writers.start(stepper, stepper.record())
        for record in stepper.run():
            writers.record(stepper, record)
        writers.finish(stepper)
    run, script = tmp_path / "run", tmp_path / "script"
    assert Manifest.load(script).entries == Manifest.load(run).entries
    assert sorted(p.relative_to(script) for p in script.rglob("*")) == \
        sorted(p.relative_to(run) for p in run.rglob("*"))
    assert history_without_timings(script) == history_without_timings(run)
    assert (script / "crack_path.csv").read_text() == (run / "crack_path.csv").read_text()
    assert list(open_results(script / "results.h5").snapshot_steps()) == [0, 2, 4]


def test_run_scene_calls_more_writers_in_order(tmp_path):
    from ngfrac import run_scene
    from ngfrac.io.writers import Writer

    class Log(Writer):
        def __init__(self):
            self.calls = []

        def start(self, stepper, record):
            self.calls.append(("start", record.step))

        def record(self, stepper, record):
            self.calls.append(("record", record.step))

        def finish(self, stepper):
            self.calls.append(("finish", stepper.k))

        def close(self):
            self.calls.append(("close",))

    log = Log()
    run_scene(tiny_scene(), tmp_path / "run", plots=False, writers=[log])
    assert log.calls == [("start", 0), ("record", 1), ("record", 2), ("record", 3),
                         ("record", 4), ("finish", 4), ("close",)]
