#!/usr/bin/env python3
"""The 3D box on 1 (serial), 3, 4, ... processes: time per step split into solves, mesh
changes and the rest, and the largest resident memory of one process (issue #14, item 6)::

    python benchmarks/mpi_scaling.py [--np 1 3 4] [--set KEY=VALUE ...]

Each run is ``ngfrac run demos/box3d.toml`` (serial, or under the environment's ``mpiexec
-np N``) with one NGSolve thread per process, into a temporary folder; the table comes from
the history rank 0 writes (``step_s``, ``solve_s``, ``adapt_s`` per step) and
``getrusage(RUSAGE_CHILDREN)`` after each run (its ``ru_maxrss`` is the largest of any one
process of the run, which for a distributed run is rank 0, the one holding the serial mesh).
``-np 2`` is left out: Netgen's ``Distribute`` leaves rank 0 without elements, so it would be one
worker (ngfrac refuses it). On a machine with fewer cores than processes the runs are
oversubscribed: the table then shows the cost of MPI, not its speed-up; say so with the
numbers. Measure on a quiet machine (check ``uptime``).
"""
from __future__ import annotations

import argparse
import csv
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "demos" / "box3d.toml"
DEFAULT_SETS = ["discretization.order=2", "time.adaptive=false", "time.dt=0.1", "time.t_end=2.0",
                "adaptivity.max_vertices=3000", "output.vtk_every=0", "output.results=false",
                "output.checkpoint_every=0"]
"""P2 (the demo is P1: BDDC of P1 has only vertex dofs, so its coarse problem is the whole
problem) under a 3,000-vertex cap, 20 fixed steps: the crack starts to grow and the mesh
changes a few times."""


def launcher() -> list[str]:
    """The environment's ``mpiexec`` (:func:`ngfrac.parallel.mpiexec_command`), or exit."""
    from ngfrac.parallel import mpiexec_command

    command = mpiexec_command()
    if command is None:
        sys.exit("mpi_scaling: no mpi4py or no mpiexec of its MPI; pip install -e .[mpi]")
    return command


def run(processes: int, sets: list[str], out: Path) -> dict[str, float]:
    """One run; its history's timing medians and sums, wall and CPU time, memory."""
    command = [sys.executable, "-m", "ngfrac", "run", str(SCENE), "--out", str(out),
               "--no-progress", "--no-plots", "--overwrite"]
    for value in sets:
        command += ["--set", value]
    if processes > 1:
        command = [*launcher(), "-np", str(processes), *command]
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMI_", "PMIX_"))}
    env["NGFRAC_THREADS"] = "1"
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    result = subprocess.run(command, env=env, capture_output=True, text=True, cwd=ROOT)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if result.returncode != 0:
        sys.exit(f"mpi_scaling: the run on {processes} process(es) failed:\n{result.stderr[-2000:]}")
    with open(out / "history.csv", newline="") as handle:
        rows = list(csv.DictReader(line for line in handle if not line.startswith("#")))[1:]
    number = lambda row, key: float(row[key]) if row[key] not in ("", "nan") else math.nan
    changed = [row for row in rows if number(row, "adapt_s") > 0.05]
    steady = [row for row in rows if row not in changed]
    return {
        "processes": processes, "steps": len(rows), "changes": len(changed),
        "nv_max": max(int(row["nv"]) for row in rows),
        "wall_s": wall,
        "cpu_s": (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime),
        "step_median_s": statistics.median(number(row, "step_s") for row in steady),
        "solve_median_s": statistics.median(number(row, "solve_s") for row in steady),
        "change_median_s": (statistics.median(number(row, "adapt_s") for row in changed)
                            if changed else math.nan),
        "steps_total_s": sum(number(row, "step_s") for row in rows),
        "solves_total_s": sum(number(row, "solve_s") for row in rows),
        "changes_total_s": sum(number(row, "adapt_s") for row in changed),
        "maxrss_mb": after.ru_maxrss / 1024,
        "E_el_end": number(rows[-1], "E_el"), "crack_length_end": number(rows[-1], "crack_length"),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--np", type=int, nargs="+", default=[1, 3, 4],
                        help="process counts (1: serial; 2 is refused by ngfrac)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="scene overrides after the benchmark's own")
    args = parser.parse_args(argv)
    if 2 in args.np:
        parser.error("-np 2 leaves one worker (rank 0 holds no elements); use 1, 3 or more")
    sets = DEFAULT_SETS + args.set
    print(f"# box3d {' '.join(sets)}; load average {os.getloadavg()[0]:.2f}, "
          f"{os.cpu_count()} cores", flush=True)
    header = ("processes", "steps", "changes", "nv_max", "wall_s", "cpu_s", "step_median_s",
              "solve_median_s", "change_median_s", "steps_total_s", "solves_total_s",
              "changes_total_s", "maxrss_mb", "E_el_end", "crack_length_end")
    print(" | ".join(header), flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        for processes in args.np:
            row = run(processes, sets, Path(tmp) / f"np{processes}")
            print(" | ".join(f"{row[key]:.4g}" if isinstance(row[key], float) else str(row[key])
                             for key in header), flush=True)
    print(f"# load average at the end {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
