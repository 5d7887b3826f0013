"""The crack as a set of mesh nodes: its connected part, its ridge, its tip and its length.

The crack set is the connected part of ``{z >= 1/2}`` (at the Lagrange nodes of z, connected
through the elements) that touches an initial crack; with no initial crack, the part that
holds the point where damage first reached 1/2. Damage elsewhere (a loaded face, a clamped
corner, a second nucleation) forms other components: it is counted (``n_damage_zones``),
never taken for the crack.

Along the crack set, ``s`` is the distance from the initial crack through the set (Dijkstra on
the node graph, edge lengths as weights). A node is on the *ridge* when no neighbour across
the band (offset within 45 degrees of the normal to the local direction of growth, the
direction in which ``s`` increases) has a larger z: the ridge is where z is largest across the
band. The tip is the end of the ridge: the mean of the crack nodes farthest in the direction
of growth in the 40-degree cone ahead of the ridge node with the largest ``s`` (or ahead of
the initial tip, along the first crack's last segment, when no ridge node lies beyond the
initial band: a crack grown as a diffuse zone). In 3D the crack is a
surface and its front a curve; the tip is the node of the crack set farthest along it (the
most advanced point of the front), without the ridge test, which needs a 1D crack.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import cached_property
from typing import Sequence

import numpy as np
import ngsolve as ngs
from scipy import sparse
from scipy.sparse import csgraph

from ..fem.elements import ElementGeometry, edge_numbers
from ..physics.cracks import distance_to_cracks
from ..fem.nodal import LagrangeNodes

__all__ = ["CrackSet", "JOINED", "NodeGraph", "find_crack"]

THRESHOLD = 0.5
"""z at and above which a node belongs to a crack or a damage zone."""
ACROSS_COS = math.cos(math.radians(45.0))
"""A neighbour is across the band when its offset is within 45 degrees of the normal to the
direction of growth (a narrower cone holds no neighbour of some P1 nodes)."""
FRONT_COS = math.cos(math.radians(40.0))
"""The tip lies in the cone of 40 degrees ahead of the ridge's end (a damaged corner of the
specimen diagonally ahead, at 45 degrees, stays out)."""


JOINED = ("element", "sub-simplices")
"""How :class:`NodeGraph` joins nodes: all nodes of one element, or the edges of the element's
sub-simplices (P1: the mesh edges; P2: each mesh edge in two halves and the edges between the
midpoints of one element, its 4 or 8 sub-simplices)."""


class NodeGraph:
    """The Lagrange nodes of a P1/P2 space as a graph.

    ``points`` (n, d) are the node coordinates; ``edges`` (m, 2) each pair of neighbours
    once, the smaller number first, in lexicographic order; ``graph`` the symmetric (n, n)
    CSR matrix weighted by edge length, and ``dim`` the mesh dimension. The weights are built
    from one entry per element and pair, and entries of one orientation add up: an edge that
    two elements list in the same order weighs twice its length (kept so that the crack sets
    stay as they were).

    Parameters
    ----------
    mesh : ngsolve.Mesh
    nodes : ngfrac.fem.nodal.LagrangeNodes
        The nodes of z on ``mesh`` (vertices, then edge midpoints).
    joined : {"element", "sub-simplices"}
        Which nodes are neighbours (:data:`JOINED`). The crack set (:func:`find_crack`) uses
        "element"; branch counting (:func:`ngfrac.post.branching.crack_topology_of`)
        "sub-simplices". For P1 the two are the mesh edges.

    """

    def __init__(self, mesh: ngs.Mesh, nodes: LagrangeNodes, joined: str = "element") -> None:
        if joined not in JOINED:
            raise ValueError(f"joined = {joined!r}: must be one of {JOINED}")
        self.points = np.asarray(nodes.points, dtype=float)
        rows, cols = _joined_pairs(mesh, nodes, joined)
        n = len(self.points)
        lengths = np.linalg.norm(self.points[rows] - self.points[cols], axis=1)
        graph = sparse.coo_matrix((lengths, (rows, cols)), shape=(n, n)).tocsr()
        graph = graph.maximum(graph.T)  # symmetric
        self.graph = graph.tocsr()
        self.dim = mesh.dim
        self.scale = float(np.ptp(self.points, axis=0).max()) if n else 0.0
        """The largest extent of the nodes along an axis (the size of the domain)."""

    @cached_property
    def edges(self) -> np.ndarray:
        """Each pair of neighbours once (m, 2), the smaller number first, in lexicographic
        order: the upper triangle of :attr:`graph` (edge lengths are positive, so no pair is
        missing from it)."""
        upper = sparse.triu(self.graph, k=1).tocsr()
        upper.sort_indices()
        return np.column_stack([np.repeat(np.arange(upper.shape[0]), np.diff(upper.indptr)),
                                upper.indices]).astype(np.int64)

    @property
    def n_nodes(self) -> int:
        """The number of nodes."""
        return self.graph.shape[0]


def _joined_pairs(mesh: ngs.Mesh, nodes: LagrangeNodes, joined: str) -> tuple[np.ndarray, np.ndarray]:
    """The neighbour pairs (rows, cols) of :class:`NodeGraph`, one per element and pair
    ("element") or per sub-simplex edge ("sub-simplices"), repeats included."""
    corners = ElementGeometry.of(mesh).vertices
    pairs = list(itertools.combinations(range(corners.shape[1]), 2))
    if nodes.order == 2:
        mids = nodes.nv + edge_numbers(nodes.edge_vertices, corners)
    if joined == "element":
        local = corners if nodes.order == 1 else np.column_stack([corners, mids])
        columns = list(itertools.combinations(range(local.shape[1]), 2))
        return (np.concatenate([local[:, i] for i, _ in columns]),
                np.concatenate([local[:, j] for _, j in columns]))
    if nodes.order == 1:
        edges = np.concatenate([corners[:, [i, j]] for i, j in pairs])
    else:
        halves = np.concatenate([np.column_stack([nodes.edge_vertices[:, k], nodes.nv +
                                                  np.arange(len(nodes.edge_vertices))])
                                 for k in (0, 1)])
        across = np.concatenate([mids[:, [i, j]] for i, j in
                                 itertools.combinations(range(mids.shape[1]), 2)])
        edges = np.concatenate([halves, across])
    return edges[:, 0], edges[:, 1]


@dataclass(frozen=True)
class CrackSet:
    """What :func:`find_crack` found.

    Attributes
    ----------
    tip : (d,) array
        The crack tip (``start`` while the crack has not grown beyond its initial band; NaN
        when nothing is cracked and there is no initial crack).
    ridge : (m, d) array
        The ridge nodes of the crack set in order of ``s`` (2D; in 3D all crack nodes).
    ridge_s : (m,) array
        Their distance along the crack from the initial crack.
    path : (k, d) array
        The grown crack as a polyline from ``start`` along the ridge to the tip (its points
        about ``bin_width`` apart; just ``start`` while not grown). The arcs of
        :func:`ngfrac.post.crackpath.final_ridge` measure the same path another way.
    grown_length : float
        Length of ``path`` (0 while not grown).
    n_damage_zones : int
        Components of ``{z >= 1/2}`` that are not the crack.
    n_crack_nodes : int
        Nodes in the crack set.
    """

    tip: np.ndarray
    ridge: np.ndarray
    ridge_s: np.ndarray
    path: np.ndarray
    grown_length: float
    n_damage_zones: int
    n_crack_nodes: int


def _growth_direction(points: np.ndarray, members: np.ndarray, s: np.ndarray, owner: np.ndarray,
                      neighbours: np.ndarray) -> np.ndarray:
    """Unit gradient of ``s`` at each member: least squares over its neighbours in the crack
    set (zero where it cannot be told, e.g. at the initial crack, where s = 0)."""
    position = np.full(len(points), -1)
    position[members] = np.arange(len(members))
    other = position[neighbours]
    use = other >= 0
    owner, other = owner[use], other[use]
    # np.take gathers rows 2-3x faster than fancy indexing, with the same values
    offset = np.take(points, members[other], axis=0) - np.take(points, members[owner], axis=0)
    ds = s[other] - s[owner]
    dim = points.shape[1]
    normal = np.zeros((len(members), dim, dim))
    rhs = np.zeros((len(members), dim))
    for i in range(dim):
        rhs[:, i] = np.bincount(owner, ds * offset[:, i], minlength=len(members))
        for j in range(dim):
            normal[:, i, j] = np.bincount(owner, offset[:, i] * offset[:, j], minlength=len(members))
    solvable = np.abs(np.linalg.det(normal)) > 1e-12 * np.einsum("kii->k", normal) ** dim
    gradient = np.zeros((len(members), dim))
    gradient[solvable] = np.linalg.solve(normal[solvable], rhs[solvable][..., None])[..., 0]
    norm = np.linalg.norm(gradient, axis=1)
    positive = norm > 0
    gradient[positive] /= norm[positive, None]
    return gradient


def _ridge(graph: sparse.csr_matrix, points: np.ndarray, z: np.ndarray, members: np.ndarray,
           s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mask over ``members`` (indices into the full node set) of the ridge nodes, and the
    direction of growth at each member."""
    sub = graph[members]  # rows: members, columns: all nodes
    indptr, neighbours = sub.indptr, sub.indices
    owner = np.repeat(np.arange(len(members)), np.diff(indptr))
    direction = _growth_direction(points, members, s, owner, neighbours)
    has_direction = np.any(direction != 0, axis=1)
    offset = np.take(points, neighbours, axis=0) - np.take(points, members[owner], axis=0)
    # the norms column by column: what np.linalg.norm(offset, axis=1) sums, in its order,
    # without its strided reduction
    offset /= np.sqrt(sum(offset[:, i] ** 2 for i in range(offset.shape[1])))[:, None]
    along = np.abs(np.einsum("ij,ij->i", offset, np.take(direction, owner, axis=0)))
    across = along <= ACROSS_COS
    higher = across & (z[neighbours] > z[members[owner]])
    blocked = np.bincount(owner[higher], minlength=len(members)) > 0
    return has_direction & ~blocked, direction


