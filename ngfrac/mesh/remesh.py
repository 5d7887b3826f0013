"""Mesh change by regeneration: a local mesh-size field in, a new Netgen mesh out.

NGSolve refines (bisection) but cannot coarsen, so every adaptation builds a *new* mesh of the
scene geometry from a mesh-size field: the field is sampled at points, each point restricts
Netgen's local mesh size (``MeshingParameters.RestrictH``), and Netgen meshes from scratch.
Refinement and coarsening are then the same operation, and the old mesh only serves to carry
the field (one size per element) and the solution for :mod:`ngfrac.mesh.transfer`.

Pipeline (the caller makes h_T, :func:`adapt_mesh` does the rest)::

    eta_T --size_field_from_indicator--> h_T --enforce_crack_sizes--> h_T <= h_tip, h_crack
        --grade_sizes--> |grad h| <= 0.3 --cap_vertices--> predicted nv <= 0.95 cap
        --sample_size_field--> (points, h, weights) --remesh--> new mesh, nv <= cap (checked)

Measured with ngsolve/netgen 6.2.2608 on a shared 2-core machine (``pytest --runslow -s -k
benchmark tests/ngfrac/test_meshing.py`` prints the numbers again):

* Time: Netgen's meshing dominates (``RestrictH`` is ~0.3-3 us per point): a crack mesh of
  ~5,000 vertices takes ~0.5 s (3,300: 0.3 s; 6,600: 0.7 s; 11,800: 0.85 s), with
  ``optsteps2d=1``, which halves the default's time at nearly equal quality (smallest angle
  29.7 deg, 5th percentile 43.5 deg, against 29.6 and 44.0 deg). Uniform meshes for reference:
  11,800 vertices 1.1 s, 46,600 vertices 6.3 s (default optimisation).
* Netgen realises a *graded* size field ~1.2-1.45x coarser than requested (longest edge over
  requested h, median), although a uniform ``maxh`` is met exactly (median 1.00) and
  ``GetLocalH`` reports the requested values. Sizes below hmax therefore go to Netgen divided
  by :data:`SIZE_RATIO` = 1.3; then the median ratio is ~0.95 on a constant band and ~1.2 on
  the graded flanks, 95th percentile < 1.6.
* Near the finest, graded sizes Netgen also leaves a few elements *below* the local h asked
  (smallest longest edge 0.81-0.86 hmin); :class:`SizeFloor` learns that shortfall per run and
  :func:`adapt_mesh` remeshes until no element is below ``hmin``.
* Sampling: a point per element, or a lattice with spacing ~h where the carrying element is
  coarser than the requested h; sampling 2x denser changes the vertex count by < 3 %.
* Vertex count: ``nv ~ c * int h^-2 dx`` over the *graded* requested field, c =
  :data:`VERTEX_DENSITY` = 1.45; measured 1.20 (smooth fields) to 1.58 (a small fine disc),
  1.32-1.36 for capped fields (2/sqrt(3) = 1.155 would be equilateral triangles of size h).
  :func:`remesh` re-measures c whenever a mesh exceeds the cap and regenerates, so the cap
  holds whatever the constant; with c = 1.45 one attempt is the rule.

Alternative measured: rebuild from the base mesh (uniform hmax) by repeated marked bisection
(``SetRefinementFlags`` + ``Refine`` until every longest edge <= 1.5 h) for the field
``h = clip(hmin + 0.3 d, hmin, 0.1)`` around a crack on the unit square, hmin = 0.005 /
0.0025 / 0.00125: bisection 0.03 / 0.04 / 0.09 s against 0.08 / 0.14 / 0.33 s, but 2.4-2.7x
the vertices (2,338 / 4,595 / 9,044 against 956 / 1,810 / 3,410), sizes overshooting the
request (median L/h 0.8) and worse shapes (5th percentile of the smallest angle 31 deg against
41 deg). Under a vertex cap regeneration resolves the crack ~1.6x finer and needs no hierarchy
bookkeeping, so it is the choice; a remesh every few steps costs about one or two time steps.

Dimension: everything but :func:`sample_size_field`'s lattice and the Netgen geometry is
written for d = 2 or 3 (``h^-d``, facets of d vertices); 3D needs an OCC geometry and a
calibrated ``VERTEX_DENSITY``.
"""
from __future__ import annotations

