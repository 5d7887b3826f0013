"""Lagrange-node values of P1/P2 fields in NGSolve's hierarchical H1 basis.

NGSolve's H1 space of order 2 stores vertex values and, per edge, the coefficient c_e of a
quadratic edge bubble. The value at the edge midpoint is ``(u_a + u_b)/2 + beta c_e`` with a
fixed ``beta`` (-1/8 in 6.2.2608; measured here, not assumed). Pointwise operations such as
the bounds ``0 <= z <= 1`` and the non-repair condition ``z >= z_old`` must act on these node
values, not on the hierarchical coefficients; this module converts between the two.
"""
from __future__ import annotations

import numpy as np
import ngsolve as ngs

from .threads import meshing_threads


def vertex_dofs_first(fes: ngs.FESpace) -> bool:
    """Whether a scalar H1 space numbers one dof per vertex first, in vertex order (NGSolve's
    hierarchical basis does): then its first nv coefficients are the vertex values."""
    nv = fes.mesh.nv
    return bool(nv) and fes.ndof >= nv and tuple(fes.GetDofNrs(ngs.NodeId(ngs.VERTEX, nv - 1))) == (nv - 1,)


class LagrangeNodes:
    """Node coordinates and value conversion for an order 1 or 2 ``H1`` space.

    Parameters
    ----------
    fes : ngsolve.H1
        A scalar H1 space of order 1 or 2 (2D or 3D).
    """

    def __init__(self, fes: ngs.FESpace) -> None:
        order = fes.globalorder
        if order not in (1, 2):
            raise ValueError(f"LagrangeNodes supports H1 of order 1 or 2, got order {order}")
        mesh = fes.mesh
        self.fes = fes
        self.order = order
        vertices = np.array(mesh.ngmesh.Coordinates())[:, : mesh.dim]
        nv = mesh.nv
        if order == 1 or mesh.ne == 0:  # no elements: rank 0 of a distributed mesh
            self.edge_vertices = np.zeros((0, 2), dtype=int)
            self.points = vertices
            self.beta = 1.0
            self._edge_dofs = np.zeros(0, dtype=int)
        else:
            pairs = np.array([(e.vertices[0].nr, e.vertices[1].nr) for e in mesh.edges], dtype=int)
            self.edge_vertices = pairs
            # Edge dofs follow the vertex dofs in edge order for a uniform order-2 space.
            self._edge_dofs = nv + np.arange(len(pairs))
            first = fes.GetDofNrs(ngs.NodeId(ngs.EDGE, 0))
            if fes.ndof != nv + len(pairs) or tuple(first) != (nv,):
                raise RuntimeError("unexpected dof layout of the order-2 H1 space")
            self.points = np.vstack([vertices, 0.5 * (vertices[pairs[:, 0]] + vertices[pairs[:, 1]])])
            if mesh.GetCurveOrder() > 1:
                self._curved_midpoints(mesh, vertices)
            if mesh.comm.size > 1:  # point evaluation is not local on a distributed mesh
                self.beta = _reference_beta(mesh.dim)
            else:
                self.beta = self._midpoint_bubble_value(fes, vertices, pairs)
        self.nv = nv

    def _curved_midpoints(self, mesh: ngs.Mesh, vertices: np.ndarray) -> None:
        """On a curved mesh the edge node of a curved (boundary) edge is the image of the
        reference midpoint, not the chord's midpoint (which may lie outside the mesh)."""
        dim = mesh.dim
        corners = (np.array([[0.0], [1.0]]) if dim == 2
                   else np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]))
        nv = mesh.nv
        for el in mesh.Elements(ngs.BND):
            trafo = mesh.GetTrafo(ngs.ElementId(el))
            mapped = np.array([list(trafo(*c).point) for c in corners])
            local = {}  # global vertex -> reference coordinates
            for v in el.vertices:
                k = int(np.argmin(np.linalg.norm(mapped - vertices[v.nr], axis=1)))
                local[v.nr] = corners[k]
            for edge in el.edges:
                a, b = (v.nr for v in mesh[edge].vertices)
                middle = 0.5 * (local[a] + local[b])
                self.points[nv + edge.nr] = np.array(list(trafo(*middle).point))

    @staticmethod
    def _midpoint_bubble_value(fes: ngs.FESpace, vertices: np.ndarray, pairs: np.ndarray) -> float:
        gf = ngs.GridFunction(fes)
        gf.vec[:] = 0
        gf.vec[int(fes.mesh.nv)] = 1.0
        mid = 0.5 * (vertices[pairs[0, 0]] + vertices[pairs[0, 1]])
        beta = float(gf(fes.mesh(*mid)))
        if abs(beta) < 1e-12:
            raise RuntimeError("edge bubble vanishes at the midpoint; unexpected basis")
        return beta

    @property
    def n_nodes(self) -> int:
        return len(self.points)

    def values(self, gf: ngs.GridFunction) -> np.ndarray:
        """Node values (vertices first, then edge midpoints) of a GridFunction."""
        coeffs = gf.vec.FV().NumPy()
        if self.order == 1:
            return coeffs.copy()
        vert = coeffs[: self.nv]
        mean = 0.5 * (vert[self.edge_vertices[:, 0]] + vert[self.edge_vertices[:, 1]])
        return np.concatenate([vert, mean + self.beta * coeffs[self._edge_dofs]])

    def assign(self, gf: ngs.GridFunction, node_values: np.ndarray) -> None:
        """Set a GridFunction so that it takes the given node values.

        The round trip ``values(gf)`` returns every node value at least as large as given
        (equal up to an ulp), and never above 1 where the given value is at most 1, so
        bounds and non-repair hold exactly, not only up to round-off.
        """
        coeffs = gf.vec.FV().NumPy()
        node_values = np.asarray(node_values, dtype=float)
        if node_values.shape != (self.n_nodes,):
            raise ValueError(f"expected {self.n_nodes} node values, got {node_values.shape}")
        if self.order == 1:
            coeffs[:] = node_values
            return
        vert = node_values[: self.nv]
        coeffs[: self.nv] = vert
        mean = 0.5 * (vert[self.edge_vertices[:, 0]] + vert[self.edge_vertices[:, 1]])
        coeffs[self._edge_dofs] = self._edge_coefficients(mean, node_values[self.nv:])

    def coefficient_matrix(self) -> "scipy.sparse.csr_matrix":
        """The sparse map T from node values to the space's coefficients (``c = T v``).

        Identity for P1; for P2 ``c_e = (v_e - (v_a + v_b)/2) / beta`` on each edge. A
        matrix ``A`` and vector ``f`` of the space become ``T^T A T`` and ``T^T f`` in the
        node basis, where bounds at the nodes are bounds on single unknowns.
        """
        import scipy.sparse as sp

        n = self.n_nodes
        if self.order == 1:
            return sp.identity(n, format="csr")
        ne = len(self.edge_vertices)
        edges = self.nv + np.arange(ne)
        rows = np.concatenate([np.arange(self.nv), edges, edges, edges])
        cols = np.concatenate([np.arange(self.nv), edges, self.edge_vertices[:, 0],
                               self.edge_vertices[:, 1]])
        vals = np.concatenate([np.ones(self.nv), np.full(ne, 1.0 / self.beta),
                               np.full(2 * ne, -0.5 / self.beta)])
        return sp.csr_matrix((vals, (rows, cols)), shape=(n, n))

    def _edge_coefficients(self, mean: np.ndarray, target: np.ndarray) -> np.ndarray:
        """Edge coefficients whose midpoint values, as :meth:`values` computes them, are
        at least ``target`` and, where ``target <= 1``, at most 1.

        ``(target - mean) / beta`` alone loses an ulp or so in the round trip (measured
        1.7e-21 at z ~ 1e-5), which breaks ``z >= z_old`` and ``z <= 1`` in exact
        arithmetic. A step of one ulp in a coefficient moves the value by ``|beta|`` times
        that, below one ulp of the value, so a few steps reach the target from above.
        """
        coefficient = (target - mean) / self.beta
        raise_value = -np.inf if self.beta < 0 else np.inf  # direction in c that raises the value
        for _ in range(64):
            low = mean + self.beta * coefficient < target
            if not low.any():
                break
            coefficient[low] = np.nextafter(coefficient[low], raise_value)
        for _ in range(64):
            value = mean + self.beta * coefficient
            high = (value > 1.0) & (value > target)
            if not high.any():
                break
            coefficient[high] = np.nextafter(coefficient[high], -raise_value)
        return coefficient


def _reference_beta(dim: int) -> float:
    """The midpoint value of the edge bubble, measured on a serial mesh of dimension ``dim``."""
    if dim == 2:
        from netgen.geom2d import unit_square as geometry
    else:
        from netgen.csg import unit_cube as geometry
    mesh = ngs.Mesh(geometry.GenerateMesh(maxh=1.0, **meshing_threads()))
    fes = ngs.H1(mesh, order=2)
    vertices = np.array(mesh.ngmesh.Coordinates())[:, :dim]
    pairs = np.array([(e.vertices[0].nr, e.vertices[1].nr) for e in mesh.edges], dtype=int)
    return LagrangeNodes._midpoint_bubble_value(fes, vertices, pairs)
