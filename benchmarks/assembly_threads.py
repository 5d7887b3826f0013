#!/usr/bin/env python3
"""When do NGSolve's threads pay for one assembly?  (docs/benchmarks.md, section 14,
"Kernels too short for threads")

Assembles a 2D P2 vector-Laplace form on unit squares of growing size, on one thread and in a
two-thread TaskManager, and prints the median of 7 wall times of each, quiet and (``--busy``)
beside a busy process (a Python loop on one core)::

    python benchmarks/assembly_threads.py [--busy]

The choice of ``ngfrac.fem.threads.ThreadChooser.SMALL`` comes from this table.
"""
from __future__ import annotations

import argparse
import contextlib
import statistics
import sys
import time

import ngsolve as ngs
from netgen.geom2d import unit_square

from busy_neighbour import neighbour  # benchmarks/busy_neighbour.py


def median_seconds(form: ngs.BilinearForm, threads: int) -> float:
    ngs.SetNumThreads(threads)
    times = []
    for _ in range(7):
        start = time.perf_counter()
        with ngs.TaskManager() if threads > 1 else contextlib.nullcontext():
            form.Assemble()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--busy", action="store_true", help="with a busy process beside it")
    args = parser.parse_args()
    with neighbour(args.busy):
        print(f"{'vertices':>8} {'1 thread ms':>12} {'2 threads ms':>13} {'ratio':>6}")
        for h in (0.2, 0.1, 0.05, 0.03, 0.02, 0.012):
            mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=h))
            u, v = ngs.VectorH1(mesh, order=2).TnT()
            form = ngs.BilinearForm(ngs.InnerProduct(ngs.Grad(u), ngs.Grad(v)) * ngs.dx)
            form.Assemble()  # the matrix graph
            one, two = median_seconds(form, 1), median_seconds(form, 2)
            print(f"{mesh.nv:8d} {one * 1e3:12.3f} {two * 1e3:13.3f} {two / one:6.2f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
