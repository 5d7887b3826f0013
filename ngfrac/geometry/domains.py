"""Domains: the rectangle and the box as objects, with their cracks embedded for Netgen.

A :class:`Domain` knows its boundary names, its measure, which points lie in it or on its
boundary, grids for checking expressions, and how to become a Netgen geometry with the
initial cracks as interior lines (2D, :class:`Rectangle`) or interior faces (3D,
:class:`Box`), so every mesh has edges or faces along them. The initial profile
exp(-d/epsilon) has a kink on the crack; on an aligned mesh its P2 interpolant is smooth on
each side and the surface energy is accurate (docs/theory.md, "Crack-aligned meshes").
Nothing else in ngfrac does width/height arithmetic; :func:`domain_of` builds the domain of a
scene's ``geometry`` section. CAD domains (``geometry.kind = "occ"``, any netgen.occ shape)
are :class:`ngfrac.geometry.cad.OccDomain`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, Sequence, runtime_checkable

import numpy as np
import ngsolve as ngs

from ..fem.threads import meshing_threads, netgen_meshing

__all__ = ["CRACK_BOUNDARY", "BOUNDARY_TOL", "MeshingError", "Domain", "Rectangle", "Box",
           "domain_of", "netgen_geometry", "build_mesh", "crack_polygon_faces"]

CRACK_BOUNDARY = "crack"
"""Name of the interior mesh edges (2D) or faces (3D) that follow the initial cracks."""

BOUNDARY_TOL = 1e-10
"""Default tolerance of :meth:`Domain.on_boundary`, relative to the longest side."""

Cracks = Sequence[Sequence[Sequence[float]]]
"""Polylines [[x, y], ...] (2D) or planar polygons [[x, y, z], ...] (3D)."""


class MeshingError(RuntimeError):
    """Netgen could not mesh the domain (with its cracks), or no mesh meets the vertex cap.

    The message is one line that says what failed and what to change; the CLI prints it
    (exit 3) instead of Netgen's traceback.
    """


def generate_mesh(geometry: Any, maxh: float, what: str, fix: str, dim: int = 2) -> ngs.Mesh:
    """Netgen's quasi-uniform mesh of ``geometry`` (of dimension ``dim``) at ``maxh``; a
    Netgen failure is a :class:`MeshingError` naming ``what`` was meshed and how to ``fix``
    it. A volume is meshed on threads where they paid lately
    (:data:`ngfrac.fem.threads.MESHING_CHOOSER`)."""
    if maxh <= 0:
        raise ValueError(f"maxh must be > 0, got {maxh}")
    with netgen_meshing(dim) as call:
        try:
            ngmesh = geometry.GenerateMesh(maxh=maxh, **meshing_threads(call.threaded))
        except MeshingError:
            raise
        except Exception as err:  # netgen raises plain Exceptions for bad geometries
            raise MeshingError(f"Netgen could not mesh {what} with its cracks ({err}) at "
                               f"maxh = {maxh:g}; {fix}") from None
        call.work = len(ngmesh.Points())
    return ngs.Mesh(ngmesh)


@runtime_checkable
class Domain(Protocol):
    """What ngfrac needs of a domain: geometry with its cracks, boundaries, measure, points."""

    kind: ClassVar[str]
    """The scene's ``geometry.kind``."""

    @property
    def dim(self) -> int:
        """2 or 3."""

    @property
    def boundary_names(self) -> tuple[str, ...]:
        """Names of the boundary parts, as the mesh's boundary conditions are named."""

    @property
    def measure(self) -> float:
        """Area (2D) or volume (3D)."""

    @property
    def diameter(self) -> float:
        """Largest distance between two points of the domain."""

    @property
    def curved(self) -> bool:
        """Whether a boundary edge (face) is curved, so that meshes of order >= 2 are curved
        (:meth:`ngfrac.geometry.cad.OccDomain.curve`)."""

    @property
    def shortest_side(self) -> float:
        """Smallest extent of the domain."""

    def netgen_geometry(self, cracks: Cracks = ()) -> Any:
        """The Netgen geometry with the cracks embedded."""

    def build_mesh(self, maxh: float, cracks: Cracks = ()) -> ngs.Mesh:
        """A quasi-uniform mesh of element size ``maxh``, aligned with the cracks."""

    def on_boundary(self, point: Sequence[float], tol: float | None = None) -> bool:
        """Whether a point of the closed domain lies on its boundary (within ``tol``)."""

    def contains(self, points: Any, tol: float = 0.0) -> Any:
        """Whether points lie in the closed domain (one bool per point)."""

    def sample_points(self, n: int = 0) -> tuple[np.ndarray, ...]:
        """A grid over the domain, for checking expressions: (xs, ys) or (xs, ys, zs)."""

    def boundary_points(self, name: str, n: int = 0) -> tuple[np.ndarray, ...]:
        """A grid on one named boundary part."""


