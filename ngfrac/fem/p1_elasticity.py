"""The degraded P1 stiffness matrix from element weights, without NGSolve's element loop.

For P1 u on straight simplices the strain of every basis function is constant in each
element, so with constant Lame constants the matrix of ``int g(z) sigma[u]:e[v] dx`` is

    A = sum_T  mean_T(g(z))  K_T,

K_T being the element's matrix of ``int_T sigma[u]:e[v] dx``. For P1 z and
``g = (1 - z)^2 + eta`` the mean is exact from the vertex values ``w = 1 - z``:
``mean(w^2) = (sum w_i^2 + (sum w_i)^2) / ((d + 1)(d + 2))``. The K_T and the position of each
of their entries in the assembled matrix are computed once per mesh; an assembly is then one
sparse matrix-vector product ``values = M g`` written into the matrix NGSolve assembled first
(same sparsity, same dof numbers), so its factorization and solvers see the same object.
Only the entries on and below the diagonal are weighted (K_T is symmetric); each entry above
is copied from its mirror (78 of 144 weights per tetrahedron). Its sums run in a fixed order on
one thread: the values do not depend on the thread count.
"""
from __future__ import annotations

import numpy as np
import ngsolve as ngs
import scipy.sparse as sp

from .elements import ElementGeometry
from .nodal import vertex_dofs_first

__all__ = ["P1ElasticStiffness"]


def _barycentric_gradients(corners: np.ndarray) -> np.ndarray:
    """Gradients (ne, d+1, d) of the barycentric coordinates of simplices with ``corners``
    (ne, d+1, d)."""
    edges = corners[:, 1:] - corners[:, :1]  # (ne, d, d), rows = edge vectors
    inverse = np.linalg.inv(edges)  # column k: gradient of lambda_{k+1}
    gradients = np.empty(corners.shape)
    gradients[:, 1:] = np.transpose(inverse, (0, 2, 1))
    gradients[:, 0] = -gradients[:, 1:].sum(axis=1)
    return gradients


def element_stiffness(geom: ElementGeometry, lam: float, mu: float) -> np.ndarray:
    """K_T (ne, (d+1) d, (d+1) d) of ``int_T 2 mu e[u]:e[v] + lam div u div v`` for the P1
    basis ``phi_a e_i`` ordered vertex-major (a, i)."""
    gradients = _barycentric_gradients(geom.coordinates[geom.vertices])
    measures = geom.measures
    ne, n_corners, d = gradients.shape
    g = gradients
    gt = np.transpose(g, (0, 2, 1))  # (T, i, b)
    dots = mu * np.matmul(g, gt)  # mu G_a . G_b
    k = np.empty((ne, n_corners, d, n_corners, d))  # (T, a, i, b, j)
    term = np.empty((ne, d, n_corners, d))
    for a in range(n_corners):  # one corner at a time: temporaries of a quarter (a third) of k
        ka = k[:, a]
        np.multiply(g[:, a, :, None, None], g[:, None, :, :], out=ka)  # G_ai G_bj
        ka *= lam
        np.multiply(g[:, a, None, None, :], gt[:, :, :, None], out=term)  # G_aj G_bi
        term *= mu
        ka += term
        for i in range(d):
            ka[:, i, :, i] += dots[:, a]
        ka *= measures[:, None, None, None]
    return k.reshape(ne, n_corners * d, n_corners * d)


def _positions(keys: np.ndarray, wanted: np.ndarray, missing: str) -> np.ndarray:
    """Where each of ``wanted`` stands in the ascending ``keys`` (row * n + column of a CSR
    pattern); a ValueError saying ``missing`` if one of them is not there."""
    found = np.searchsorted(keys, wanted)
    if np.any(found >= keys.size) or np.any(keys[np.minimum(found, keys.size - 1)] != wanted):
        raise ValueError(f"P1ElasticStiffness: {missing}")
    return found


def _neighbour_ranks(vertices: np.ndarray, columns: np.ndarray, starts: np.ndarray,
                     nv: int) -> np.ndarray:
    """rank[T, a, b]: where vertex b of element T stands among the neighbours of its vertex a
    (the sorted columns below nv of the row of dof a), from the matrix's CSR arrays."""
    rows = np.repeat(np.arange(nv, dtype=np.int64), np.diff(starts[: nv + 1]))
    first = columns[: starts[nv]]  # the rows of dofs 0..nv-1
    block = first < nv  # the first component's block of each of those rows
    keys = rows[block] * nv + first[block]
    offsets = (np.arange(starts[nv]) - starts[rows])[block]
    n_corners = vertices.shape[1]
    wanted = (np.repeat(vertices, n_corners, axis=1) * nv + np.tile(vertices, (1, n_corners))).ravel()
    found = _positions(keys, wanted, "an element's vertex pair is not in the matrix")
    return offsets[found].reshape(len(vertices), n_corners, n_corners)


