"""Meshes for scene geometries, with named boundaries."""
from __future__ import annotations

import ngsolve as ngs
from netgen.geom2d import SplineGeometry

from .scene import Geometry


def netgen_geometry(geometry: Geometry) -> SplineGeometry:
    """The Netgen geometry of a rectangle with boundaries bottom, right, top, left."""
    x0, y0 = geometry.origin
    geo = SplineGeometry()
    geo.AddRectangle((x0, y0), (x0 + geometry.width, y0 + geometry.height),
                     bcs=list(Geometry.BOUNDARIES))
    return geo


def build_mesh(geometry: Geometry, maxh: float) -> ngs.Mesh:
    """A quasi-uniform triangular mesh of the scene geometry.

    Parameters
    ----------
    geometry : Geometry
        The scene's domain.
    maxh : float
        Maximal element size.
    """
    if maxh <= 0:
        raise ValueError(f"maxh must be > 0, got {maxh}")
    return ngs.Mesh(netgen_geometry(geometry).GenerateMesh(maxh=maxh))
