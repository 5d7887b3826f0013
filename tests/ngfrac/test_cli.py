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
