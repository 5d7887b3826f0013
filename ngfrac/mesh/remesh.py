"""Mesh change by regeneration: a local mesh-size field in, a new Netgen mesh out (2D and 3D).

NGSolve refines (bisection) but cannot coarsen, so every adaptation builds a *new* mesh of the
domain from a mesh-size field: the field is sampled at points, each point restricts Netgen's
local mesh size (``MeshingParameters.RestrictH``), and Netgen meshes from scratch. Refinement
and coarsening are then the same operation, and the old mesh only serves to carry the field
(one size per element) and the solution for :mod:`ngfrac.mesh.transfer`.

Pipeline (the caller makes h_T, :func:`adapt_mesh` does the rest)::

    eta_T --size_field_from_indicator--> h_T (the caller lowers it on the crack)
        --grade_sizes--> |grad h| <= 0.3 --cap_vertices--> predicted nv <= 0.95 cap
        --sample_size_field--> (points, h, weights) --Netgen--> new mesh, nv <= cap (checked)

One path serves both dimensions; what differs is in :class:`MeshingConstants`
(:data:`MESHING_2D`, :data:`MESHING_3D`, chosen by :func:`meshing_constants`): Netgen's
vertex density ``nv ~ c * int h^-d dx``, the ratio by which Netgen meshes graded fields
coarser than asked, its optimisation steps, and whether hmin is a checked floor of the
delivered mesh. Why regeneration and not bisection, and the measurements behind every
constant: docs/adaptivity.md ("Meshing constants").
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

from ..fem.elements import ElementGeometry, edge_numbers
from ..fem.threads import meshing_threads, netgen_meshing
from ..geometry.domains import Domain, MeshingError, domain_of
from ..scene import Geometry

log = logging.getLogger(__name__)

VERTEX_DENSITY = 1.45
"""c in ``nv ~ c * int h(x)^-2 dx`` for 2D Netgen meshes (h = graded requested size)."""

SIZE_RATIO = 1.3
"""Netgen meshes graded 2D fields this much coarser than asked; sizes are divided by it."""

DENSITY = 1.0
"""Sample points per requested h along an edge (see :func:`sample_size_field`)."""

LEARNED_MARGIN = 0.93
"""Share of the cap a 2D remesh aims at once :class:`VertexDensity` has measured its constant."""

FIRST_MARGIN = 0.95
"""Share of the cap a remesh aims at before the constant is measured."""

NETGEN_GRADING = 0.3
"""Netgen's default grading: its local h grows at most like ``h + 0.3 * distance``."""


@dataclass(frozen=True)
class MeshingConstants:
    """What the remesh path needs to know of Netgen in one dimension.

    Attributes
    ----------
    dim : int
    vertex_density : float
        c in ``nv ~ c * int h^-d dx`` over the graded requested field, until a run has
        measured its own (:class:`VertexDensity`).
    size_ratio : float
        Sizes below hmax go to Netgen divided by it (Netgen realises graded fields coarser
        than asked; a uniform ``maxh`` is met).
    optimize_steps : int
        Netgen's ``optsteps2d`` / ``optsteps3d``.
    learned_margin : float
        Share of the cap aimed at once the vertex density is measured.
    floor_factor : float
        Requested sizes are raised to ``floor_factor * hmin`` (2D: to ``floor_factor`` times
        :meth:`SizeFloor.floor`); 2D: the size ratio, so Netgen is asked for hmin.
    hmin_checked : bool
        Whether no element of the delivered mesh may be below hmin (2D: the mesh is made
        again with a lowered :class:`SizeFloor`); in 3D hmin only floors the request.
    recap_graded : bool
        What a mesh over the cap is followed by: a new cap of the graded element field (3D,
        where Netgen's grading halo holds most of a fine band's vertices), or a cap of the
        sampled field as it is (2D).
    """

    dim: int
    vertex_density: float
    size_ratio: float
    optimize_steps: int
    learned_margin: float
    floor_factor: float
    hmin_checked: bool
    recap_graded: bool


MESHING_2D = MeshingConstants(dim=2, vertex_density=VERTEX_DENSITY, size_ratio=SIZE_RATIO,
                              optimize_steps=1, learned_margin=LEARNED_MARGIN,
                              floor_factor=SIZE_RATIO, hmin_checked=True, recap_graded=False)
