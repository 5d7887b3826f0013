"""Cost of moving the fields to a new mesh (ngfrac.mesh.transfer).

    python benchmarks/transfer_cost.py [--quick] [--threads N]

A markdown table (formerly the slow test ``test_benchmark_transfer`` of
tests/ngfrac/test_transfer.py): the optimal profile z = exp(-d/epsilon) of a half slit
(epsilon 0.02) on a P2 mesh graded to the crack, moved to a second graded mesh of about
5,000 vertices; the time of ``transfer_phase_field`` and of ``transfer(u)`` by ``set``
(NGSolve's interpolation) and by ``nodes`` (evaluation at the Lagrange nodes). ``--quick``
uses meshes about four times coarser. Times depend on the machine and its load (one NGSolve
thread by default).
"""
from __future__ import annotations

import sys
import time

import numpy as np
import ngsolve as ngs

from ngfrac.mesh.domains import build_mesh
from ngfrac.mesh.remesh import ElementGeometry, adapt_mesh, enforce_crack_sizes
from ngfrac.mesh.transfer import transfer, transfer_phase_field
from ngfrac.physics.cracks import distance_to_polylines, optimal_profile
from ngfrac.scene import Geometry
from ngfrac.solve.nodal import LagrangeNodes

SQUARE = Geometry(width=1.0, height=1.0)
EPS = 0.02
CRACK = [[(0.0, 0.5), (0.5, 0.5)]]
SMOOTH = 0.5 + 0.4 * ngs.sin(3 * ngs.x) * ngs.cos(2 * ngs.y)


def profile_field(mesh: ngs.Mesh, order: int) -> ngs.GridFunction:
    """z = exp(-dist/eps) at the Lagrange nodes."""
    fes = ngs.H1(mesh, order=order)
    z = ngs.GridFunction(fes, "z")
    nodes = LagrangeNodes(fes)
    nodes.assign(z, optimal_profile(distance_to_polylines(nodes.points, CRACK), EPS))
    return z


def crack_mesh(start: ngs.Mesh, *, h_band: float, h_core: float, hmax: float, width: float,
               order: int = 2) -> ngs.Mesh:
    """h <= h_band within ``width`` of the crack, h <= h_core where z >= 0.6."""
    mesh = start
    for _ in range(2):
        geom = ElementGeometry.of(mesh)
        band = distance_to_polylines(geom.centroids, CRACK) < width
        sizes = enforce_crack_sizes(mesh, np.where(band, h_band, hmax),
                                    z=profile_field(mesh, order), z_level=0.6, h_crack=h_core)
        mesh = adapt_mesh(mesh, SQUARE, sizes, hmax=hmax, max_vertices=10**6)
    return mesh


def main(argv: list[str]) -> int:
    threads = int(argv[argv.index("--threads") + 1]) if "--threads" in argv else 1
    ngs.SetNumThreads(threads)
    scale = 2.0 if "--quick" in argv else 1.0
    old = crack_mesh(build_mesh(SQUARE, 0.05), h_band=scale * EPS / 3, h_core=scale * EPS / 3,
                     hmax=0.1, width=6 * EPS)
    new = crack_mesh(old, h_band=scale * 0.3 * EPS, h_core=scale * 0.3 * EPS, hmax=0.08,
                     width=5 * EPS)
    z = profile_field(old, 2)
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