import itertools
import logging
import math
import time
import warnings
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import ngsolve as ngs
import netgen.meshing as ngm
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from .domains import MeshingError, netgen_geometry
from ..solve.nodal import LagrangeNodes
from ..scene import Geometry

log = logging.getLogger(__name__)

VERTEX_DENSITY = 1.45
"""c in ``nv ~ c * int h(x)^-2 dx`` for 2D Netgen meshes (h = graded requested size)."""

SIZE_RATIO = 1.3
"""Netgen meshes graded fields this much coarser than asked; sizes are divided by it."""

DENSITY = 1.0
"""Sample points per requested h along an edge (see :func:`sample_size_field`)."""

LEARNED_MARGIN = 0.93
"""Share of the cap a remesh aims at once :class:`VertexDensity` has measured its constant."""


@dataclass
class VertexDensity:
    """The constant c of ``nv ~ c * int h^-d dx``, learned from the meshes made so far.

    Netgen's c depends on the field (1.2 for smooth fields, up to 1.6 for a small fine disc),
    so a fixed c mispredicts a crack mesh by up to 40 %: in the adaptive Fig. 2 demo 49 of 50
    remeshes with c = 1.45 overshot the cap and were made twice. Successive meshes of one run
    have similar fields, so the c measured on the last mesh predicts the next one to about
    +-7 % (measured: ``python benchmarks/adaptivity_cost.py``); pass one instance to every
    :func:`remesh` of a run.
    """

    value: float = VERTEX_DENSITY
    measured: bool = False

    def update(self, vertices: int, integral: float) -> None:
        """Record the count of a mesh made for a field whose ``int h^-d dx`` is ``integral``."""
        if integral > 0:
            self.value, self.measured = vertices / integral, True

NETGEN_GRADING = 0.3
"""Netgen's default grading: its local h grows at most like ``h + 0.3 * distance``."""


@dataclass
class SizeFloor:
    """What Netgen delivers at the finest requested size: ``ratio`` = smallest longest edge
    over the floor it was sent, learned from the meshes made so far.

    Netgen's advancing front leaves a few elements below the local h it was given near a
    graded region: asked for nothing below hmin, crack meshes had smallest longest edges of
    0.81-0.86 hmin (Fig. 2 demo: 1.62e-3 under hmin = 2e-3). :func:`adapt_mesh` sends
    ``hmin / ratio`` as the floor, and whenever a mesh still has an element below hmin it
    lowers ``ratio`` by the shortfall and makes the mesh again; successive meshes of a run
    have the same kind of field, so after the first shortfall one attempt is the rule. Pass
    one instance to every :func:`adapt_mesh` of a run.
    """

    ratio: float = 1.0
    remeshes: int = 0
    """Meshes made again because an element was below hmin."""

    def floor(self, hmin: float) -> float:
        """The smallest size to send Netgen so that it delivers at least ``hmin``."""
        return hmin / self.ratio

    def update(self, smallest: float, hmin: float) -> bool:
        """Record a mesh whose smallest longest edge is ``smallest``; True if below hmin."""
        if smallest >= hmin:
            return False
        self.ratio *= smallest / hmin
        self.remeshes += 1
        return True


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


@dataclass(frozen=True)
class SizeField:
    """A mesh-size field sampled at points.

    Attributes
    ----------
    points : (n, d) array
    sizes : (n,) array
        Requested element size (longest edge) at each point.
    weights : (n,) array
        Area (volume) each point stands for; they sum to the domain's measure.
    """

    points: np.ndarray
    sizes: np.ndarray
    weights: np.ndarray

    def predicted_vertices(self, density: float = VERTEX_DENSITY) -> float:
        """``c * sum_p w_p / h_p^d``: the vertex count Netgen will roughly produce."""
        return predict_vertices(self.sizes, self.weights, density=density, dim=self.points.shape[1])


