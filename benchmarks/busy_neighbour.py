#!/usr/bin/env python3
"""Does a run slow down when another process keeps a core busy?  (docs/benchmarks.md,
"Threads on a busy machine")

Runs two scenes through ``python -m ngfrac run`` with NGSolve's default thread count (all
cores: NGFRAC_THREADS unset) and with ``NGFRAC_THREADS=1``, each on a quiet machine and beside
a busy neighbour (a Python loop on one core), and prints wall and CPU seconds (median of
``--repeat`` runs)::

    python benchmarks/busy_neighbour.py [--repeat 3] [--ngfrac PATH] [--scene NAME ...]

``--ngfrac PATH`` runs the ngfrac of another checkout (``PYTHONPATH=PATH``), e.g. one of the
commit before a change. Run it on an otherwise quiet machine.
"""
from __future__ import annotations

import argparse
import contextlib
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENES = {
    # the first 60 steps of the Fig. 2 demo (adaptive, ~4,000 vertices)
    "demo excerpt": ("mode3_slit", ["time.t_end=0.03"]),
    # a coarse crack-free strip: 100 steps on ~80 vertices (P2), tiny kernels
    "coarse strip": ("mode3_slit", ["cracks=[]", "adaptivity.enabled=false",
                                    "geometry.mesh_size=0.15", "time.t_end=0.05",
                                    "output.vtk_every=0"]),
    # the 3D demo to t = 2.2: 55 adaptive steps, the crack from x = 0.3 to 0.55 across three
    # mesh changes (~1,350 vertices), Netgen's volume meshing at each
    "3D box": ("box3d", ["time.t_end=2.2", "output.vtk_every=0"]),
}
BUSY = [sys.executable, "-c", "while True: pass"]


@contextlib.contextmanager
def neighbour(busy: bool = True, settle: float = 0.5):
    """A busy process (a Python loop on one core) for the enclosed code, when ``busy``; it
    starts ``settle`` seconds before the code and is killed after it."""
    process = subprocess.Popen(BUSY) if busy else None
    try:
        if busy:
            time.sleep(settle)
        yield
    finally:
        if process is not None:
            process.kill()
            process.wait()


def run(scene: str, overrides: list[str], threads: str | None, out: Path,
        ngfrac: Path | None) -> tuple[float, float]:
    """(wall, CPU) seconds of one ``ngfrac run``."""
    command = [sys.executable, "-m", "ngfrac", "run", str(ROOT / "demos" / f"{scene}.toml"),
               "--out", str(out), "--overwrite", "--no-progress", "--no-plots",
               "--set", "output.results=false", "--set", "output.checkpoint_every=0"]
    for value in overrides:
        command += ["--set", value]
    env = dict(os.environ)
    env.pop("NGFRAC_THREADS", None)
    if threads is not None:
        env["NGFRAC_THREADS"] = threads
    if ngfrac is not None:
        env["PYTHONPATH"] = str(ngfrac)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, env=env, check=True, capture_output=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--ngfrac", type=Path, help="checkout whose ngfrac to run")
    parser.add_argument("--scene", action="append", choices=list(SCENES),
                        help="only this scene (repeatable; default: all)")
    args = parser.parse_args()
    print(f"load before: {os.getloadavg()[0]:.2f}; ngfrac from {args.ngfrac or ROOT}")
    print(f"{'scene':14} {'threads':8} {'neighbour':9} {'wall s':>8} {'CPU s':>8}")
    with tempfile.TemporaryDirectory() as tmp:
        for name, (scene, overrides) in SCENES.items():
            if args.scene and name not in args.scene:
                continue
            for busy in (False, True):
                with neighbour(busy):
                    for threads in (None, "1"):
                        runs = [run(scene, overrides, threads, Path(tmp) / "run", args.ngfrac)
                                for _ in range(args.repeat)]
                        wall = statistics.median(w for w, _ in runs)
                        cpu = statistics.median(c for _, c in runs)
                        print(f"{name:14} {threads or 'default':8} {'busy' if busy else 'none':9} "
                              f"{wall:8.2f} {cpu:8.2f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
