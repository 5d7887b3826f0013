"""Cost of moving the fields to a new mesh (ngfrac.mesh.transfer).

    python benchmarks/transfer_cost.py [--quick] [--threads N]

A markdown table (formerly the slow test ``test_benchmark_transfer`` of
tests/mesh/test_transfer.py): the optimal profile z = exp(-d/epsilon) of a half slit
(epsilon 0.02) on a P2 mesh graded to the crack, moved to a second graded mesh of about
5,000 vertices; the time of ``transfer_phase_field`` and of ``transfer(u)`` by ``set``
(NGSolve's interpolation) and by ``nodes`` (evaluation at the Lagrange nodes). ``--quick``
uses meshes about four times coarser. Times depend on the machine and its load (one NGSolve
thread by default).
"""
from __future__ import annotations

import sys
import time

import ngsolve as ngs

from ngfrac.geometry.domains import build_mesh
from ngfrac.mesh.transfer import transfer, transfer_phase_field
from ngfrac.testing.meshes import UNIT_SQUARE, crack_mesh, profile_field

EPS = 0.02
SMOOTH = 0.5 + 0.4 * ngs.sin(3 * ngs.x) * ngs.cos(2 * ngs.y)


def main(argv: list[str]) -> int:
    threads = int(argv[argv.index("--threads") + 1]) if "--threads" in argv else 1
    ngs.SetNumThreads(threads)
    scale = 2.0 if "--quick" in argv else 1.0
    old = crack_mesh(build_mesh(UNIT_SQUARE, 0.05), h_band=scale * EPS / 3, h_core=scale * EPS / 3,
                     hmax=0.1, width=6 * EPS, epsilon=EPS)
    new = crack_mesh(old, h_band=scale * 0.3 * EPS, h_core=scale * 0.3 * EPS, hmax=0.08,
                     width=5 * EPS, epsilon=EPS)
    z = profile_field(old, 2, EPS)
    u = ngs.GridFunction(ngs.H1(old, order=2))
    u.Set(SMOOTH)
    fes = ngs.H1(new, order=2)
    started = time.perf_counter()
    transfer_phase_field(z, z, fes)
    phase = time.perf_counter() - started
    timings = []
    for method in ("set", "nodes"):
        started = time.perf_counter()
        transfer(u, fes, method)
        timings.append(time.perf_counter() - started)
    print("| old nv | new nv | P2 nodes | transfer_phase_field s | transfer(u) set s | "
          "transfer(u) nodes s |")
    print("|---|---|---|---|---|---|")
    print(f"| {old.nv} | {new.nv} | {fes.ndof} | {phase:.3f} | {timings[0]:.3f} | {timings[1]:.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