"""Triangles (Netgen 6.2.2608)."""

MESHING_3D = MeshingConstants(dim=3, vertex_density=4.3, size_ratio=1.15, optimize_steps=1,
                              learned_margin=FIRST_MARGIN, floor_factor=SIZE_RATIO,
                              hmin_checked=False, recap_graded=True)
"""Tetrahedra (Netgen 6.2.2608). ``floor_factor`` is the 2D size ratio, so Netgen is asked
for nothing below 1.3 / 1.15 hmin."""


def meshing_constants(dim: int) -> MeshingConstants:
    """:data:`MESHING_2D` or :data:`MESHING_3D`."""
    if dim == 2:
        return MESHING_2D
    if dim == 3:
        return MESHING_3D
    raise ValueError(f"no meshing constants for dimension {dim}")


@dataclass
class VertexDensity:
    """The constant c of ``nv ~ c * int h^-d dx``, learned from the meshes made so far.

    Netgen's c depends on the field, so a fixed c mispredicts a crack mesh by up to 40 %;
    successive meshes of one run have similar fields, so the c measured on the last mesh
    predicts the next one to a few per cent (docs/adaptivity.md, "Meshing constants"). Pass
    one instance to every :func:`adapt_mesh` of a run. Until ``measured``, the dimension's
    :attr:`MeshingConstants.vertex_density` is used and ``value`` is ignored.
    """

    value: float = VERTEX_DENSITY
    measured: bool = False

    def of(self, constants: MeshingConstants) -> float:
        """The constant to predict with: the measured one, else the dimension's default."""
        return self.value if self.measured else constants.vertex_density

    def update(self, vertices: int, integral: float) -> None:
        """Record the count of a mesh made for a field whose ``int h^-d dx`` is ``integral``."""
        if integral > 0:
            self.value, self.measured = vertices / integral, True


