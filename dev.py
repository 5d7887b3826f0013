#!/usr/bin/env python3
"""Set up ``.venv`` when needed and run the main demo, the test suite or the docs build.

    python3 dev.py demo     # runs demos/mode3_slit.toml into out/mode3_slit
    python3 dev.py test     # runs the test suite (extra arguments go to pytest)
    python3 dev.py docs     # builds the HTML docs into docs/_build/html (arguments: sphinx-build)

Only the Python standard library is used here, so this works on a machine
that has nothing but Python 3.11 and pip.
"""
from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
STAMP = VENV / ".ngfrac-setup-stamp"
EXTRAS = "test,docs,mpi"
"""The extras installed into .venv: one environment serves every command (mpi: the
MPI tests in tests/parallel run in CI too, not only where someone installed it)."""


def venv_python() -> Path:
    """Path of the interpreter inside ``.venv``."""
    sub = "Scripts/python.exe" if os.name == "nt" else "bin/python"
    return VENV / sub


def setup_fingerprint() -> str:
    """Hash of the files that decide what gets installed."""
    digest = hashlib.sha256()
    for name in ("setup.cfg", "pyproject.toml"):
        digest.update((ROOT / name).read_bytes())
    digest.update(EXTRAS.encode())
    return digest.hexdigest()


def ensure_environment() -> Path:
    """Create ``.venv`` and install the project into it, unless already current."""
    python = venv_python()
    if not python.exists():
        print(f"creating {VENV}", flush=True)
        venv.EnvBuilder(with_pip=True).create(VENV)
    fingerprint = setup_fingerprint()
    if not STAMP.exists() or STAMP.read_text() != fingerprint:
        print("installing ngfrac and its dependencies into .venv", flush=True)
        subprocess.run([python, "-m", "pip", "install", "-q", "--upgrade", "pip"], check=True)
        subprocess.run([python, "-m", "pip", "install", "-q", "-e", f"{ROOT}[{EXTRAS}]"],
                       check=True)
        STAMP.write_text(fingerprint)
    return python


def main(argv: list[str]) -> int:
    if not argv or argv[0] not in ("demo", "test", "docs"):
        print("usage: python3 dev.py demo | test [pytest arguments] "
              "| docs [sphinx-build arguments]", file=sys.stderr)
        return 2
    python = ensure_environment()
    if argv[0] == "demo":
        command = [python, "-m", "ngfrac", "run", "demos/mode3_slit.toml",
                   "--out", "out/mode3_slit", "--overwrite", *argv[1:]]
    elif argv[0] == "docs":
        command = [python, "-m", "sphinx", "-b", "html", "docs", "docs/_build/html", *argv[1:]]
        print("building the docs into docs/_build/html (open index.html)", flush=True)
    else:
        command = [python, "-m", "pytest", *argv[1:]]
    return subprocess.run(command, cwd=ROOT).returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