def _upper_entries(columns: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The positions of a structurally symmetric CSR matrix's entries above the diagonal and,
    for each, the position of its mirror below it."""
    n = len(starts) - 1
    rows = np.repeat(np.arange(n, dtype=np.int64), np.diff(starts.astype(np.int64)))
    columns = columns.astype(np.int64)
    upper = np.flatnonzero(columns > rows)
    keys = rows * n + columns  # ascending: rows in order, columns sorted in each row
    wanted = columns[upper] * n + rows[upper]
    mirror = _positions(keys, wanted, "the matrix's sparsity is not symmetric")
    index = np.int32 if keys.size < 2 ** 31 else np.int64
    return upper.astype(index), mirror.astype(index)


class P1ElasticStiffness:
    """``int ((1 - z)^2 + eta) sigma[u]:e[v] dx`` for P1 u and P1 z, assembled by element
    weights into a matrix NGSolve assembled for the same form (module docstring).

    Parameters
    ----------
    mat : ngsolve.la.SparseMatrixd
        The assembled matrix of the form (its sparsity and dof numbers are used; its values
        are overwritten by :meth:`assemble`).
    fes_u : ngsolve.FESpace
        The order-1 ``VectorH1`` space of u (component-blocked dofs: c nv + vertex).
    lam, mu : float
        The Lame constants of the form (plane stress: the effective lam).
    eta : float
        The residual stiffness.
    """

    def __init__(self, mat: ngs.BaseMatrix, fes_u: ngs.FESpace, lam: float, mu: float,
                 eta: float) -> None:
        mesh = fes_u.mesh
        geom = ElementGeometry.of(mesh)
        d, nv = mesh.dim, mesh.nv
        # held: the value array written below is the matrix's own memory
        self.mat, self.eta, self.vertices = mat, eta, geom.vertices
        values, columns, starts = mat.CSR()
        self._values = np.asarray(values)
        starts = np.asarray(starts).astype(np.int64)
        vertices = geom.vertices
        # the rows of the first component suffice (the others repeat their pattern)
        rank = _neighbour_ranks(vertices, np.asarray(columns)[: starts[nv]].astype(np.int64),
                                starts, nv)
        index = np.int32 if self._values.size < 2 ** 31 else np.int64
        starts, rank = starts.astype(index), rank.astype(index)
        # a row of dof (i, v) holds the columns (j, w) of v's neighbours w, block j after block
        # i: its entry (j, w) sits at start(i, v) + j deg(v) + rank_v(w)
        components = np.arange(d, dtype=index)
        row_start = starts[vertices[:, :, None] + nv * components]  # (ne, d+1, d)
        degree = (starts[vertices + 1] - starts[vertices]) // d  # (ne, d+1)
        position = (row_start[:, :, :, None, None]
                    + (degree[:, :, None, None, None] * components)
                    + rank[:, :, None, :, None])  # (ne, a, i, b, j)
        k = element_stiffness(geom, lam, mu).reshape(position.shape)
        # the entries on and below the diagonal: row dof (i, v_a) >= column dof (j, v_b)
        row_dof = (components[None, None, :] * nv + vertices[:, :, None]).astype(np.int64)
        lower = (row_dof[:, :, :, None, None] >= row_dof[:, None, None, :, :]).reshape(len(k), -1)
        n_local = int(lower[0].sum())  # the same count in every element: (n + 1) n / 2
        # column T of the weights holds K_T's lower half at its positions in the value array
        self._weights = sp.csc_matrix(
            (k.reshape(len(k), -1)[lower], position.reshape(len(k), -1)[lower],
             np.arange(0, n_local * len(k) + 1, n_local)), shape=(self._values.size, len(k)))
        del k, position
        self._upper, self._mirror = _upper_entries(np.asarray(columns), starts)
        self._denominator = float((d + 1) * (d + 2))

    @staticmethod
    def applies(fes_u: ngs.FESpace, fes_z: ngs.FESpace) -> bool:
        """Whether u and z are order-1 spaces whose dofs are numbered as this class assumes
        (vertex values; u component c of vertex v at c nv + v)."""
        mesh = fes_u.mesh
        nv, d = mesh.nv, mesh.dim
        if fes_u.globalorder != 1 or fes_z.globalorder != 1 or nv == 0:
            return False
        if fes_u.ndof != d * nv or fes_z.ndof != nv:
            return False
        last = ngs.NodeId(ngs.VERTEX, nv - 1)
        return (tuple(fes_u.GetDofNrs(last)) == tuple(c * nv + nv - 1 for c in range(d))
                and vertex_dofs_first(fes_z))

    def writes_into(self, mat: ngs.BaseMatrix) -> bool:
        """Whether ``mat`` (a form's current matrix) is the matrix this was built on (the same
        value array): NGSolve makes a new one when the space changes."""
        values = mat.CSR()[0] if isinstance(mat, ngs.la.SparseMatrixd) else None
        return (values is not None and len(values) == self._values.size
                and np.asarray(values).ctypes.data == self._values.ctypes.data)

    def element_degradation(self, z: np.ndarray) -> np.ndarray:
        """mean_T((1 - z)^2) + eta per element, from the vertex values of z."""
        w = 1.0 - z[self.vertices]
        return (np.sum(w * w, axis=1) + np.sum(w, axis=1) ** 2) / self._denominator + self.eta

    def assemble(self, z: ngs.GridFunction) -> None:
        """Write the matrix for ``z`` into :attr:`mat`."""
        values = self._weights @ self.element_degradation(z.vec.FV().NumPy())
        values[self._upper] = values[self._mirror]
        self._values[:] = values
