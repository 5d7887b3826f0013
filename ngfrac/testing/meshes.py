"""Meshes graded to a crack and its optimal profile, for the transfer tests and benchmarks."""
from __future__ import annotations

from typing import Sequence

import numpy as np
import ngsolve as ngs

from ..fem.elements import ElementGeometry, edge_numbers
from ..mesh.remesh import adapt_mesh
from ..physics.cracks import distance_to_polylines, optimal_profile
from ..scene import Geometry
from ..fem.nodal import LagrangeNodes

__all__ = ["UNIT_SQUARE", "HALF_SLIT", "crack_mesh", "element_maximum", "profile_field"]

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


def element_maximum(z: ngs.GridFunction) -> np.ndarray:
    """Largest Lagrange-node value of z on each element."""
    nodes = LagrangeNodes(z.space)
    index = ElementGeometry.of(z.space.mesh).vertices
    if nodes.order == 2:
        index = np.hstack([index, nodes.nv + edge_numbers(nodes.edge_vertices, index)])
    return nodes.values(z)[index].max(axis=1)


def crack_mesh(start: ngs.Mesh, *, h_band: float, h_core: float, hmax: float, width: float,
               epsilon: float, cracks: Sequence = HALF_SLIT, geometry: Geometry = UNIT_SQUARE,
               order: int = 2) -> ngs.Mesh:
    """Two mesh changes from ``start``: h <= h_band within ``width`` of the cracks, h <= h_core
    where the profile (:func:`profile_field`) has z >= 0.6, hmax elsewhere."""
    mesh = start
    for _ in range(2):
        geom = ElementGeometry.of(mesh)
        band = distance_to_polylines(geom.centroids, cracks) < width
        sizes = np.where(band, h_band, hmax)
        cracked = element_maximum(profile_field(mesh, order, epsilon, cracks)) >= 0.6
        sizes = np.where(cracked, np.minimum(sizes, h_core), sizes)
        mesh = adapt_mesh(mesh, geometry, sizes, hmax=hmax, max_vertices=10**6)
    return mesh
