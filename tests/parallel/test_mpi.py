"""MPI runs (``mpirun -np 3``) give the serial history on a fixed mesh; a failure on one rank
ends the job; what is not supported yet is refused in one line.

Each run is a subprocess with a timeout (its whole process group is killed then: a hang
fails the test, never the suite). Skipped without mpi4py or without a launcher of the MPI
mpi4py uses (the mpich wheel's ``mpiexec`` next to the interpreter, or one on PATH; Open MPI
gets ``--oversubscribe``, MPICH oversubscribes by default). 3 processes: Netgen's
``Distribute`` leaves rank 0 without elements.
"""
from __future__ import annotations

import csv
import importlib.util
import math
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TIMEOUT = 180
"""Seconds for one MPI run (they take 5-20 s; the rest is for a loaded machine)."""
CG_RTOL = 1e-8
"""The MPI run solves u and z by CG to a relative residual of 1e-10 (the serial run by sparse
Cholesky): a column may differ by the solver tolerance times a condition-number factor;
measured at most 9e-11 of the column's largest value (Fx_top, plane strain)."""
COMPARED = ("nv", "ndof", "hmin", "hmax", "E_el", "E_surf", "E_total", "crack_length", "tip_x",
            "tip_y", "path_length", "n_damage_zones")

PLANE_STRAIN = ("demos/mode12_kink.toml",
                ["adaptivity.enabled=false", "geometry.mesh_size=0.05", "phase_field.epsilon=0.05",
                 "time.dt=0.01", "time.t_end=0.1", "output.vtk_every=5"])
MODE3 = ("demos/mode3_slit.toml",
         ["adaptivity.enabled=false", "geometry.mesh_size=0.05", "phase_field.epsilon=0.05",
          "time.dt=0.02", "time.t_end=0.18", "output.vtk_every=0"])
"""Grows the slit from x = 0.3 to a tip near x = 0.53 in 9 steps (490 vertices)."""


def _env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("OMPI_", "PMI_", "PMIX_", "HYDRA_"))}
    env["NGFRAC_THREADS"] = "1"
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def _run(command: list[str], timeout: float = TIMEOUT) -> subprocess.CompletedProcess:
    """``command`` in its own process group, killed whole after ``timeout`` (then: fail)."""
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, env=_env(), cwd=ROOT, start_new_session=True)
    try:
        out, err = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.communicate()
        pytest.fail(f"{' '.join(command[:6])} ... did not end within {timeout} s (a hang)")
    return subprocess.CompletedProcess(command, process.returncode, out, err)


def _launcher() -> list[str] | None:
    """mpiexec of the MPI that mpi4py loads, with the flag to oversubscribe if it needs one."""
    if importlib.util.find_spec("mpi4py") is None:
        return None
    library = subprocess.run([sys.executable, "-c", "from mpi4py import MPI; "
                              "print(MPI.Get_library_version())"], capture_output=True, text=True,
                             timeout=60, env=_env()).stdout
    candidates = [str(Path(sys.executable).parent / "mpiexec"), shutil.which("mpiexec"),
                  shutil.which("mpirun")]
    for candidate in candidates:
        if not candidate or not os.access(candidate, os.X_OK):
            continue
        version = subprocess.run([candidate, "--version"], capture_output=True, text=True,
                                 timeout=60).stdout
        if "MPICH" in library and "HYDRA" in version.upper():
            return [candidate]
        if "Open MPI" in library and "Open MPI" in version:
            as_root = ["--allow-run-as-root"] if os.geteuid() == 0 else []  # else it refuses
            return [candidate, "--oversubscribe", *as_root]
    return None


@pytest.fixture(scope="module")
def mpiexec() -> list[str]:
    launcher = _launcher()
    if launcher is None:
        pytest.skip("mpi4py or an mpiexec of its MPI is missing (pip install ngfrac[mpi])")
    return [*launcher, "-np", "3"]


def _ngfrac_run(scene: str, sets: list[str], out: Path, prefix: list[str] = ()) -> subprocess.CompletedProcess:
    command = [*prefix, sys.executable, "-m", "ngfrac", "run", str(ROOT / scene), "--out", str(out),
               "--no-progress", "--no-plots"]
    for value in sets:
        command += ["--set", value]
    return _run(command)


def _history(path: Path) -> dict[str, list[float]]:
    with open(path, newline="") as handle:
        rows = list(csv.reader(line for line in handle if not line.startswith("#")))
    return {name: [float(row[i]) for row in rows[1:]] for i, name in enumerate(rows[0])}


