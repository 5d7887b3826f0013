"""Branch counting: how many cracks, ends and branch points the phase field z has.

The crack set is the part of ``{z >= level}`` (level 1/2) at the Lagrange nodes, connected
through mesh edges. Each connected part is one crack. Its shape is read from a Reeb graph of
the graph distance inside the crack: starting from one end of the crack (the node farthest
from an arbitrary node of it, a double sweep), nodes are grouped into shells of width
``spacing`` along that distance, and the connected pieces of each shell are joined to the
pieces of the next shell that share a mesh edge with them. A band of any width becomes a
chain of pieces; where the crack forks, a piece has two successors. Successors that stop
within ``min_length`` of the fork are spurs of a lumpy band, not branches, and are pruned.

So a straight crack has 2 ends and 0 branch points, a Y-shaped crack 3 ends and 1 branch
point. A crack that closes a loop counts as a tree cut open somewhere (loops are not counted).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import ngsolve as ngs
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import connected_components, dijkstra

from ..fem.nodal import LagrangeNodes
from .crackset import NodeGraph

__all__ = ["CrackTopology", "crack_topology", "crack_topology_of"]


@dataclass(frozen=True)
class CrackTopology:
    """What :func:`crack_topology` found.

    Attributes
    ----------
    components : int
        Connected parts of ``{z >= level}`` (each at least ``min_length`` long).
    branch_points : int
        Forks over all components (a fork into k arms counts k - 1).
    endpoints : int
        Ends over all components (a straight crack has 2).
    forks : (n, d) array
        Where the forks are (centroid of the shell piece that splits).
    lengths : list of float
        Graph length of each component (its longest path, from the double sweep).
    """

    components: int
    branch_points: int
    endpoints: int
    forks: np.ndarray
    lengths: list[float] = field(default_factory=list)


def crack_topology_of(z: ngs.GridFunction, *, spacing: float, level: float = 0.5,
                      min_length: float | None = None) -> CrackTopology:
    """:func:`crack_topology` of a P1/P2 GridFunction at its Lagrange nodes."""
    nodes = LagrangeNodes(z.space)
    edges = NodeGraph(z.space.mesh, nodes, joined="sub-simplices").edges
    return crack_topology(nodes.points, edges, nodes.values(z),
                          spacing=spacing, level=level, min_length=min_length)


def crack_topology(points: np.ndarray, edges: np.ndarray, z: np.ndarray, *, spacing: float,
                   level: float = 0.5, min_length: float | None = None) -> CrackTopology:
    """Count cracks, ends and branch points of ``{z >= level}`` on a node graph.

    Parameters
    ----------
    points : (n, d) array
        Node coordinates.
    edges : (m, 2) int array
        Node pairs joined by a mesh edge (``NodeGraph(mesh, nodes, joined="sub-simplices").edges``).
    z : (n,) array
        Phase field at the nodes.
    spacing : float
        Shell width of the Reeb graph: about the band's width (for AT2 with z >= 1/2, from
        ``epsilon`` to ``2 epsilon``), and several mesh sizes. A fork is seen once its arms
        are more than a mesh edge apart.
    level : float
        Threshold of the crack set.
    min_length : float, optional
        Shortest arm (beyond its fork) and shortest crack that count; default ``3 * spacing``.

    Returns
    -------
    CrackTopology
    """
    points = np.asarray(points, dtype=float)
    z = np.asarray(z, dtype=float)
    edges = np.asarray(edges, dtype=int).reshape(-1, 2)
    if spacing <= 0:
        raise ValueError(f"spacing must be > 0, got {spacing}")
    min_length = 3.0 * spacing if min_length is None else min_length
    inside = np.flatnonzero(z >= level)
    if len(inside) == 0:
        return CrackTopology(0, 0, 0, np.zeros((0, points.shape[1])), [])
    local = np.full(len(z), -1)
    local[inside] = np.arange(len(inside))
    kept = edges[(local[edges[:, 0]] >= 0) & (local[edges[:, 1]] >= 0)]
    a, b = local[kept[:, 0]], local[kept[:, 1]]
    length = np.linalg.norm(points[kept[:, 0]] - points[kept[:, 1]], axis=1)
    n = len(inside)
    graph = coo_matrix((np.concatenate([length, length]), (np.concatenate([a, b]),
                                                            np.concatenate([b, a]))),
                       shape=(n, n)).tocsr()
    n_parts, labels = connected_components(graph, directed=False)
    ends = branch_points = 0
    forks: list[np.ndarray] = []
    lengths: list[float] = []
    for part in range(n_parts):
        members = np.flatnonzero(labels == part)
        sub = graph[members][:, members]
        start = int(np.argmax(dijkstra(sub, indices=0)))  # one end of the crack
        distance = dijkstra(sub, indices=start)
        extent = float(distance.max())
        if extent < min_length:
            continue
        n_ends, n_branch, where = _shape(sub, distance, points[inside[members]], spacing, min_length)
        ends, branch_points = ends + n_ends, branch_points + n_branch
        forks.extend(where)
        lengths.append(extent)
    return CrackTopology(len(lengths), branch_points, ends,
                         np.array(forks).reshape(-1, points.shape[1]), lengths)


def _shape(graph: csr_matrix, distance: np.ndarray, points: np.ndarray, spacing: float,
           min_length: float) -> tuple[int, int, list[np.ndarray]]:
    """Ends, branch points and fork positions of one crack from its Reeb graph."""
    shell = np.floor(distance / spacing).astype(int)
    coo = graph.tocoo()
    same = shell[coo.row] == shell[coo.col]
    within = coo_matrix((np.ones(int(same.sum())), (coo.row[same], coo.col[same])),
                        shape=graph.shape)
    _, piece = connected_components(within, directed=False)
    # pieces joined by an edge across shells: parent (shell k) -> child (a later shell)
    step = shell[coo.col] > shell[coo.row]
    links = set(zip(piece[coo.row[step]].tolist(), piece[coo.col[step]].tolist()))
    children: dict[int, list[int]] = {}
    for parent, child in links:
        children.setdefault(parent, []).append(child)
    reach = np.zeros(piece.max() + 1)  # farthest distance reached from each piece onwards
    np.maximum.at(reach, piece, distance)
    start_of = np.full(piece.max() + 1, np.inf)
    np.minimum.at(start_of, piece, distance)
    for p in sorted(range(len(reach)), key=lambda q: -start_of[q]):  # leaves first
        for c in children.get(p, []):
            reach[p] = max(reach[p], reach[c])
    root = int(piece[int(np.argmin(distance))])
    ends, branch_points, forks = 1, 0, []
    todo, seen = [root], {root}
    while todo:
        p = todo.pop()
        arms = [c for c in children.get(p, []) if reach[c] - start_of[p] >= min_length
                and c not in seen]
        seen.update(arms)
        if not arms:
            ends += 1 if p != root else 0
            continue
        if len(arms) > 1:
            branch_points += len(arms) - 1
            forks.append(points[piece == p].mean(axis=0))
        todo.extend(arms)
    return ends, branch_points, forks