# -- the size field ---------------------------------------------------------------------------
def size_field_from_indicator(mesh: ngs.Mesh, eta: np.ndarray, *, target_h: float, hmin: float,
                              hmax: float, order: int = 1) -> np.ndarray:
    """Element sizes that equidistribute an error indicator.

    An L2-type indicator of a P_k field behaves like ``eta_T ~ h_T^(k + d/2)`` (ZZ, residual).
    Asking every new element for the same error ``tol`` gives::

        h_new,T = h_T * (tol / eta_T)^(1 / (k + d/2)),   clipped to [hmin, hmax],

    with ``tol`` chosen so that the element of largest indicator gets ``target_h``: the
    resolution asked for at the worst place (e.g. the crack tip) sets the error level, a
    length the user can relate to epsilon, rather than an abstract tolerance.

    Parameters
    ----------
    mesh : ngsolve.Mesh
        The mesh the indicator lives on.
    eta : (ne,) array
        Nonnegative indicator per element (e.g. :func:`estimators.zz_estimator`).
    target_h : float
        Size asked for at the element with the largest indicator.
    hmin, hmax : float
        Bounds of the result.
    order : int
        Polynomial order k of the estimated field.

    Returns
    -------
    (ne,) array
        Desired size per element.
    """
    if not 0 < hmin <= hmax:
        raise ValueError(f"need 0 < hmin <= hmax, got hmin={hmin}, hmax={hmax}")
    if target_h <= 0:
        raise ValueError(f"target_h must be > 0, got {target_h}")
    geom = ElementGeometry.of(mesh)
    eta = np.asarray(eta, dtype=float)
    if eta.shape != geom.measures.shape:
        raise ValueError(f"eta has shape {eta.shape}; the mesh has {len(geom.measures)} elements")
    if np.any(eta < 0) or not np.all(np.isfinite(eta)):
        raise ValueError("eta must be finite and nonnegative")
    p = order + mesh.dim / 2
    worst = int(np.argmax(eta))
    if eta[worst] == 0:
        return np.full(len(eta), hmax)
    tol = eta[worst] * (target_h / geom.diameters[worst]) ** p
    with np.errstate(divide="ignore"):
        sizes = geom.diameters * (tol / eta) ** (1.0 / p)
    return np.clip(sizes, hmin, hmax)


def enforce_crack_sizes(mesh: ngs.Mesh, sizes: np.ndarray, *,
                        tip: np.ndarray | tuple[float, ...] | None = None,
                        h_tip: float | None = None, margin: float = 0.0,
                        z: ngs.GridFunction | None = None, z_level: float = 0.1,
                        h_crack: float | None = None) -> np.ndarray:
    """Lower element sizes near the crack tip and on the crack.

    ``h_T <= h_tip`` for every element within ``margin`` of ``tip`` (so the tip never runs into
    a coarse mesh between two adaptations) and ``h_T <= h_crack`` where ``z >= z_level`` at a
    Lagrange node of the element (z: a P1/P2 H1 GridFunction on ``mesh``).

    Returns
    -------
    (ne,) array
        A new array; ``sizes`` is not changed.
    """
    geom = ElementGeometry.of(mesh)
    sizes = np.array(sizes, dtype=float, copy=True)
    if sizes.shape != geom.measures.shape:
        raise ValueError(f"sizes has shape {sizes.shape}; the mesh has {len(geom.measures)} elements")
    if tip is not None and h_tip is not None:
        tip = np.asarray(tip, dtype=float)[: geom.dim]
        if np.all(np.isfinite(tip)):
            # |c - tip| - r_T is a lower bound of the distance from the tip to T.
            near = np.linalg.norm(geom.centroids - tip, axis=1) - geom.radii <= margin
            sizes[near] = np.minimum(sizes[near], h_tip)
    if z is not None and h_crack is not None:
        cracked = element_maximum(mesh, z, geom) >= z_level
        sizes[cracked] = np.minimum(sizes[cracked], h_crack)
    return sizes


def element_maximum(mesh: ngs.Mesh, gf: ngs.GridFunction,
                    geom: ElementGeometry | None = None) -> np.ndarray:
    """Largest Lagrange-node value of a P1/P2 field on each element."""
    geom = geom or ElementGeometry.of(mesh)
    nodes = LagrangeNodes(gf.space)
    values = nodes.values(gf)
    result = values[geom.vertices].max(axis=1)
    if nodes.order == 2:
        edge_ids = edge_numbers(nodes.edge_vertices, geom.vertices)
        np.maximum(result, values[nodes.nv + edge_ids].max(axis=1), out=result)
    return result


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