class _AxisAligned:
    """The shared part of an axis-parallel rectangle or box ``origin + [0, extent]``."""

    kind: ClassVar[str]
    FACE_NAMES: ClassVar[tuple[tuple[str, str], ...]]
    """Per axis, the names of the boundary at its low and its high end."""
    CRACK_WORDS: ClassVar[str]
    origin: tuple[float, ...]

    @property
    def extent(self) -> tuple[float, ...]:
        raise NotImplementedError

    @property
    def dim(self) -> int:
        return len(self.extent)

    @property
    def upper(self) -> tuple[float, ...]:
        """The corner opposite the origin."""
        return tuple(o + e for o, e in zip(self.origin, self.extent))

    @property
    def measure(self) -> float:
        return math.prod(self.extent)

    @property
    def diameter(self) -> float:
        return math.hypot(*self.extent)

    @property
    def curved(self) -> bool:
        """Never: the sides are straight."""
        return False

    @property
    def shortest_side(self) -> float:
        return min(self.extent)

    @property
    def longest_side(self) -> float:
        return max(self.extent)

    def sides(self) -> dict[str, tuple[int, float]]:
        """Boundary name -> (axis, coordinate) of the side (face) it names."""
        found = {}
        for axis, (o, e) in enumerate(zip(self.origin, self.extent)):
            low, high = self.FACE_NAMES[axis]
            found[low], found[high] = (axis, o), (axis, o + e)
        return found

    def on_boundary(self, point: Sequence[float], tol: float | None = None) -> bool:
        """Whether a point of the closed domain lies on its boundary.

        ``tol`` defaults to :data:`BOUNDARY_TOL` times the longest side. Only the first
        ``dim`` coordinates count (a 2D point may come with z = 0).
        """
        tol = BOUNDARY_TOL * self.longest_side if tol is None else tol
        return any(abs(p - lo) <= tol or abs(p - hi) <= tol
                   for p, lo, hi in zip(point, self.origin, self.upper))

    def contains(self, points: Any, tol: float = 0.0) -> Any:
        """Whether a point (d,) or points (n, d) lie in the closed domain, within ``tol``."""
        p = np.asarray(points, dtype=float)
        if p.shape[-1] != self.dim:
            raise ValueError(f"points of dimension {p.shape[-1]} in a {self.dim}D {self.kind}")
        low, high = np.asarray(self.origin) - tol, np.asarray(self.upper) + tol
        inside = np.all((p >= low) & (p <= high), axis=-1)
        return bool(inside) if p.ndim == 1 else inside

    def sample_points(self, n: int = 0) -> tuple[np.ndarray, ...]:
        """A regular grid over the domain, ``n`` points per side (0: 201 in 2D, 41 in 3D)."""
        n = n or (201 if self.dim == 2 else 41)
        axes = [np.linspace(o, o + e, n) for o, e in zip(self.origin, self.extent)]
        return tuple(a.ravel() for a in np.meshgrid(*axes, indexing="ij"))

    def boundary_points(self, name: str, n: int = 0) -> tuple[np.ndarray, ...]:
        """A regular grid on one named side (face), ``n`` points per edge (0: as
        :meth:`sample_points`)."""
        for axis, names in enumerate(self.FACE_NAMES):
            if name in names:
                break
        else:
            raise ValueError(f"{name!r} is not a boundary of the {self.kind}")
        n = n or (201 if self.dim == 2 else 41)
        axes = [np.linspace(o, o + e, n) for o, e in zip(self.origin, self.extent)]
        axes[axis] = np.array([self.sides()[name][1]])
        return tuple(a.ravel() for a in np.meshgrid(*axes, indexing="ij"))

    def netgen_geometry(self, cracks: Cracks = ()) -> Any:
        raise NotImplementedError

    def build_mesh(self, maxh: float, cracks: Cracks = ()) -> ngs.Mesh:
        """A quasi-uniform triangular (tetrahedral) mesh with maximal element size ``maxh``,
        with edges (faces) along the cracks.

        Raises
        ------
        MeshingError
            Netgen failed; the message names the domain and what to change.
        """
        return generate_mesh(self.netgen_geometry(cracks), maxh, f"the {self.kind}",
                             f"run ngfrac check on the scene, or change the {self.CRACK_WORDS} "
                             "or the mesh size", dim=self.dim)


