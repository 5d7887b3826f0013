"""A run folder is self-contained and a finished run can be extended (issue 28, items 1-2):
a scene that reads its CAD file by a relative path restarts from its folder alone, in 2D and
3D; a finished run continued to a later time.t_end equals the longer run."""
import csv
import hashlib
import json
import shutil
from pathlib import Path

import pytest

from ngfrac import cli

pytestmark = pytest.mark.usefixtures("one_thread")

SCENE_2D = """
name = "plate"
[model]
kind = "mode3"
[material]
mu = 1.0
[phase_field]
epsilon = 0.1
alpha2 = 1e-3
[geometry]
kind = "occ"
file = "plate.step"
mesh_size = 0.25
[[geometry.boundaries]]
name = "bottom"
normal = [0.0, -1.0]
[[geometry.boundaries]]
name = "top"
normal = [0.0, 1.0]
[[loads]]
boundary = "bottom"
value = "0"
[[loads]]
boundary = "top"
value = "t"
[time]
dt = 0.001
t_end = 0.002
[discretization]
order = 1
[output]
vtk_every = 0
checkpoint_every = 1
"""

SCENE_3D = """
name = "plate3d"
[model]
kind = "elasticity_3d"
[material]
E = 1.0
nu = 0.3
[phase_field]
epsilon = 0.1
alpha2 = 1e-3
[geometry]
kind = "occ"
file = "plate3d.step"
mesh_size = 0.5
[[geometry.boundaries]]
name = "bottom"
normal = [0.0, -1.0, 0.0]
[[geometry.boundaries]]
name = "top"
normal = [0.0, 1.0, 0.0]
[[loads]]
boundary = "bottom"
value = ["0", "0", "0"]
[[loads]]
boundary = "top"
value = ["0", "t", "0"]
[time]
dt = 0.001
t_end = 0.002
[discretization]
order = 1
[output]
vtk_every = 0
checkpoint_every = 2
"""


def write_cad(folder: Path, dim: int) -> None:
    from netgen import occ

    if dim == 2:
        occ.WorkPlane().Rectangle(1, 1).Face().WriteStep(str(folder / "plate.step"))
    else:
        occ.Box((0, 0, 0), (1, 1, 0.25)).WriteStep(str(folder / "plate3d.step"))


def history(folder: Path) -> list[dict[str, str]]:
    with (folder / "history.csv").open() as handle:
        return list(csv.DictReader(handle))


@pytest.mark.parametrize("dim", [2, 3])
def test_restart_of_a_cad_scene_read_by_a_relative_path(dim, tmp_path, monkeypatch, capsys):
    """`ngfrac run scenes/S.toml --out out` from the folder above the scene, then
    `ngfrac run --restart out` from elsewhere, with the original CAD file gone."""
    scenes = tmp_path / "work" / "scenes"
    scenes.mkdir(parents=True)
    name = "plate" if dim == 2 else "plate3d"
    (scenes / f"{name}.toml").write_text(SCENE_2D if dim == 2 else SCENE_3D)
    write_cad(scenes, dim)
    monkeypatch.chdir(tmp_path / "work")
    flags = ["--no-progress", "--no-plots"]
    assert cli.main(["run", f"scenes/{name}.toml", "--out", "out", *flags]) == 0
    out = Path("out")
    copy = out / f"{name}.step"
    assert copy.read_bytes() == (scenes / f"{name}.step").read_bytes()
    stored = (out / "scene.toml").read_text()
    assert f'file = "{name}.step"' in stored, stored
    info = json.loads((out / "run.json").read_text())
    assert info["cad_file"] == {"name": f"{name}.step", "source": f"scenes/{name}.step",
                                "sha256": hashlib.sha256(copy.read_bytes()).hexdigest()}
    assert f"{name}.step" in json.loads((out / "manifest.json").read_text())["files"]
    # the folder alone: the scene's CAD file removed, the folder moved, another directory
    (scenes / f"{name}.step").unlink()
    moved = tmp_path / "elsewhere" / "run"
    moved.parent.mkdir()
    shutil.move("out", moved)
    monkeypatch.chdir(tmp_path)
    capsys.readouterr()
    restart = ["run", "--restart", str(moved.relative_to(tmp_path)), "--set", "time.t_end=0.003",
               *flags]
    code = cli.main(restart)
    assert code == 0, capsys.readouterr().err
    assert [row["step"] for row in history(moved)] == ["0", "1", "2", "3"]
    assert f'file = "{name}.step"' in (moved / "scene.toml").read_text()


SLIT = str(Path(__file__).resolve().parents[2] / "demos" / "mode3_slit.toml")
TINY = ["--set", "phase_field.epsilon=0.08", "--set", "geometry.mesh_size=0.04",
        "--set", "adaptivity.enabled=false", "--set", "discretization.order=1",
        "--set", "output.checkpoint_every=50", "--no-progress", "--no-plots"]
TIMINGS = {"wall_s", "step_s", "solve_s", "adapt_s"}


def test_a_finished_run_is_extended_as_the_longer_run(tmp_path, capsys):
    """A 3-step run (checkpoints every 50 steps) continued to 5 steps has the history of a
    5-step run, every column but the timings."""
    short, straight = tmp_path / "short", tmp_path / "straight"
    assert cli.main(["run", SLIT, "--out", str(short), "--set", "time.t_end=0.0015", *TINY]) == 0
    assert (short / "checkpoint.h5").exists()  # written at the end
    assert cli.main(["run", SLIT, "--out", str(straight), "--set", "time.t_end=0.0025",
                     *TINY]) == 0
    capsys.readouterr()
    assert cli.main(["run", "--restart", str(short), "--set", "time.t_end=0.0025",
                     "--no-progress", "--no-plots"]) == 0, capsys.readouterr().err
    extended, reference = history(short), history(straight)
    assert len(extended) == len(reference) == 6
    for row, expected in zip(extended, reference):
        assert {k: v for k, v in row.items() if k not in TIMINGS} == \
               {k: v for k, v in expected.items() if k not in TIMINGS}


def test_a_changed_or_missing_cad_copy_is_refused(tmp_path):
    """run.json's sha256 is that of the copy a restart reads: another file is refused."""
    from ngfrac.io.output import OutputError, copy_cad_file, write_run_json
    from ngfrac.runner import _check_cad_copy

    source = tmp_path / "part.step"
    source.write_text("ISO-10303-21;\n")
    run = tmp_path / "run"
    run.mkdir()
    cad = copy_cad_file({"geometry": {"file": str(source)}}, run)
    write_run_json(run, {"cad_file": cad})
    _check_cad_copy(run)  # the copy as written
    (run / "part.step").write_text("ISO-10303-21;\nchanged\n")
    with pytest.raises(OutputError, match="changed since the run read it"):
        _check_cad_copy(run)
    (run / "part.step").unlink()
    with pytest.raises(OutputError, match=f"is missing.*copy '{source}' back"):
        _check_cad_copy(run)