def grade_sizes(mesh: ngs.Mesh, sizes: np.ndarray, grading: float = NETGEN_GRADING) -> np.ndarray:
    """Make the size field Lipschitz: ``h_T <= h_S + grading * dist(T, S)`` for all T, S.

    Netgen grades its local h the same way (``grading = 0.3`` by default), so grading first
    makes the vertex prediction see the field Netgen will mesh. See :func:`element_grader`.
    """
    return element_grader(ElementGeometry.of(mesh), grading)(sizes)


def element_grader(geom: ElementGeometry, grading: float = NETGEN_GRADING
                   ) -> Callable[[np.ndarray], np.ndarray]:
    """The grading of :func:`grade_sizes` as a function of the sizes, its graph built once.

    One Dijkstra run on the element-adjacency graph from a virtual source joined to each
    element T by an edge of length h_T gives ``min_S (h_S + grading * path(S, T))``; paths
    along centroids are a little longer than straight lines, so this grades a little more
    gently than Netgen. About 15 ms for 40,000 elements.
    """
    ne = len(geom.measures)
    a, b = _adjacent_elements(geom.vertices)
    length = grading * np.linalg.norm(geom.centroids[a] - geom.centroids[b], axis=1)
    rows = np.concatenate([a, b, np.full(ne, ne)])
    cols = np.concatenate([b, a, np.arange(ne)])

    def grade(sizes: np.ndarray) -> np.ndarray:
        sizes = np.asarray(sizes, dtype=float)
        if sizes.shape != (ne,):
            raise ValueError(f"sizes has shape {sizes.shape}; the mesh has {ne} elements")
        data = np.concatenate([length, length, sizes])
        graph = coo_matrix((data, (rows, cols)), shape=(ne + 1, ne + 1)).tocsr()
        return np.minimum(sizes, dijkstra(graph, directed=True, indices=ne)[:ne])

    return grade


