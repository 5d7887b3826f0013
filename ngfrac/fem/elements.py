"""Element geometry of a simplicial mesh as arrays (vertices, centroids, measures, sizes)."""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
import ngsolve as ngs

__all__ = ["ElementGeometry", "edge_numbers"]


@dataclass(frozen=True)
class ElementGeometry:
    """Per-element geometry of a simplicial mesh, in NGSolve's element order.

    Attributes
    ----------
    vertices : (ne, d+1) int array
        Vertex numbers (NGSolve's, from 0).
    coordinates : (nv, d) array
    centroids : (ne, d) array
    measures : (ne,) array
        Areas (2D) or volumes (3D).
    diameters : (ne,) array
        Longest edge, the h of the element (Netgen's maxh is a longest edge).
    radii : (ne,) array
        Largest distance from the centroid to a vertex.
    """

    vertices: np.ndarray
    coordinates: np.ndarray
    centroids: np.ndarray
    measures: np.ndarray
    diameters: np.ndarray
    radii: np.ndarray

    @property
    def dim(self) -> int:
        return self.coordinates.shape[1]

    @classmethod
    def of(cls, mesh: ngs.Mesh) -> "ElementGeometry":
        """Read the geometry of the volume elements of ``mesh`` (first order, simplices)."""
        dim = mesh.dim
        coords = np.array(mesh.ngmesh.Coordinates())[:, :dim]
        elements = mesh.ngmesh.Elements2D() if dim == 2 else mesh.ngmesh.Elements3D()
        vertices = elements.NumPy()["nodes"][:, : dim + 1].astype(int) - 1  # Netgen counts from 1
        corners = coords[vertices]
        centroids = corners.mean(axis=1)
        edges = corners[:, 1:] - corners[:, :1]
        measures = np.abs(np.linalg.det(edges)) / math.factorial(dim)
        diameters = np.zeros(len(vertices))
        for i, j in itertools.combinations(range(dim + 1), 2):
            np.maximum(diameters, np.linalg.norm(corners[:, i] - corners[:, j], axis=1), out=diameters)
        radii = np.linalg.norm(corners - centroids[:, None, :], axis=2).max(axis=1)
        return cls(vertices, coords, centroids, measures, diameters, radii)


def edge_numbers(edge_vertices: np.ndarray, element_vertices: np.ndarray) -> np.ndarray:
    """Edge numbers (rows of ``edge_vertices``) of each element's edges, vectorised."""
    nv = int(max(edge_vertices.max(), element_vertices.max())) + 1
    keys = np.sort(edge_vertices, axis=1) @ np.array([nv, 1])
    order = np.argsort(keys)
    pairs = list(itertools.combinations(range(element_vertices.shape[1]), 2))
    local = np.stack([np.sort(element_vertices[:, [i, j]], axis=1) @ np.array([nv, 1])
                      for i, j in pairs], axis=1)
    found = order[np.searchsorted(keys[order], local)]
    if not np.array_equal(keys[found], local):
        raise RuntimeError("an element edge is missing from the edge list")
    return found