@dataclass
class SizeFloor:
    """What Netgen delivers at the finest requested size: ``ratio`` = smallest longest edge
    over the floor it was sent, learned from the meshes made so far.

    Netgen's advancing front leaves a few elements below the local h it was given near a
    graded region (docs/adaptivity.md, "hmin, a floor"). :func:`adapt_mesh` sends
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

    def predicted_vertices(self, density: float | None = None) -> float:
        """``c * sum_p w_p / h_p^d``: the vertex count Netgen will roughly produce (c: the
        dimension's :attr:`MeshingConstants.vertex_density` unless given)."""
        dim = self.points.shape[1]
        c = meshing_constants(dim).vertex_density if density is None else density
        return predict_vertices(self.sizes, self.weights, density=c, dim=dim)


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
    gently than Netgen.
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
    return sample_elements(ElementGeometry.of(mesh), sizes, density)


def sample_elements(geom: ElementGeometry, sizes: np.ndarray, density: float = DENSITY) -> SizeField:
    """:func:`sample_size_field` on the element geometry of a mesh, read once."""
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
                 grade: Callable[[np.ndarray], np.ndarray] | None = None,
                 keep_finest: bool = True) -> np.ndarray:
    """Coarsen a size field until its predicted vertex count is <= ``max_vertices``.

    With ``keep_finest = False`` the whole field is scaled, ``min(s h, max(hmax, s min h))``
    with the least s >= 1 that fits: the field's shape (an equidistribution's) is kept and
    every size grows by the same factor (up to hmax).

    With ``keep_finest`` (the default) the finest sizes (largest errors) are kept longest.
    Stage 1 raises the coarse part only::

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
    keep_finest : bool
        Coarsen the coarse part first (stages 1 and 2), or scale the whole field.

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
    if not keep_finest:
        def scaled(factor: float) -> np.ndarray:
            return np.minimum(factor * sizes, max(hmax, factor * h_lo))

        factor = _bisect(lambda t: count(scaled(t)) <= max_vertices, 1.0,
                         _fitting_factor(count, scaled, max_vertices))
        log.info("vertex cap: every size grew by %.3g (h_lo %.3g -> %.3g)", factor, h_lo, factor * h_lo)
        return grade(scaled(factor))

    def stage1(lam: float) -> np.ndarray:
        return np.minimum(hmax, h_lo * (sizes / h_lo) ** (1.0 + lam))

    lam_max = 8.0
    if count(stage1(lam_max)) <= max_vertices:
        lam = _bisect(lambda t: count(stage1(t)) <= max_vertices, 0.0, lam_max)
        log.info("vertex cap: coarse part raised (lambda=%.3g), finest h=%.3g kept", lam, h_lo)
        return grade(stage1(lam))
    base = stage1(lam_max)
    s = _bisect(lambda t: count(t * base) <= max_vertices, 1.0,
                _fitting_factor(count, lambda t: t * base, max_vertices))
    log.info("vertex cap: the finest sizes had to grow by %.3g (h_lo %.3g -> %.3g)",
                s, h_lo, s * h_lo)
    return grade(s * base)


def _fitting_factor(count: Callable[[np.ndarray], float], field: Callable[[float], np.ndarray],
                    max_vertices: float) -> float:
    """A power of two t >= 2 with ``count(field(t)) <= max_vertices``."""
    t = 2.0
    while count(field(t)) > max_vertices:
        t *= 2.0
        if t > 1e6:
            raise ValueError(f"max_vertices={max_vertices} cannot be met by any size field")
    return t


def _bisect(fits: Callable[[float], bool], lo: float, hi: float, rtol: float = 1e-3) -> float:
    """Nearly the smallest t in [lo, hi] with ``fits(t)`` (``fits(hi)`` must hold)."""
    while hi - lo > rtol * max(1.0, abs(hi)):
        mid = 0.5 * (lo + hi)
        if fits(mid):
            hi = mid
        else:
            lo = mid
    return hi




# -- Netgen runs under the vertex cap ----------------------------------------------------------
Proposal = Callable[[float, float], "tuple[np.ndarray, np.ndarray, float]"]
"""``(allowed vertices, vertex density) -> (points, sizes to send, int h^-d dx)``: the field
of one remesh attempt, capped for the allowed count."""


def remesh(geometry: Geometry | Domain | Any, points: np.ndarray, sizes: np.ndarray, *,
           hmax: float, max_vertices: int, weights: np.ndarray | None = None,
           grading: float = NETGEN_GRADING, optimize_steps: int | None = None,
           max_attempts: int = 8, density: VertexDensity | None = None) -> ngs.Mesh:
    """Generate a new mesh of ``geometry`` that follows a size field sampled at points.

    Sizes are capped with :func:`cap_vertices` (predicted count <= 0.95 ``max_vertices``),
    sent to Netgen divided by the dimension's size ratio, and the mesh is generated. If it
    still has more than ``max_vertices`` vertices, the constant of the prediction is
    re-measured on the mesh just made, the margin tightened, and the mesh generated again:
    the returned mesh never exceeds the cap.

    Parameters
    ----------
    geometry : Geometry, Domain or netgen geometry
        A scene geometry or domain (meshed without cracks) or any Netgen geometry with
        ``GenerateMesh(mp=...)``.
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
    optimize_steps : int, optional
        Netgen's ``optsteps2d`` (``optsteps3d``); default :attr:`MeshingConstants.optimize_steps`.
    max_attempts : int
        Generations before giving up with a :class:`~ngfrac.geometry.domains.MeshingError`.
    density : VertexDensity, optional
        The run's learned vertex-count constant: used for the prediction and updated with the
        mesh made. Without it every call starts from the dimension's default.

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
    if weights is None:
        weights = voronoi_weights(points)

    def propose(allowed: float, c: float) -> tuple[np.ndarray, np.ndarray, float]:
        current = cap_vertices(sizes, weights, allowed, hmax=hmax, density=c, dim=dim)
        return points, current, predict_vertices(current, weights, density=1.0, dim=dim)

    return _generate_under_cap(
        _netgen_geometry(geometry), propose, hmax=hmax, max_vertices=max_vertices,
        density=density if density is not None else VertexDensity(),
        constants=meshing_constants(dim), grading=grading, optimize_steps=optimize_steps,
        max_attempts=max_attempts)


def _netgen_geometry(geometry: Geometry | Domain | Any) -> Any:
    """A Netgen geometry: that of a scene geometry or domain (no cracks), else ``geometry``."""
    if isinstance(geometry, (Geometry, Domain)):
        return domain_of(geometry).netgen_geometry()
    return geometry


