"""The command line: exit codes, one-line errors without traceback, outputs."""
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SLIT = str(ROOT / "demos" / "mode3_slit.toml")
QUICK = ["--set", "phase_field.epsilon=0.08", "--set", "geometry.mesh_size=0.04",
         "--set", "time.t_end=0.002", "--no-progress"]


def ngfrac(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "ngfrac", *args], capture_output=True, text=True,
                          cwd=cwd)


def test_check_valid_scene():
    result = ngfrac("check", SLIT)
    assert result.returncode == 0, result.stderr
    assert "is valid" in result.stdout


@pytest.mark.parametrize("override, fragment", [
    ("phase_field.epsilon=-1", "phase_field.epsilon"),
    ("time.dtt=1", "did you mean 'time.dt'"),
    ("loads.0.boundary=\"nowhere\"", "not a boundary"),
    ("time.t_end=\"soon\"", "must be a number"),
])
def test_bad_scene_exits_2_with_one_line(override, fragment):
    result = ngfrac("check", SLIT, "--set", override)
    assert result.returncode == 2
    assert fragment in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
    assert "Traceback" not in result.stderr


def test_missing_scene_file(tmp_path):
    result = ngfrac("run", str(tmp_path / "nope.toml"), "--out", str(tmp_path / "o"))
    assert result.returncode == 2 and "does not exist" in result.stderr
    assert "Traceback" not in result.stderr


def test_run_writes_outputs_and_refuses_to_overwrite(tmp_path):
    out = tmp_path / "run"
    result = ngfrac("run", SLIT, "--out", str(out), *QUICK)
    assert result.returncode == 0, result.stderr
    for name in ("history.csv", "scene.toml", "history.png", "crack.png", "vtk/fields.pvd"):
        assert (out / name).exists(), name
    header = (out / "history.csv").read_text().splitlines()[0].split(",")
    contract = "step,t,wall_s,nv,ndof,hmin,hmax,E_el,E_surf,E_total,crack_length,tip_x,tip_y".split(",")
    assert header[: len(contract)] == contract
    before = (out / "history.csv").read_text()
    again = ngfrac("run", SLIT, "--out", str(out), *QUICK)
    assert again.returncode == 2 and "--overwrite" in again.stderr
    assert (out / "history.csv").read_text() == before  # nothing lost
    assert ngfrac("run", SLIT, "--out", str(out), "--overwrite", *QUICK).returncode == 0


def test_restart_continues_a_killed_run_exactly(tmp_path):
    """Run 6 steps with a checkpoint at 4; continue from it to 8 steps, compare with 8 straight."""
    common = ["--set", "phase_field.epsilon=0.08", "--set", "geometry.mesh_size=0.04",
              "--set", "adaptivity.enabled=false", "--set", "output.checkpoint_every=4",
              "--no-progress", "--no-plots"]
    straight, broken = tmp_path / "straight", tmp_path / "broken"
    assert ngfrac("run", SLIT, "--out", str(straight), "--set", "time.t_end=0.004", *common).returncode == 0
    assert ngfrac("run", SLIT, "--out", str(broken), "--set", "time.t_end=0.003", *common).returncode == 0
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


def test_restart_without_checkpoint_is_a_clear_error(tmp_path):
    result = ngfrac("run", "--restart", str(tmp_path))
    assert result.returncode == 2
    assert "Traceback" not in result.stderr


def test_plot_command(tmp_path):
    out = tmp_path / "run"
    assert ngfrac("run", SLIT, "--out", str(out), *QUICK).returncode == 0
    result = ngfrac("plot", str(out))
    assert result.returncode == 0, result.stderr
    assert (out / "plots" / "history.png").exists()
    assert list((out / "plots").glob("z_t*.png"))
