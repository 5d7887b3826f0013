"""Cost of a mesh change by regeneration, and regeneration against marked bisection.

    python benchmarks/meshing_cost.py [--quick] [--threads N]

Two markdown tables (formerly the slow tests ``test_benchmark_numbers`` and
``test_benchmark_bisection_against_regeneration`` of tests/mesh/test_meshing.py):

1. a band of width 4 epsilon (epsilon 0.01) along a half slit at h_band = epsilon/2, /3, /4,
   three mesh changes each: the vertices delivered, their ratio ``c`` to the predicted count
   (``predict_vertices`` with density 1: the vertex-density calibration), the time of
   ``remesh`` alone and of ``adapt_mesh`` (grading, sampling and ``remesh``), and the number
   of sample points of the size field;
2. a mesh graded to h = hmin + 0.3 d (d the distance to the slit) built by marked bisection
   from a uniform mesh against one regeneration of that mesh: vertices, time, the 5th
   percentile of the smallest angle and the median and 95th percentile of the longest edge
   over the requested size.

Times depend on the machine and its load (one NGSolve thread by default); ``--quick`` runs
the first size of each table only.
"""
from __future__ import annotations

import logging
import sys
import time

import numpy as np
import ngsolve as ngs

from ngfrac.mesh import remesh as meshing
from ngfrac.geometry.domains import build_mesh
from ngfrac.fem.elements import ElementGeometry
from ngfrac.mesh.remesh import adapt_mesh, predict_vertices, remesh, sample_size_field
from ngfrac.physics.cracks import distance_to_polylines
from ngfrac.scene import Geometry

SQUARE = Geometry(width=1.0, height=1.0)
HMAX = 0.1
LINE = [[(0.0, 0.5), (0.5, 0.5)]]


def regeneration_table(quick: bool) -> list[str]:
    eps = 0.01
    rows = ["| h_band | nv | c = nv / predicted | remesh s | adapt_mesh s | sample points |",
            "|---|---|---|---|---|---|"]
    for h_band in (eps / 2,) if quick else (eps / 2, eps / 3, eps / 4):
        mesh = build_mesh(SQUARE, 0.05)
        for _ in range(3):
            geom = ElementGeometry.of(mesh)
            sizes = np.where(distance_to_polylines(geom.centroids, LINE) < 4 * eps, h_band, HMAX)
            graded = meshing.element_grader(geom)(sizes)
            integral = predict_vertices(graded, geom.measures, density=1.0)
            field = sample_size_field(mesh, graded)
            started = time.perf_counter()
            remesh(SQUARE, field.points, field.sizes, weights=field.weights, hmax=HMAX,
                   max_vertices=10**6)
            alone = time.perf_counter() - started
            started = time.perf_counter()
            mesh = adapt_mesh(mesh, SQUARE, sizes, hmax=HMAX, max_vertices=10**6)
            rows.append(f"| {h_band:.4f} | {mesh.nv} | {mesh.nv / integral:.3f} | {alone:.2f} "
                        f"| {time.perf_counter() - started:.2f} | {len(field.sizes)} |")
    return rows


def smallest_angles(geom: ElementGeometry) -> np.ndarray:
    """The smallest angle of each triangle (degrees)."""
    corners = geom.coordinates[geom.vertices]
    angles = []
    for i in range(3):
        a = corners[:, (i + 1) % 3] - corners[:, i]
        b = corners[:, (i + 2) % 3] - corners[:, i]
        cosine = np.sum(a * b, axis=1) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1)
        angles.append(np.degrees(np.arccos(np.clip(cosine, -1, 1))))
    return np.min(angles, axis=0)


def bisection_table(quick: bool) -> list[str]:
    rows = ["| hmin | mesh | nv | s | smallest angle p5 (deg) | L/h median | L/h p95 |",
            "|---|---|---|---|---|---|---|"]
    for hmin in (0.005,) if quick else (0.005, 0.0025, 0.00125):
        def field(points: np.ndarray) -> np.ndarray:
            return np.clip(hmin + 0.3 * distance_to_polylines(points, LINE), hmin, HMAX)

        started = time.perf_counter()
        mesh = build_mesh(SQUARE, HMAX)
        while True:
            geom = ElementGeometry.of(mesh)
            coarse = geom.diameters > 1.5 * field(geom.centroids)
            if not coarse.any():
                break
            mesh.SetRefinementFlags(coarse.tolist())
            mesh.Refine()
        bisect_time = time.perf_counter() - started
        started = time.perf_counter()
        regenerated = adapt_mesh(mesh, SQUARE, field(ElementGeometry.of(mesh).centroids),
                                 hmax=HMAX, max_vertices=10**6)
        regen_time = time.perf_counter() - started
        for name, m, t in (("bisection", mesh, bisect_time), ("regeneration", regenerated, regen_time)):
            geom = ElementGeometry.of(m)
            ratio = geom.diameters / field(geom.centroids)
            rows.append(f"| {hmin} | {name} | {m.nv} | {t:.2f} | "
                        f"{np.percentile(smallest_angles(geom), 5):.1f} | {np.median(ratio):.2f} "
                        f"| {np.percentile(ratio, 95):.2f} |")
    return rows


def main(argv: list[str]) -> int:
    threads = int(argv[argv.index("--threads") + 1]) if "--threads" in argv else 1
    ngs.SetNumThreads(threads)
    logging.basicConfig(level=logging.WARNING)
    quick = "--quick" in argv
    print("\n".join(regeneration_table(quick)), end="\n\n", flush=True)
    print("\n".join(bisection_table(quick)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