def _generate_under_cap(ngeo: Any, propose: Proposal, *, hmax: float, max_vertices: int,
                        density: VertexDensity, constants: MeshingConstants, grading: float,
                        optimize_steps: int | None, max_attempts: int) -> ngs.Mesh:
    """Netgen runs on the proposed fields until a mesh has at most ``max_vertices`` vertices;
    each mesh updates ``density``, each failure lowers the share of the cap aimed at."""
    margin = constants.learned_margin if density.measured else FIRST_MARGIN
    nv = 0
    for attempt in range(1, max_attempts + 1):
        c = density.of(constants)
        points, sent, integral = propose(margin * max_vertices, c)
        started = time.perf_counter()
        ngmesh = generate(ngeo, points, sent, maxh=max(hmax, float(sent.max())), grading=grading,
                          constants=constants, optimize_steps=optimize_steps)
        nv = len(ngmesh.Points())
        log.info("remesh attempt %d: %d vertices (cap %d, predicted %.0f) in %.2f s", attempt, nv,
                 max_vertices, c * integral, time.perf_counter() - started)
        density.update(nv, integral)
        if nv <= max_vertices:
            return ngs.Mesh(ngmesh)
        margin *= 0.95
    raise MeshingError(f"remesh: no mesh with <= {max_vertices} vertices after {max_attempts} "
                       f"attempts (last had {nv}); raise max_vertices or hmax")


def generate(ngeo: Any, points: np.ndarray, sizes: np.ndarray, *, maxh: float,
             grading: float = NETGEN_GRADING, constants: MeshingConstants | None = None,
             optimize_steps: int | None = None) -> ngm.Mesh:
    """One Netgen run: ``RestrictH(point, size / size_ratio)`` for every size below ``maxh``.

    Parameters
    ----------
    ngeo : netgen geometry
        ``SplineGeometry`` (a rectangle) or ``OCCGeometry`` (a box, an occ domain in 2D or 3D),
        from :meth:`Domain.netgen_geometry`.
    points : (n, d) array
    sizes : (n,) array
    maxh : float
        Netgen's ``maxh``; it meets it itself, so sizes at or above it are not sent.
    grading : float
    constants : MeshingConstants, optional
        Default: those of the points' dimension.
    optimize_steps : int, optional
        Default: ``constants.optimize_steps``.
    """
    constants = constants or meshing_constants(points.shape[1])
    steps = constants.optimize_steps if optimize_steps is None else optimize_steps
    active = sizes < maxh  # Netgen meets maxh itself, without the size-ratio correction
    xyz = np.zeros((int(active.sum()), 3))
    xyz[:, : points.shape[1]] = points[active]
    with netgen_meshing(constants.dim) as call:
        mp = ngm.MeshingParameters(maxh=maxh, grading=grading, **meshing_threads(call.threaded),
                                   **{f"optsteps{constants.dim}d": steps})
        for (x, y, z), h in zip(xyz.tolist(), (sizes[active] / constants.size_ratio).tolist()):
            mp.RestrictH(x, y, z, h)
        try:
            ngmesh = ngeo.GenerateMesh(mp=mp)
        except Exception as err:  # netgen raises plain Exceptions
            raise MeshingError(f"Netgen could not remesh ({err}) with maxh = {maxh:g} and "
                               f"sizes down to {float(sizes.min()):g}; raise adaptivity.hmin"
                               ) from None
        call.work = len(ngmesh.Points())
    return ngmesh


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


# -- the adaptive path ---------------------------------------------------------------------------
def _element_proposal(geom: ElementGeometry, grade: Callable[[np.ndarray], np.ndarray],
                      requested: np.ndarray, hmax: float, constants: MeshingConstants,
                      keep_finest: bool = True) -> Proposal:
    """The fields of the remesh attempts for element sizes: the graded element field capped
    and sampled; after a mesh over the cap either that again with a tighter cap
    (``constants.recap_graded``) or the sampled field capped as it is."""
    field: SizeField | None = None

    def propose(allowed: float, c: float) -> tuple[np.ndarray, np.ndarray, float]:
        nonlocal field
        if field is None or constants.recap_graded:
            capped = cap_vertices(requested, geom.measures, allowed, hmax=hmax, density=c,
                                  dim=geom.dim, grade=grade, keep_finest=keep_finest)
            field = sample_elements(geom, capped)
            if constants.recap_graded:
                return field.points, field.sizes, predict_vertices(capped, geom.measures,
                                                                   density=1.0, dim=geom.dim)
        sent = cap_vertices(field.sizes, field.weights, allowed, hmax=hmax, density=c, dim=geom.dim,
                            keep_finest=keep_finest)
        return field.points, sent, predict_vertices(sent, field.weights, density=1.0, dim=geom.dim)

    return propose