@dataclass(frozen=True)
class Rectangle(_AxisAligned):
    """``[x0, x0 + width] x [y0, y0 + height]``; boundaries bottom (y = y0), right, top, left."""

    width: float
    height: float
    origin: tuple[float, ...] = (0.0, 0.0)

    kind: ClassVar[str] = "rectangle"
    FACE_NAMES: ClassVar[tuple[tuple[str, str], ...]] = (("left", "right"), ("bottom", "top"))
    CRACK_WORDS: ClassVar[str] = "cracks"

    @property
    def extent(self) -> tuple[float, ...]:
        return (self.width, self.height)

    @property
    def boundary_names(self) -> tuple[str, ...]:
        return ("bottom", "right", "top", "left")

    def _sides(self) -> list[tuple[str, tuple[float, float], tuple[float, float]]]:
        """The sides counter-clockwise from the bottom: (name, start, end)."""
        (x0, y0), (x1, y1) = self.origin, self.upper
        return [("bottom", (x0, y0), (x1, y0)), ("right", (x1, y0), (x1, y1)),
                ("top", (x1, y1), (x0, y1)), ("left", (x0, y1), (x0, y0))]

    def netgen_geometry(self, cracks: Cracks = ()) -> Any:
        """The ``SplineGeometry`` of the rectangle with the crack polylines as interior lines
        (boundary ``crack``); a crack point on a side splits that side, both parts keep its name.
        """
        from netgen.geom2d import SplineGeometry

        tol = BOUNDARY_TOL * self.longest_side
        geo = SplineGeometry()
        index: dict[tuple[float, float], int] = {}

        def point(p: Sequence[float]) -> int:
            for q, i in index.items():
                if abs(q[0] - p[0]) <= tol and abs(q[1] - p[1]) <= tol:
                    return i
            i = geo.AppendPoint(float(p[0]), float(p[1]))
            index[(float(p[0]), float(p[1]))] = i
            return i

        crack_points = [tuple(p) for line in cracks for p in line]
        for name, a, b in self._sides():
            chain = [a] + _points_on_segment(crack_points, a, b, tol) + [b]
            for p, q in zip(chain[:-1], chain[1:]):
                if point(p) != point(q):
                    geo.Append(["line", point(p), point(q)], leftdomain=1, rightdomain=0, bc=name)
        for line in cracks:
            for p, q in zip(line[:-1], line[1:]):
                if point(p) == point(q):  # Netgen segfaults on a line from a point to itself
                    raise MeshingError(f"a crack segment from {list(p)} to {list(q)} has zero "
                                       "length; remove the repeated point (ngfrac check finds it)")
                middle = (0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1]))
                if self.on_boundary(middle, tol):
                    continue  # only a segment along a side has its middle on the boundary
                geo.Append(["line", point(p), point(q)], leftdomain=1, rightdomain=1,
                           bc=CRACK_BOUNDARY)
        return geo


def _points_on_segment(points: Sequence[Sequence[float]], a: Sequence[float],
                       b: Sequence[float], tol: float) -> list[Sequence[float]]:
    """The points strictly inside segment ab (within ``tol``), ordered from a to b."""
    ax, ay = a
    dx, dy = b[0] - ax, b[1] - ay
    length2 = dx * dx + dy * dy
    on_side = []
    for p in points:
        s = ((p[0] - ax) * dx + (p[1] - ay) * dy) / length2
        off = abs((p[0] - ax) * dy - (p[1] - ay) * dx) / length2 ** 0.5
        if off <= tol and tol < s * length2 ** 0.5 < length2 ** 0.5 - tol:
            on_side.append((s, p))
    return [p for _, p in sorted(on_side)]