def _adjacent_elements(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of elements that share a facet (d of their d+1 vertices)."""
    ne, nvert = vertices.shape
    facets = np.concatenate([np.sort(np.delete(vertices, drop, axis=1), axis=1)
                             for drop in range(nvert)])
    owner = np.tile(np.arange(ne), nvert)
    order = np.lexsort(facets.T[::-1])
    ordered = facets[order]
    same = np.flatnonzero(np.all(ordered[1:] == ordered[:-1], axis=1))
    return owner[order[same]], owner[order[same + 1]]


# -- sampling and the vertex cap --------------------------------------------------------------
def sample_size_field(mesh: ngs.Mesh, sizes: np.ndarray, *, density: float = DENSITY) -> SizeField:
    """Points that carry an element-wise size field to Netgen.

    An element whose requested h is at least its own diameter is represented by its centroid;
    a larger element by a barycentric lattice with ``k = ceil(density * H_T / h_T)`` intervals
    per edge, so points are about h apart (Netgen keeps a requested h only at the tree box that
    holds the point and grows it by 0.3 h per h elsewhere). Each point carries the element's
    measure divided by its number of points.
    """
    return _sample(ElementGeometry.of(mesh), sizes, density)


def _sample(geom: ElementGeometry, sizes: np.ndarray, density: float = DENSITY) -> SizeField:
    sizes = np.asarray(sizes, dtype=float)
    if sizes.shape != geom.measures.shape:
        raise ValueError(f"sizes has shape {sizes.shape}; the mesh has {len(geom.measures)} elements")
    if np.any(sizes <= 0):
        raise ValueError("sizes must be > 0")
    k = np.maximum(1, np.ceil(density * geom.diameters / sizes - 1e-9).astype(int))
    points, values, weights = [], [], []
    for kk in np.unique(k):
        chosen = np.flatnonzero(k == kk)
        if kk == 1:
            lattice_points = geom.centroids[chosen][:, None, :]
        else:
            lattice = _barycentric_lattice(geom.dim, int(kk))
            corners = geom.coordinates[geom.vertices[chosen]]
            lattice_points = np.einsum("mj,ejd->emd", lattice, corners)
        m = lattice_points.shape[1]
        points.append(lattice_points.reshape(-1, geom.dim))
        values.append(np.repeat(sizes[chosen], m))
        weights.append(np.repeat(geom.measures[chosen] / m, m))
    field = SizeField(np.concatenate(points), np.concatenate(values), np.concatenate(weights))
    log.debug("size field: %d points from %d elements", len(field.sizes), len(sizes))
    return field


def _barycentric_lattice(dim: int, k: int) -> np.ndarray:
    """All barycentric coordinates with denominators k: shape (m, dim+1)."""
    rows = [c for c in itertools.product(range(k + 1), repeat=dim) if sum(c) <= k]
    interior = np.array(rows, dtype=float)
    return np.column_stack([k - interior.sum(axis=1), interior]) / k


def predict_vertices(sizes: np.ndarray, weights: np.ndarray, *, density: float = VERTEX_DENSITY,
                     dim: int = 2) -> float:
    """``c * sum w / h^d``, Netgen's vertex count for the field (see :data:`VERTEX_DENSITY`)."""
    return float(density * np.sum(np.asarray(weights) / np.asarray(sizes) ** dim))


def cap_vertices(sizes: np.ndarray, weights: np.ndarray, max_vertices: float, *, hmax: float,
                 density: float = VERTEX_DENSITY, dim: int = 2,
                 grade: Callable[[np.ndarray], np.ndarray] | None = None) -> np.ndarray:
    """Coarsen a size field until its predicted vertex count is <= ``max_vertices``.

    The finest sizes (largest errors) are kept longest. Stage 1 raises the coarse part only::

        h_lam = min(hmax, h_lo * (h / h_lo)^(1 + lam)),   h_lo = min h,

    which keeps h_lo exactly, keeps the order of sizes, and tends to {h_lo, hmax} as lam grows.
    If even lam = 8 predicts too many vertices, stage 2 scales that field uniformly,
    ``s * h_8`` (s >= 1, also past hmax), which coarsens the finest part too. Each stage is a
    bisection on a monotone family (to 0.1 %).

    Parameters
    ----------
    sizes, weights : (n,) arrays
        Requested sizes and the measure each stands for (elements or sample points).
    max_vertices : float
        The allowed prediction (give a margin below the hard cap).
    hmax : float
        Coarsest size of stage 1.
    density, dim : float, int
        The prediction ``density * sum w / h^dim``.
    grade : callable, optional
        Applied to each candidate before predicting (e.g. :func:`element_grader`), since
        Netgen will grade the field anyway.

    Returns
    -------
    (n,) array
        ``grade(sizes)`` if that fits, else the graded, coarsened field.
    """
    sizes = np.minimum(np.asarray(sizes, dtype=float), hmax)
    weights = np.asarray(weights, dtype=float)
    grade = grade or (lambda h: h)

    def count(h: np.ndarray) -> float:
        return predict_vertices(grade(h), weights, density=density, dim=dim)

    if count(sizes) <= max_vertices:
        return grade(sizes)
    h_lo = float(sizes.min())

    def stage1(lam: float) -> np.ndarray:
        return np.minimum(hmax, h_lo * (sizes / h_lo) ** (1.0 + lam))

    lam_max = 8.0
    if count(stage1(lam_max)) <= max_vertices:
        lam = _bisect(lambda t: count(stage1(t)) <= max_vertices, 0.0, lam_max)
        log.info("vertex cap: coarse part raised (lambda=%.3g), finest h=%.3g kept", lam, h_lo)
        return grade(stage1(lam))
    base = stage1(lam_max)
    s_max = 2.0
    while count(s_max * base) > max_vertices:
        s_max *= 2.0
        if s_max > 1e6:
            raise ValueError(f"max_vertices={max_vertices} cannot be met by any size field")
    s = _bisect(lambda t: count(t * base) <= max_vertices, 1.0, s_max)
    log.info("vertex cap: the finest sizes had to grow by %.3g (h_lo %.3g -> %.3g)",
                s, h_lo, s * h_lo)
    return grade(s * base)


def _bisect(fits: Callable[[float], bool], lo: float, hi: float, rtol: float = 1e-3) -> float:
    """Nearly the smallest t in [lo, hi] with ``fits(t)`` (``fits(hi)`` must hold)."""
    while hi - lo > rtol * max(1.0, abs(hi)):
        mid = 0.5 * (lo + hi)
        if fits(mid):
            hi = mid
        else:
            lo = mid
    return hi


def remesh(geometry: Geometry | Any, points: np.ndarray, sizes: np.ndarray, *, hmax: float,
           max_vertices: int, weights: np.ndarray | None = None,
           grading: float = NETGEN_GRADING, optimize_steps: int = 1,
           max_attempts: int = 8, density: VertexDensity | None = None) -> ngs.Mesh:
    """Generate a new mesh of ``geometry`` that follows a sampled size field.

    Sizes are capped with :func:`cap_vertices` (predicted count <= 0.95 ``max_vertices``),
    sent to Netgen divided by :data:`SIZE_RATIO`, and the mesh is generated. If it still has
    more than ``max_vertices`` vertices, the constant of the prediction is re-measured on the
    mesh just made, the margin tightened, and the mesh generated again: the returned mesh
    never exceeds the cap.

    Parameters
    ----------
    geometry : Geometry or netgen geometry
        A scene geometry (boundaries bottom, right, top, left are kept) or any Netgen geometry
        with ``GenerateMesh(mp=...)``.
    points : (n, d) array
        Where the sizes apply.
    sizes : (n,) array
        Requested element size (longest edge) at the points.
    hmax : float
        Size wherever no point asks for less (Netgen's ``maxh``).
    max_vertices : int
        Hard upper bound of the vertex count.
    weights : (n,) array, optional
        Measure each point stands for (:class:`SizeField`); if omitted, the Voronoi cells of
        the points on a grid over their bounding box.
    grading : float
        Netgen's grading.
    optimize_steps : int
        Netgen's ``optsteps2d``; 1 halves the time of the default 3 at nearly equal quality.
    max_attempts : int
        Generations before giving up with a :class:`~ngfrac.mesh.domains.MeshingError`.
    density : VertexDensity, optional
        The run's learned vertex-count constant: used for the prediction and updated with the
        mesh made. Without it every call starts from :data:`VERTEX_DENSITY`.

    Returns
    -------
    ngsolve.Mesh
    """
    points = np.asarray(points, dtype=float)
    sizes = np.asarray(sizes, dtype=float)
    if points.ndim != 2 or len(points) != len(sizes):
        raise ValueError(f"points {points.shape} and sizes {sizes.shape} do not match")
    if hmax <= 0 or np.any(sizes <= 0):
        raise ValueError("hmax and all sizes must be > 0")
    dim = points.shape[1]
    ngeo = netgen_geometry(geometry) if isinstance(geometry, Geometry) else geometry
    if weights is None:
        weights = voronoi_weights(points)
    learned = density if density is not None else VertexDensity()
    margin = LEARNED_MARGIN if learned.measured else 0.95
    for attempt in range(1, max_attempts + 1):
        current = cap_vertices(sizes, weights, margin * max_vertices, hmax=hmax,
                               density=learned.value, dim=dim)
        started = time.perf_counter()
        ngmesh = _generate(ngeo, points, current, maxh=max(hmax, float(current.max())),
                           grading=grading, optimize_steps=optimize_steps)
        nv = len(ngmesh.Points())
        integral = predict_vertices(current, weights, density=1.0, dim=dim)
        log.info("remesh attempt %d: %d vertices (cap %d, predicted %.0f) in %.2f s", attempt, nv,
                 max_vertices, learned.value * integral, time.perf_counter() - started)
        learned.update(nv, integral)
        if nv <= max_vertices:
            return ngs.Mesh(ngmesh)
        margin *= 0.95
    raise MeshingError(f"remesh: no mesh with <= {max_vertices} vertices after {max_attempts} "
                       f"attempts (last had {nv}); raise max_vertices or hmax")


def _generate(ngeo: Any, points: np.ndarray, sizes: np.ndarray, *, maxh: float,
              grading: float, optimize_steps: int) -> ngm.Mesh:
    mp = ngm.MeshingParameters(maxh=maxh, grading=grading, optsteps2d=optimize_steps)
    active = sizes < maxh  # Netgen meets maxh itself, without the SIZE_RATIO correction
    xyz = np.zeros((int(active.sum()), 3))
    xyz[:, : points.shape[1]] = points[active]
    for (x, y, z), h in zip(xyz.tolist(), (sizes[active] / SIZE_RATIO).tolist()):
        mp.RestrictH(x, y, z, h)
    try:
        return ngeo.GenerateMesh(mp=mp)
    except Exception as err:  # netgen raises plain Exceptions
        raise MeshingError(f"Netgen could not remesh ({err}) with maxh = {maxh:g} and sizes "
                           f"down to {float(sizes.min()):g}; raise adaptivity.hmin") from None


def voronoi_weights(points: np.ndarray, n_grid: int | None = None) -> np.ndarray:
    """Measure of each point's Voronoi cell within the points' bounding box (grid quadrature)."""
    points = np.asarray(points, dtype=float)
    lo, hi = points.min(axis=0), points.max(axis=0)
    extent = np.maximum(hi - lo, 1e-300)
    n_grid = n_grid or int(min(400_000, max(10_000, 8 * len(points))))
    per_axis = max(2, int(round(n_grid ** (1.0 / points.shape[1]))))
    axes = [lo[i] + (np.arange(per_axis) + 0.5) * extent[i] / per_axis for i in range(points.shape[1])]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, points.shape[1])
    _, owner = cKDTree(points).query(grid)
    cell = float(np.prod(extent)) / len(grid)
    return np.bincount(owner, minlength=len(points)) * cell


