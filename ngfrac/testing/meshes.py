"""Meshes graded to a crack and its optimal profile, for the transfer tests and benchmarks."""
from __future__ import annotations

from typing import Sequence

import numpy as np
import ngsolve as ngs

from ..mesh.remesh import ElementGeometry, adapt_mesh, enforce_crack_sizes
from ..physics.cracks import distance_to_polylines, optimal_profile
from ..scene import Geometry
from ..solve.nodal import LagrangeNodes

__all__ = ["UNIT_SQUARE", "HALF_SLIT", "profile_field", "crack_mesh"]

UNIT_SQUARE = Geometry(width=1.0, height=1.0)
"""The unit square (boundaries bottom, right, top, left)."""
HALF_SLIT = [[(0.0, 0.5), (0.5, 0.5)]]
"""A straight crack from the left edge to the centre of the unit square."""


def profile_field(mesh: ngs.Mesh, order: int, epsilon: float,
                  cracks: Sequence = HALF_SLIT) -> ngs.GridFunction:
    """z = exp(-d/epsilon) at the Lagrange nodes of order ``order``, d the distance to ``cracks``."""
    fes = ngs.H1(mesh, order=order)
    z = ngs.GridFunction(fes, "z")
    nodes = LagrangeNodes(fes)
    nodes.assign(z, optimal_profile(distance_to_polylines(nodes.points, cracks), epsilon))
    return z


def crack_mesh(start: ngs.Mesh, *, h_band: float, h_core: float, hmax: float, width: float,
               epsilon: float, cracks: Sequence = HALF_SLIT, geometry: Geometry = UNIT_SQUARE,
               order: int = 2) -> ngs.Mesh:
    """Two mesh changes from ``start``: h <= h_band within ``width`` of the cracks, h <= h_core
    where the profile (:func:`profile_field`) has z >= 0.6, hmax elsewhere."""
    mesh = start
    for _ in range(2):
        geom = ElementGeometry.of(mesh)
        band = distance_to_polylines(geom.centroids, cracks) < width
        sizes = enforce_crack_sizes(mesh, np.where(band, h_band, hmax),
                                    z=profile_field(mesh, order, epsilon, cracks), z_level=0.6,
                                    h_crack=h_core)
        mesh = adapt_mesh(mesh, geometry, sizes, hmax=hmax, max_vertices=10**6)
    return mesh
