#!/usr/bin/env python3
"""Do two versions of ngfrac compute the same demo histories?  (the redesign's check)

Runs the demos (AT2 and AT1, mode III, modes I+II, a split, a CAD domain, 3D) through the command line (``python -m ngfrac run``) with one NGSolve thread
and compares every history column except the timings::

    NGFRAC_THREADS=1 python benchmarks/same_histories.py save DIR      # with the old code
    NGFRAC_THREADS=1 python benchmarks/same_histories.py compare DIR   # with the new code

``compare`` runs the same demos into a temporary folder and prints, per demo and column,
the largest relative difference max|a - b| / max(max|a|, tiny); it exits 1 when one is above
``--rtol`` (1e-10) or a column or row count differs. Only the command line is used, so any
version of ngfrac since the CLI existed can make the reference (``PYTHONPATH=CLONE``).
"""
from __future__ import annotations

import argparse
import csv
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
QUICK = ["phase_field.epsilon=0.04", "geometry.mesh_size=0.02", "output.vtk_every=50",
         "time.dt=1e-3", "adaptivity.max_vertices=2000"]
DEMOS = {
    "mode3_slit": [],  # the README's demo, full
    "mode12_kink": QUICK + ["phase_field.epsilon=0.03", "discretization.order=1", "time.dt=4e-3"],
    "box3d": QUICK + ["time.dt=0.04", "time.adaptive=false", "adaptivity.max_vertices=1000"],
    "sent": QUICK + ["phase_field.epsilon=0.03", "time.dt=1.25e-4", "time.t_end=8.5e-3",
                     "time.adaptive=false"],
    "mode3_slit_at1": QUICK + ["time.dt=2e-3"],  # AT1: the obstacle z-step
    "sens_amor": QUICK + ["phase_field.epsilon=0.03", "discretization.order=1", "time.dt=2e-4",
                          "time.t_end=1.2e-2", "time.adaptive=false", "material.split=amor",
                          "material.split_mode=full"],  # the full split's Newton u-step
    "plate_hole": QUICK + ["phase_field.epsilon=0.015", "discretization.order=1",
                           "time.dt=1e-4", "time.t_end=1.2e-2", "time.adaptive=false",
                           "adaptivity.max_vertices=3000"],  # a CAD (OCC) domain
}
"""The demos of the check and their overrides (the quick modes of tests/demos/test_demos.py)."""
TIMINGS = {"wall_s", "step_s", "solve_s", "adapt_s"}


SCENES = {"sens_amor": "sens"}
"""Checks that run another demo's scene file (with a split, say)."""


def run(name: str, out: Path) -> Path:
    scene = ROOT / "demos" / f"{SCENES.get(name, name)}.toml"
    command = [sys.executable, "-m", "ngfrac", "run", str(scene),
               "--out", str(out / name), "--overwrite", "--no-progress", "--no-plots"]
    for value in DEMOS[name]:
        command += ["--set", value]
    env = {**os.environ, "NGFRAC_THREADS": os.environ.get("NGFRAC_THREADS", "1")}
    subprocess.run(command, check=True, env=env)
    return out / name / "history.csv"


def read(path: Path) -> dict[str, list[float]]:
    with open(path, newline="") as handle:
        rows = list(csv.reader(line for line in handle if not line.startswith("#")))
    header, data = rows[0], rows[1:]
    return {name: [float(row[i]) for row in data] for i, name in enumerate(header)}


def difference(a: list[float], b: list[float]) -> float:
    if len(a) != len(b):
        return math.inf
    scale = max([abs(x) for x in a if math.isfinite(x)] + [1e-300])
    worst = 0.0
    for x, y in zip(a, b):
        if math.isnan(x) and math.isnan(y):
            continue
        if math.isnan(x) or math.isnan(y):
            return math.inf
        worst = max(worst, abs(x - y) / scale)
    return worst


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=["save", "compare"])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--demo", action="append", choices=list(DEMOS))
    parser.add_argument("--rtol", type=float, default=1e-10)
    args = parser.parse_args()
    names = args.demo or list(DEMOS)
    if args.action == "save":
        for name in names:
            run(name, args.folder)
        return 0
    failed = False
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            new = read(run(name, Path(tmp)))
            old = read(args.folder / name / "history.csv")
            if set(new) != set(old):
                print(f"{name}: columns differ: {sorted(set(new) ^ set(old))}")
                failed = True
                continue
            worst = {c: difference(old[c], new[c]) for c in old if c not in TIMINGS}
            column = max(worst, key=worst.get)
            print(f"{name}: {len(old['step'])} rows, largest relative difference "
                  f"{worst[column]:.2e} (column {column})")
            failed |= worst[column] > args.rtol
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