def adapt_mesh(mesh: ngs.Mesh, geometry: Geometry | Any, sizes: np.ndarray, *, hmax: float,
               max_vertices: int, grading: float = NETGEN_GRADING,
               density: VertexDensity | None = None, hmin: float | None = None,
               floor: SizeFloor | None = None, max_attempts: int = 4) -> ngs.Mesh:
    """Grade, cap, sample and remesh: the new mesh for element sizes given on ``mesh``.

    The cap is applied here on the elements, with grading inside the prediction (a steep
    field costs Netgen's grading halo), so :func:`remesh` rarely needs a second attempt.

    Parameters
    ----------
    mesh : ngsolve.Mesh
        The current mesh, on which ``sizes`` lives (one per element).
    geometry : Geometry or netgen geometry
        The domain of the new mesh.
    sizes : (ne,) array
        Requested sizes, e.g. from :func:`size_field_from_indicator` and
        :func:`enforce_crack_sizes`.
    hmax, max_vertices, grading, density
        As in :func:`remesh`.
    hmin : float, optional
        Floor of the delivered mesh: no element's longest edge is below it. The sizes sent
        are raised to ``floor.floor(hmin)`` and the mesh is made again (up to
        ``max_attempts`` times, then a warning) while it has a smaller element.
    floor : SizeFloor, optional
        The run's learned ratio (see :class:`SizeFloor`); updated with every mesh.
    """
    geom = ElementGeometry.of(mesh)
    grade = element_grader(geom, grading)
    learned = density if density is not None else VertexDensity()
    floor = floor if floor is not None else SizeFloor()
    requested = np.minimum(sizes, hmax)
    for _ in range(max_attempts):
        # the sizes go to Netgen divided by SIZE_RATIO: floor them before that division
        floored = requested if hmin is None else np.maximum(requested, SIZE_RATIO * floor.floor(hmin))
        margin = LEARNED_MARGIN if learned.measured else 0.95
        capped = cap_vertices(floored, geom.measures, margin * max_vertices, hmax=hmax,
                              density=learned.value, dim=geom.dim, grade=grade)
        field = _sample(geom, capped)
        new = remesh(geometry, field.points, field.sizes, weights=field.weights, hmax=hmax,
                     max_vertices=max_vertices, grading=grading, density=learned)
        if hmin is None:
            return new
        smallest = float(ElementGeometry.of(new).diameters.min())
        if not floor.update(smallest, hmin):
            return new
        log.info("remesh: smallest element %.3g below hmin %.3g; Netgen floor ratio now %.3f",
                 smallest, hmin, floor.ratio)
    warnings.warn(f"adapt_mesh: an element of {smallest:.3g} is below hmin = {hmin:.3g} after "
                  f"{max_attempts} meshes; lower hmin or refine the geometry's small features",
                  stacklevel=2)
    return new
