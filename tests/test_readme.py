"""The README's commands work for a newcomer (issue 28, item 3): its first two commands are
`python3 dev.py demo` and `python3 dev.py test`; every later command is a dev.py command
(which reaches the ngfrac of .venv) or comes after the line that activates .venv; the MPI line
has what Open MPI needs on a small machine and as root."""
import re
import subprocess
import sys
from pathlib import Path

import pytest

import dev  # dev.py at the checkout's root, on sys.path as tests/ is a package

ROOT = Path(__file__).resolve().parents[1]


def code_lines() -> list[str]:
    text = (ROOT / "README.md").read_text()
    return [line.strip() for block in re.findall(r"```\n(.*?)```", text, flags=re.S)
            for line in block.splitlines() if line.strip()]


def test_readme_commands_run_without_activating_anything_first():
    lines = code_lines()
    assert lines[:2] == ["python3 dev.py demo", "python3 dev.py test"]
    activated = False
    for line in lines:
        if line.startswith("source .venv/bin/activate"):
            activated = True
        elif line.startswith("python3 dev.py"):
            assert line.split()[2] in dev.COMMANDS, line
        elif line.startswith(("ngfrac", "mpiexec")):
            assert activated, f"{line!r} needs .venv's ngfrac on PATH: activate it first"
    text = (ROOT / "README.md").read_text()
    for mpi in re.findall(r"`(mpiexec [^`]*)`", text):  # a command, not the name
        assert "--oversubscribe" in mpi, mpi


@pytest.fixture
def calls(monkeypatch):
    """dev.py's subprocess calls, with .venv's interpreter taken to be this one."""
    made = []

    def run(command, **kwargs):
        made.append([str(part) for part in command])
        if "-c" in command:  # the probe for the MPI launcher
            return subprocess.CompletedProcess(command, 0, '["mpiexec", "--oversubscribe"]\n', "")
        return subprocess.CompletedProcess(command, 0)

    monkeypatch.setattr(dev, "ensure_environment", lambda: Path(sys.executable))
    monkeypatch.setattr(dev.subprocess, "run", run)
    return made


def test_dev_run_forwards_to_ngfrac_of_the_venv(calls):
    assert dev.main(["run", "demos/mode3_stripes.toml", "--out", "out/s"]) == 0
    assert dev.main(["ngfrac", "check", "demos/mode3_stripes.toml"]) == 0
    assert calls == [[sys.executable, "-m", "ngfrac", "run", "demos/mode3_stripes.toml", "--out",
                      "out/s"],
                     [sys.executable, "-m", "ngfrac", "check", "demos/mode3_stripes.toml"]]


def test_dev_mpi_uses_the_launcher_with_its_flags(calls):
    assert dev.main(["mpi", "3", "scene.toml", "--out", "o"]) == 0
    assert calls[-1] == ["mpiexec", "--oversubscribe", "-np", "3", sys.executable, "-m", "ngfrac",
                         "run", "scene.toml", "--out", "o"]
    assert dev.main(["mpi", "scene.toml"]) == 2  # no process count: usage, exit 2