def _ridge_path(points: np.ndarray, s: np.ndarray, start: np.ndarray, spacing: float) -> np.ndarray:
    """A polyline along the ridge: from ``start`` through the means of the ridge ``points`` in
    bins of ``s`` (width spacing/2), keeping points at least ``spacing`` apart, to the last
    point (the tip). The means and the spacing keep the zigzag of the nodes across the band
    (about h/2) out of the length: it adds ~(h/4 / spacing)^2 / 2 relative."""
    bins = np.floor(np.minimum(s, s[np.isfinite(s)].max(initial=0.0) + spacing) / (0.5 * spacing)).astype(np.int64)
    unique, inverse = np.unique(bins, return_inverse=True)
    means = np.zeros((len(unique), points.shape[1]))
    np.add.at(means, inverse, points)
    means /= np.bincount(inverse)[:, None]
    kept = [start]
    for point in means[:-1]:
        if np.linalg.norm(point - kept[-1]) >= spacing:
            kept.append(point)
    kept.append(points[-1])
    return np.array(kept)


def find_crack(graph: NodeGraph, z_values: np.ndarray, cracks: Sequence[Sequence[Sequence[float]]],
               start: np.ndarray | None, band: float, bin_width: float,
               nucleus: np.ndarray | None = None, previous_tip: np.ndarray | None = None) -> CrackSet:
    """The crack set of a z field, its ridge, tip, grown length and the other damage zones.

    Parameters
    ----------
    graph : NodeGraph
        The nodes of z and how they connect.
    z_values : (n,) array
        z at the nodes.
    cracks : list of polylines (2D) or planar polygons (3D)
        The initial cracks; the crack set is what of ``{z >= 1/2}`` is connected to them.
    start : (d,) array or None
        The tip before the crack grows (:func:`ngfrac.physics.cracks.initial_tip`).
    band : float
        How far along the crack the initial band reaches (where the crack model's profile
        falls to 1/2, plus an element; AT2: ``epsilon ln 2 + h``): a tip closer than this to
        the initial crack is still ``start``.
    bin_width : float
        Spacing of the points of the grown crack's polyline (a few epsilon).
    nucleus : (d,) array, optional
        With no initial crack: the point where damage first reached 1/2 (the crack is the
        component nearest to it).
    previous_tip : (d,) array, optional
        The tip found before (2D): z never decreases, so that point is still on the crack;
        when the new front lies behind it in the direction of growth, it stays the tip (the
        front's estimate scatters by about an element).
    """
    points = graph.points
    dim = points.shape[1]
    cracked = np.flatnonzero(np.asarray(z_values) >= THRESHOLD)
    start = None if start is None else np.asarray(start, dtype=float)[:dim]
    none = np.full(dim, np.nan) if start is None else start
    nothing = np.zeros((0, dim))

    def not_grown(tip: np.ndarray, ridge_points: np.ndarray = nothing, ridge_s: np.ndarray = nothing[:, 0],
                  n_zones: int = 0, n_members: int = 0) -> CrackSet:
        return CrackSet(tip, ridge_points, ridge_s, tip[None, :], 0.0, n_zones, n_members)

    if len(cracked) == 0:
        return not_grown(none)
    sub = graph.graph[cracked][:, cracked]
    n_components, labels = csgraph.connected_components(sub, directed=False)
    seeds = _seeds(points, cracked, sub, cracks, nucleus, graph.scale)
    if seeds is None:
        return not_grown(none, n_zones=n_components)
    crack_labels = np.unique(labels[seeds])
    in_crack = np.isin(labels, crack_labels)
    members = cracked[in_crack]
    member_graph = sub[in_crack][:, in_crack]
    sources = np.flatnonzero(seeds[in_crack])
    s = csgraph.dijkstra(member_graph, directed=False, indices=sources, min_only=True)
    if dim == 2:
        ridge, direction = _ridge(graph.graph, points, np.asarray(z_values), members, s)
    else:
        ridge, direction = np.isfinite(s), None
    ridge &= np.isfinite(s)
    order = np.argsort(s[ridge], kind="stable")
    ridge_points, ridge_s = points[members[ridge]][order], s[ridge][order]
    n_zones = n_components - len(crack_labels)
    ridge_grown = len(ridge_s) > 0 and ridge_s[-1] > band
    not_grown_tip = start if start is not None else (ridge_points[-1] if len(ridge_s) else none)
    ridge_direction = None if direction is None else direction[ridge][order]
    end_heading = _end_and_heading(ridge_points, ridge_s, ridge_direction, ridge_grown, cracks,
                                   start, bin_width)
    if end_heading is None:
        return not_grown(not_grown_tip, ridge_points, ridge_s, n_zones, len(members))
    end, heading = end_heading
    tip = end
    if heading is not None and np.linalg.norm(heading) > 0:
        tip = _front(points[members], s, end, heading / np.linalg.norm(heading), 0.25 * bin_width)
    if heading is not None and previous_tip is not None and np.all(np.isfinite(previous_tip)):
        before = np.asarray(previous_tip, dtype=float)[:dim]
        if (tip - before) @ heading < 0:  # the new front lies behind the old tip
            tip = before
    if not ridge_grown and np.linalg.norm(tip - start) <= band:
        return not_grown(not_grown_tip, ridge_points, ridge_s, n_zones, len(members))
    grown = ridge_s > band
    origin = start if start is not None else ridge_points[0]
    path = _ridge_path(np.vstack([ridge_points[grown], tip]), np.append(ridge_s[grown], np.inf),
                       origin, bin_width)
    length = float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
    return CrackSet(tip, ridge_points, ridge_s, path, length, n_zones, len(members))