@dataclass(frozen=True)
class Box(_AxisAligned):
    """``[x0, x0 + width] x [y0, y0 + height] x [z0, z0 + depth]``; faces left (x = x0),
    right, bottom (y = y0), top, back (z = z0), front."""

    width: float
    height: float
    depth: float
    origin: tuple[float, ...] = (0.0, 0.0, 0.0)

    kind: ClassVar[str] = "box"
    FACE_NAMES: ClassVar[tuple[tuple[str, str], ...]] = (("left", "right"), ("bottom", "top"),
                                                          ("back", "front"))
    CRACK_WORDS: ClassVar[str] = "crack polygons"

    @property
    def extent(self) -> tuple[float, ...]:
        return (self.width, self.height, self.depth)

    @property
    def boundary_names(self) -> tuple[str, ...]:
        return ("left", "right", "bottom", "top", "back", "front")

    def netgen_geometry(self, cracks: Cracks = ()) -> Any:
        """The ``OCCGeometry`` of the box with named faces and each crack polygon glued in as
        an interior face named ``crack`` (``netgen.occ.Glue``), so the tetrahedra have faces
        on it. A polygon with an edge on a box face splits that face; both parts keep its name.
        """
        from netgen import occ

        box = occ.Box(occ.Pnt(*self.origin), occ.Pnt(*self.upper))
        axes = (occ.X, occ.Y, occ.Z)
        for axis, (low, high) in enumerate(self.FACE_NAMES):
            box.faces.Min(axes[axis]).name = low
            box.faces.Max(axes[axis]).name = high
        if not cracks:
            return occ.OCCGeometry(box)
        tol = BOUNDARY_TOL * self.longest_side
        faces = crack_polygon_faces(cracks, tol)
        try:
            return occ.OCCGeometry(occ.Glue([box, *faces]))
        except Exception as err:  # OCC raises plain Exceptions for degenerate wires and faces
            raise MeshingError(f"OCC could not glue the crack polygons into the box ({err}); "
                               "run ngfrac check on the scene") from None


def crack_polygon_faces(cracks: Cracks, tol: float) -> list[Any]:
    """Planar crack polygons as netgen.occ faces named :data:`CRACK_BOUNDARY`, for
    ``occ.Glue`` into a solid.

    Raises
    ------
    MeshingError
        A polygon has an edge shorter than ``tol``, or OCC cannot make its face.
    """
    from netgen import occ

    for polygon in cracks:  # OCC segfaults on an edge from a point to itself
        corners = np.asarray(polygon, dtype=float)
        gaps = np.linalg.norm(corners - np.roll(corners, -1, axis=0), axis=1)
        if np.any(gaps <= tol):
            k = int(np.argmin(gaps))
            raise MeshingError(f"a crack polygon has a zero-length edge at corner {k} "
                               f"{corners[k].tolist()}; remove the repeated corner (ngfrac "
                               "check finds it)")
    faces = []
    try:
        for polygon in cracks:
            corners = [occ.Pnt(*map(float, p)) for p in polygon]
            edges = [occ.Segment(a, b) for a, b in zip(corners, corners[1:] + corners[:1])]
            face = occ.Face(occ.Wire(edges))
            face.name = CRACK_BOUNDARY
            faces.append(face)
    except Exception as err:  # OCC raises plain Exceptions for degenerate wires and faces
        raise MeshingError(f"OCC could not make faces of the crack polygons ({err}); "
                           "run ngfrac check on the scene") from None
    return faces


def domain_of(geometry: Any) -> Domain:
    """The domain of ``geometry``: a :class:`Domain` as it is, or what a description of one
    (a scene's ``geometry`` section, :meth:`ngfrac.scene.Geometry.domain`) builds."""
    if isinstance(geometry, Domain):
        return geometry
    build = getattr(geometry, "domain", None)
    if callable(build):
        return build()
    raise TypeError(f"need a scene Geometry or a Domain, got {type(geometry).__name__}")


def netgen_geometry(geometry: Any, cracks: Cracks = ()) -> Any:
    """The Netgen geometry of a scene geometry with the cracks embedded
    (:meth:`Domain.netgen_geometry`)."""
    return domain_of(geometry).netgen_geometry(cracks)


def build_mesh(geometry: Any, maxh: float, cracks: Cracks = ()) -> ngs.Mesh:
    """A quasi-uniform mesh of a scene geometry, aligned with the cracks
    (:meth:`Domain.build_mesh`).

    Parameters
    ----------
    geometry : Geometry or Domain
        The scene's domain.
    maxh : float
        Maximal element size.
    cracks : list of polylines (2D) or planar polygons (3D), optional
        Initial cracks; the mesh gets edges (faces) along them.
    """
    return domain_of(geometry).build_mesh(maxh, cracks)
