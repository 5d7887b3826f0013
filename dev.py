#!/usr/bin/env python3
"""Set up ``.venv`` when needed and run the main demo, the test suite or the docs build.

    python3 dev.py demo     # runs demos/mode3_slit.toml into out/mode3_slit
    python3 dev.py test     # runs the test suite (extra arguments go to pytest)
                            # on every core: see test_workers()
    python3 dev.py docs     # builds the HTML docs into docs/_build/html (arguments: sphinx-build)
    python3 dev.py run SCENE.toml --out DIR ...   # `ngfrac run ...` with the ngfrac of .venv
    python3 dev.py ngfrac check SCENE.toml        # any ngfrac command (check, plot, run)
    python3 dev.py mpi N SCENE.toml --out DIR ... # `ngfrac run ...` on N MPI processes (mpiexec
                                                  # of .venv's MPI with the flags it needs)

Only the Python standard library is used here, so this works on a machine
that has nothing but Python 3.11 and pip.
"""
from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
STAMP = VENV / ".ngfrac-setup-stamp"
EXTRAS = "test,docs,mpi,dask"
"""The extras installed into .venv: one environment serves every command (mpi: the
MPI tests in tests/parallel run in CI too, not only where someone installed it; dask: the
tests of ngfrac study, tests/test_study.py)."""


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


def usable_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def test_workers(pytest_args: list[str], environ: dict[str, str]) -> tuple[list[str], dict[str, str]]:
    """pytest's arguments and environment for a test run that uses every core.

    NGFRAC_THREADS is the NGSolve threads of each test process: unset or 1 runs one pytest
    worker per core, at most four (pytest-xdist, ``-n N --dist loadfile``: a file's tests and
    its fixtures stay in one worker) with one thread each; a larger value runs one process with that many
    threads, as before (a second process beside it would oversubscribe the cores, and
    NGSolve's idle threads spin). ``-n`` or ``-p no:xdist`` among the arguments is left as
    given.
    """
    environ = dict(environ)
    value = environ.get("NGFRAC_THREADS", "").strip()
    threads = int(value) if value.isdigit() and int(value) >= 1 else 1
    workers = min(4, usable_cores() // threads)
    chosen = any(a.startswith(("-n", "--numprocesses")) or "no:xdist" in a for a in pytest_args)
    if workers < 2 or chosen:
        return pytest_args, environ
    environ["NGFRAC_THREADS"] = str(threads)
    print(f"pytest on {workers} workers, {threads} NGSolve thread(s) each "
          "(NGFRAC_THREADS=2 runs one process with two)", flush=True)
    return ["-n", str(workers), "--dist", "loadfile", *pytest_args], environ


USAGE = ("usage: python3 dev.py demo | test [pytest arguments] | docs [sphinx-build arguments] "
         "| run [ngfrac run arguments] | ngfrac [ngfrac arguments] "
         "| mpi N [ngfrac run arguments]")
COMMANDS = ("demo", "test", "docs", "run", "ngfrac", "mpi")


def mpi_command(python: Path, processes: str, arguments: list[str]) -> list[str]:
    """``mpiexec`` of the MPI that mpi4py loads in .venv, with the flags it needs (more
    processes than cores, root), running ``ngfrac run ARGUMENTS`` on ``processes`` processes.
    Exits 2 with one line when .venv has no usable MPI."""
    probe = subprocess.run([python, "-c", "import json; from ngfrac.parallel import "
                            "mpiexec_command; print(json.dumps(mpiexec_command()))"],
                           capture_output=True, text=True)
    launcher = json.loads(probe.stdout) if probe.returncode == 0 and probe.stdout.strip() else None
    if not launcher:
        sys.exit("dev.py mpi: no MPI launcher matching mpi4py in .venv (pip install -e .[mpi])")
    return [*launcher, "-np", processes, str(python), "-m", "ngfrac", "run", *arguments]


def main(argv: list[str]) -> int:
    if not argv or argv[0] not in COMMANDS:
        print(USAGE, file=sys.stderr)
        return 2
    if argv[0] == "mpi" and (len(argv) < 2 or not argv[1].isdigit()):
        print("usage: python3 dev.py mpi N [ngfrac run arguments], e.g. python3 dev.py mpi 3 "
              "demos/mode3_slit.toml --out out/mpi", file=sys.stderr)
        return 2
    python = ensure_environment()
    if argv[0] in ("run", "ngfrac"):  # in the caller's folder: relative paths stay as given
        command = [python, "-m", "ngfrac", *(["run"] if argv[0] == "run" else []), *argv[1:]]
        return subprocess.run(command).returncode
    if argv[0] == "mpi":
        return subprocess.run(mpi_command(python, argv[1], argv[2:])).returncode
    if argv[0] == "demo":
        command = [python, "-m", "ngfrac", "run", "demos/mode3_slit.toml",
                   "--out", "out/mode3_slit", "--overwrite", *argv[1:]]
    elif argv[0] == "docs":
        command = [python, "-m", "sphinx", "-b", "html", "docs", "docs/_build/html", *argv[1:]]
        print("building the docs into docs/_build/html (open index.html)", flush=True)
    else:
        arguments, environ = test_workers(argv[1:], dict(os.environ))
        return subprocess.run([python, "-m", "pytest", *arguments], cwd=ROOT,
                              env=environ).returncode
    return subprocess.run(command, cwd=ROOT).returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