def adapt_mesh(mesh: ngs.Mesh, geometry: Geometry | Domain | Any, sizes: np.ndarray, *,
               hmax: float, max_vertices: int, grading: float = NETGEN_GRADING,
               density: VertexDensity | None = None, hmin: float | None = None,
               floor: SizeFloor | None = None, max_attempts: int = 4,
               cap_attempts: int = 8, keep_finest: bool = True) -> ngs.Mesh:
    """Grade, cap, sample and remesh: the new mesh (2D or 3D) for element sizes on ``mesh``.

    The cap is applied on the elements, with grading inside the prediction (a steep field
    costs Netgen's grading halo), so one Netgen run is the rule; the constants of the mesh's
    dimension (:func:`meshing_constants`) say what else differs.

    Parameters
    ----------
    mesh : ngsolve.Mesh
        The current mesh, on which ``sizes`` lives (one per element).
    geometry : Geometry, Domain or netgen geometry
        The domain of the new mesh (with its cracks: :meth:`Domain.netgen_geometry`).
    sizes : (ne,) array
        Requested sizes, e.g. from :func:`size_field_from_indicator`.
    hmax, max_vertices, grading, density
        As in :func:`remesh`.
    hmin : float, optional
        Sizes are raised to ``floor_factor * hmin`` before they go to Netgen. Where
        ``hmin_checked`` (2D) it is a floor of the delivered mesh: no element's longest edge is
        below it; the floor sent is :meth:`SizeFloor.floor` and the mesh is made again (up to
        ``max_attempts`` times, then a warning) while it has a smaller element. If the last
        attempt still has one, the geometry forces it (a slit narrower than hmin): the first
        attempt's mesh is returned and the floor's ratio is left as it was before the call.
    floor : SizeFloor, optional
        The run's learned ratio (see :class:`SizeFloor`); updated with every checked mesh.
    cap_attempts : int
        Netgen runs per mesh before giving up on the vertex cap (:class:`MeshingError`).
    keep_finest : bool
        How the cap coarsens (:func:`cap_vertices`): the coarse part first, or every size alike.
    """
    geom = ElementGeometry.of(mesh)
    constants = meshing_constants(geom.dim)
    grade = element_grader(geom, grading)
    learned = density if density is not None else VertexDensity()
    floor = floor if floor is not None else SizeFloor()
    ngeo = _netgen_geometry(geometry)
    checked = hmin is not None and constants.hmin_checked
    requested = np.minimum(np.asarray(sizes, dtype=float), hmax)
    ratio_before, first = floor.ratio, None
    for _ in range(max_attempts if checked else 1):
        # the sizes go to Netgen divided by the size ratio: floor them before that division
        floored = requested
        if hmin is not None:
            lowest = floor.floor(hmin) if checked else hmin
            floored = np.maximum(requested, constants.floor_factor * lowest)
        propose = _element_proposal(geom, grade, floored, hmax, constants, keep_finest)
        new = _generate_under_cap(ngeo, propose, hmax=hmax, max_vertices=max_vertices,
                                  density=learned, constants=constants, grading=grading,
                                  optimize_steps=None, max_attempts=cap_attempts)
        if not checked:
            return new
        smallest = float(ElementGeometry.of(new).diameters.min())
        first = new if first is None else first
        if not floor.update(smallest, hmin):
            return new
        log.info("remesh: smallest element %.3g below hmin %.3g; Netgen floor ratio now %.3f",
                 smallest, hmin, floor.ratio)
    # Still below hmin: a feature of the geometry (a slit narrower than hmin) forces it, and a
    # higher floor only coarsens what was asked for. Keep the first mesh and the old ratio.
    floor.ratio = ratio_before
    warnings.warn(f"adapt_mesh: an element of {smallest:.3g} is below hmin = {hmin:.3g} after "
                  f"{max_attempts} meshes; lower hmin or refine the geometry's small features",
                  stacklevel=2)
    return first