def _seeds(points: np.ndarray, cracked: np.ndarray, sub: sparse.csr_matrix,
           cracks: Sequence[Sequence[Sequence[float]]], nucleus: np.ndarray | None,
           scale: float) -> np.ndarray | None:
    """Mask over the ``cracked`` nodes of those the crack set grows from: the nodes on the
    initial cracks or, with none, the one nearest to ``nucleus``; None without either."""
    if cracks:
        distance = distance_to_cracks(points[cracked], cracks)
        # the nodes on the initial cracks (they are mesh edges/faces; on a mesh that does not
        # follow them, the nodes within half an element of them)
        return distance <= max(1e-9 * scale, float(distance.min()) + 0.5 * float(np.median(sub.data)))
    if nucleus is not None:
        dim = points.shape[1]
        nearest = int(np.argmin(np.linalg.norm(points[cracked] - np.asarray(nucleus)[:dim], axis=1)))
        return np.arange(len(cracked)) == nearest
    return None


def _end_and_heading(ridge_points: np.ndarray, ridge_s: np.ndarray, direction: np.ndarray | None,
                     ridge_grown: bool, cracks: Sequence[Sequence[Sequence[float]]],
                     start: np.ndarray | None, bin_width: float
                     ) -> tuple[np.ndarray, np.ndarray | None] | None:
    """Where the front search starts and the direction of growth there (None in 3D); None
    when the crack has not grown. ``direction``: the growth direction at the ridge points
    (2D), None in 3D."""
    dim = ridge_points.shape[1]
    if dim == 2 and ridge_grown:
        # the ridge's end and the direction there, from the ridge nodes near it and a little
        # behind it (where z is nearly flat across a wide front, single nodes and the
        # gradient of s scatter across the band)
        end = ridge_points[ridge_s >= ridge_s[-1] - 0.25 * bin_width].mean(axis=0)
        behind = (ridge_s >= ridge_s[-1] - 2 * bin_width) & (ridge_s <= ridge_s[-1] - 0.5 * bin_width)
        return end, end - ridge_points[behind].mean(axis=0) if np.any(behind) else direction[-1]
    if dim == 2 and cracks and start is not None:
        # a crack that grew as a diffuse zone (z falls along it as fast as across, so no node
        # ahead of the initial band passes the ridge test): its front from the initial tip,
        # in the direction of the first crack's last segment
        return start, np.asarray(cracks[0][-1], dtype=float) - np.asarray(cracks[0][-2], dtype=float)
    if ridge_grown:  # 3D: the most advanced node of the crack set
        return ridge_points[-1], None
    return None


def _front(points: np.ndarray, s: np.ndarray, ridge_end: np.ndarray, direction: np.ndarray,
           depth: float) -> np.ndarray:
    """The tip: the mean of the crack nodes in the cone of 40 degrees ahead of the ridge's
    end that lie within ``depth`` of the farthest one in the direction of growth. (Where the
    band rounds off, z falls towards 1/2 in every direction, so the ridge test stops a little
    behind the z = 1/2 front; a damaged corner beside the ridge's end, where the crack met a
    boundary, is not ahead of it; the mean keeps a flat front's scatter out.)"""
    offset = points - ridge_end
    along = offset @ direction
    ahead = (along >= FRONT_COS * np.linalg.norm(offset, axis=1)) & np.isfinite(s)
    if not np.any(ahead):
        return ridge_end
    front = ahead & (along >= along[ahead].max() - depth)
    return points[front].mean(axis=0)