def _worst(a: list[float], b: list[float]) -> float:
    """max |a - b| over the column's largest |a| (NaN equal to NaN)."""
    assert len(a) == len(b), f"{len(a)} rows against {len(b)}"
    scale = max([abs(x) for x in a if math.isfinite(x)] + [1e-300])
    worst = 0.0
    for x, y in zip(a, b):
        if math.isnan(x) and math.isnan(y):
            continue
        worst = max(worst, abs(x - y) / scale)
    return worst


def _compare(scene: tuple[str, list[str]], tmp_path: Path, mpiexec: list[str]) -> dict:
    serial = _ngfrac_run(*scene, tmp_path / "serial")
    assert serial.returncode == 0, serial.stderr
    parallel = _ngfrac_run(*scene, tmp_path / "mpi", mpiexec)
    assert parallel.returncode == 0, parallel.stderr
    assert parallel.stdout.count(" steps to t = ") == 1, parallel.stdout  # rank 0 prints
    a, b = _history(tmp_path / "serial" / "history.csv"), _history(tmp_path / "mpi" / "history.csv")
    columns = [*COMPARED, *(name for name in a if name[0] in "Fu" and "_" in name)]
    table = {name: _worst(a[name], b[name]) for name in columns}
    bad = {name: value for name, value in table.items() if not value <= CG_RTOL}
    assert not bad, f"MPI history differs from the serial one by more than {CG_RTOL:g}: {bad}"
    return b


def test_plane_strain_fixed_mesh_gives_the_serial_history(tmp_path, mpiexec):
    history = _compare(PLANE_STRAIN, tmp_path, mpiexec)
    assert max(history["E_el"]) > 0 and history["Fy_top"][-1] > 0  # loaded: forces compared
    collection = (tmp_path / "mpi" / "vtk" / "fields.pvd").read_text()
    for snapshot in range(3):  # t = 0, 0.05, 0.1: one part per worker rank
        for rank in (1, 2):
            name = f"fields_{snapshot:05d}_proc{rank}.vtu"
            assert (tmp_path / "mpi" / "vtk" / name).stat().st_size > 0
            assert f'part="{rank}" file="{name}"' in collection


def test_mode3_crack_grows_as_in_the_serial_run(tmp_path, mpiexec):
    history = _compare(MODE3, tmp_path, mpiexec)
    assert history["tip_x"][0] == pytest.approx(0.3) and history["tip_x"][-1] > 0.45
    assert history["crack_length"][-1] > 1.2  # grown from 0.3 + the band


def test_a_failure_on_one_rank_ends_the_job_in_one_line(tmp_path, mpiexec):
    script = ("import sys\n"
              "from ngfrac import load_scene\n"
              "from ngfrac.runner import run_scene\n"
              f"scene = load_scene({str(ROOT / MODE3[0])!r}, {MODE3[1]!r})\n"
              "def fail(stepper):\n"
              "    if stepper.k == 2 and stepper.comm.rank == 1:\n"
              "        raise RuntimeError('injected')\n"
              f"run_scene(scene, {str(tmp_path / 'run')!r}, plots=False, on_step=fail)\n")
    result = _run([*mpiexec, sys.executable, "-c", script])
    assert result.returncode != 0
    lines = [line for line in result.stderr.splitlines() if line.startswith("ngfrac:")]
    assert lines == ["ngfrac: rank 1 of 3: RuntimeError: injected"], result.stderr


def test_an_adaptive_scene_is_refused_in_one_line(tmp_path, mpiexec):
    result = _ngfrac_run("demos/mode3_slit.toml", [], tmp_path / "run", mpiexec)
    assert result.returncode == 2
    lines = [line for line in result.stderr.splitlines() if line.startswith("ngfrac: error")]
    assert len(lines) == 1 and "adaptivity under MPI is not supported yet" in lines[0], result.stderr
    assert not (tmp_path / "run").exists()  # refused before anything is written


def test_a_serial_run_never_imports_mpi4py():
    code = ("import sys, ngfrac, ngfrac.cli, ngfrac.runner\n"
            "from ngfrac.parallel import SERIAL, world\n"
            "assert world() is SERIAL\n"
            "print('mpi4py' in sys.modules)\n")
    result = _run([sys.executable, "-c", code], timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "False"
