"""The cost of bitwise reproducibility: time per step with and without threaded solves.

    python benchmarks/threads.py [--steps N] [--repeat R] [--set key=value ...]

Runs the first N steps of the Fig. 2 demo (demos/mode3_slit.toml, adaptive, cap 5,000) in
fresh processes, alternating the settings (deterministic default / ``threaded_solves``, one and
two NGSolve threads), R times each, and prints the median CPU and wall time per step and
whether the histories of the repeats are bitwise equal. Run it on a quiet machine (nothing else
running; say the load) and compare the ratios inside one run.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

WORKER = """
import hashlib, json, resource, sys, time
import numpy as np
import ngfrac
from ngfrac import PhaseFieldStepper, load_scene
ngfrac.set_threads()  # NGFRAC_THREADS
scene = load_scene(sys.argv[1], sys.argv[3:])
stepper = PhaseFieldStepper(scene)
steps = int(sys.argv[2])
rows = []
cpu0, wall0 = time.process_time(), time.perf_counter()
for record, _ in zip(stepper.run(), range(steps)):
    rows.append([record.E_total, record.crack_length, record.tip_x, record.tip_y, record.nv])
cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
digest = hashlib.sha256(np.array(rows, dtype=float).tobytes()).hexdigest()[:12]
print(json.dumps({"cpu": cpu / steps, "wall": wall / steps, "digest": digest,
                  "adaptations": len(stepper.adaptations), "nv": int(rows[-1][4])}))
"""

SETTINGS = [("deterministic (default)", 1, False), ("deterministic (default)", 2, False),
            ("threaded_solves = true", 1, True), ("threaded_solves = true", 2, True)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=120)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    args = parser.parse_args()
    scene = str(ROOT / "demos" / "mode3_slit.toml")
    results: dict[tuple[int, int, bool], list[dict]] = {}
    for _ in range(args.repeat):
        for label, threads, threaded in SETTINGS:
            overrides = ["output.history_every=1", f"discretization.threaded_solves={str(threaded).lower()}",
                         *args.overrides]
            env = dict(os.environ, NGFRAC_THREADS=str(threads))
            out = subprocess.run([sys.executable, "-c", WORKER, scene, str(args.steps), *overrides],
                                 env=env, capture_output=True, text=True, check=True)
            results.setdefault((label, threads, threaded), []).append(json.loads(out.stdout.splitlines()[-1]))
    load = os.getloadavg()[0]
    print(f"{args.steps} steps of {scene}, {args.repeat} repeats; load average at the end {load:.2f}")
    print(f"{'setting':<26}{'threads':>8}{'CPU s/step':>12}{'wall s/step':>12}{'repeats equal':>15}{'changes':>9}")
    for (label, threads, _), runs in results.items():
        cpu = np.median([r["cpu"] for r in runs])
        wall = np.median([r["wall"] for r in runs])
        equal = len({r["digest"] for r in runs}) == 1
        print(f"{label:<26}{threads:>8}{cpu:>12.4f}{wall:>12.4f}{str(equal):>15}{runs[0]['adaptations']:>9}")


if __name__ == "__main__":
    main()
