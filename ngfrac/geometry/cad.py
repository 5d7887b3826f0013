"""CAD domains: any netgen.occ shape as a :class:`~ngfrac.geometry.domains.Domain`.

A 2D domain is a face (or faces) in the plane z = 0, a 3D domain a solid. Boundary names are
the names of the shape's edges (2D) or faces (3D), as a STEP file or ``shape.edges[i].name``
gives them; :func:`name_boundaries` sets them from selectors (a name in the file, a bounding
box, a point on the part, an outward normal) and gives every part left unnamed a default name.
Initial cracks are glued in (``netgen.occ.Glue``) as interior edges (2D polylines) or faces
(3D planar polygons) named ``crack``, as the rectangle and the box do it.

Containment is exact in 2D (OCC's distance from the point to the face is 0 inside); in 3D
OCC's distance to a solid is that to its boundary, so points are located in a coarse
tetrahedral mesh of the solid (exact for planar faces, within the chord of a curved face).
"""
from __future__ import annotations

import contextlib
import math
import os
import sys
from pathlib import Path
from typing import Any, ClassVar, Iterable, Mapping, Sequence

import numpy as np
import ngsolve as ngs

from ..fem.threads import meshing_threads
from .domains import BOUNDARY_TOL, CRACK_BOUNDARY, MeshingError, crack_polygon_faces, generate_mesh

__all__ = ["OccDomain", "BoundaryConflict", "EmptyShape", "UnreadableFile", "name_boundaries",
           "shape_from_specs", "read_shape", "split_edges", "connected_pieces", "DEFAULT_BOUNDARY"]

DEFAULT_BOUNDARY = "free"
"""Name of the boundary edges (faces) that neither the shape nor a selector names."""

NORMAL_TOL = 1e-6
"""A part matches a normal selector where 1 - cos(angle) stays below this everywhere."""


class BoundaryConflict(ValueError):
    """A selector matches nothing, or two names claim the same edge (face): one line."""


class EmptyShape(ValueError):
    """The shapes or the file leave no face (2D) or solid (3D): nothing to mesh."""


class UnreadableFile(ValueError):
    """OCC cannot read a CAD file (not STEP, BREP or IGES, or damaged): one line."""


def _pnt(p: Sequence[float]) -> Any:
    from netgen import occ

    return occ.Pnt(*(float(c) for c in p), *([0.0] * (3 - len(p))))


def _sub_parts(shape: Any, dim: int) -> list[Any]:
    """The boundary parts: edges of the faces (2D) or faces of the solids (3D), each once."""
    parts = shape.edges if dim == 2 else shape.faces
    return list(parts)


class OccDomain:
    """A domain from a netgen.occ shape: a face (faces) in z = 0 for 2D, a solid for 3D.

    Parameters
    ----------
    shape : netgen.occ shape
        Its edges (2D) or faces (3D) carry the boundary names; an unnamed one is given
        ``default_name`` (in place: OCC keeps names on the shape).
    default_name : str
        Name of the parts left unnamed.
    curved_order : int
        ``build_mesh`` curves its meshes to this order (0: straight) where the geometry is
        curved; :class:`ngfrac.mesh.fields.MeshFields` curves to the order of u.

    Examples
    --------
    >>> from netgen import occ
    >>> plate = occ.WorkPlane().Rectangle(2, 1).Face() - occ.WorkPlane().Circle(1, 0.5, 0.2).Face()
    >>> plate.edges.Min(occ.Y).name = "bottom"
    >>> OccDomain(plate).boundary_names
    ('bottom', 'free')
    """

    kind: ClassVar[str] = "occ"

    def __init__(self, shape: Any, default_name: str = DEFAULT_BOUNDARY) -> None:
        self.shape = shape
        self._dim = 3 if len(shape.solids) else 2
        if self._dim == 2 and not len(shape.faces):
            raise ValueError("a 2D OCC domain needs a face (e.g. WorkPlane().Rectangle(w, h).Face())")
        box = shape.bounding_box
        pad = 1e-7  # OCC's bounding boxes are enlarged by its tolerance
        self._low = np.array([box[0][k] + pad for k in range(self._dim)])
        self._high = np.array([box[1][k] - pad for k in range(self._dim)])
        if self._dim == 2 and max(abs(box[0][2]), abs(box[1][2])) > 1e-6 * max(
                1.0, float(np.linalg.norm(self._high - self._low))):
            raise ValueError("a 2D OCC domain must lie in the plane z = 0")
        self._parts = _sub_parts(shape, self._dim)
        for part in self._parts:
            if not part.name:
                part.name = default_name
        self._boundary = None
        self._locator: ngs.Mesh | None = None
        self._curved: bool | None = None

    def __repr__(self) -> str:
        return f"OccDomain({self._dim}D, boundaries {', '.join(self.boundary_names)})"

    # -- sizes -----------------------------------------------------------------------------------

    @property
    def dim(self) -> int:
        return self._dim

    @property
    def boundary_names(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(part.name for part in self._parts))

    @property
    def measure(self) -> float:
        """Area (sum over the faces) or volume (over the solids); OCC's ``mass`` of a compound
        is 0, that of each face (solid) is its area (volume)."""
        parts = self.shape.faces if self._dim == 2 else self.shape.solids
        return float(sum(part.mass for part in parts))

    @property
    def origin(self) -> tuple[float, ...]:
        """The lower corner of the bounding box."""
        return tuple(self._low.tolist())

    @property
    def extent(self) -> tuple[float, ...]:
        """The bounding box's sides."""
        return tuple((self._high - self._low).tolist())

    @property
    def diameter(self) -> float:
        """The diagonal of the bounding box (an upper bound of the diameter)."""
        return float(np.linalg.norm(self._high - self._low))

    @property
    def shortest_side(self) -> float:
        """The smallest side of the bounding box."""
        return float(np.min(self._high - self._low))

    @property
    def curved(self) -> bool:
        """Whether a boundary edge (face) is curved, so that meshes should be curved."""
        if self._curved is None:
            self._curved = any(not _is_flat(part, self._dim) for part in self._parts)
        return self._curved

    # -- Netgen ----------------------------------------------------------------------------------

    def netgen_geometry(self, cracks: Any = ()) -> Any:
        """The ``OCCGeometry`` with the cracks glued in as interior edges (2D) or faces (3D)
        named ``crack``; a crack end on the boundary splits that edge, both parts keep its name."""
        from netgen import occ

        if not cracks:
            return occ.OCCGeometry(self.shape, dim=self._dim)
        tol = BOUNDARY_TOL * self.diameter
        pieces = (self._crack_edges(cracks, tol) if self._dim == 2
                  else crack_polygon_faces(cracks, tol))
        try:
            return occ.OCCGeometry(occ.Glue([self.shape, *pieces]), dim=self._dim)
        except Exception as err:  # OCC raises plain Exceptions
            raise MeshingError(f"OCC could not glue the cracks into the shape ({err}); run "
                               "ngfrac check on the scene") from None

    def _crack_edges(self, cracks: Any, tol: float) -> list[Any]:
        from netgen import occ

        edges = []
        for line in cracks:
            for p, q in zip(line[:-1], line[1:]):
                if math.dist(p, q) <= tol:  # OCC fails on an edge from a point to itself
                    raise MeshingError(f"a crack segment from {list(p)} to {list(q)} has zero "
                                       "length; remove the repeated point (ngfrac check finds it)")
                middle = [0.5 * (a + b) for a, b in zip(p, q)]
                if self.on_boundary(middle, tol):
                    continue  # a segment along the boundary changes nothing
                edge = occ.Segment(_pnt(p), _pnt(q))
                edge.name = CRACK_BOUNDARY
                edges.append(edge)
        return edges

    def build_mesh(self, maxh: float, cracks: Any = ()) -> ngs.Mesh:
        """A quasi-uniform mesh of element size ``maxh`` with edges (faces) along the cracks
        (straight elements: :class:`~ngfrac.mesh.fields.MeshFields` curves them).

        Raises
        ------
        MeshingError
            Netgen failed; the message says what to change.
        """
        return generate_mesh(self.netgen_geometry(cracks), maxh, "the OCC shape",
                             "change the cracks or the mesh size", dim=self.dim)

    def curve(self, mesh: ngs.Mesh, order: int, cracks: Any = ()) -> None:
        """Curve ``mesh`` (a mesh of this domain with these cracks) to ``order``.

        A mesh rebuilt from a file (a checkpoint: :class:`ngfrac.io.hdf5.MeshArrays`) has no
        geometry; it gets this domain's, with the cracks glued in as when it was meshed, so
        that Netgen finds the curved edges (faces) by the numbers the file kept.
        """
        from netgen import occ

        if not isinstance(mesh.ngmesh.GetGeometry(), occ.OCCGeometry):
            mesh.ngmesh.SetGeometry(self.netgen_geometry(cracks))
        mesh.Curve(order)

    # -- points ----------------------------------------------------------------------------------

    def _boundary_compound(self) -> Any:
        from netgen import occ

        if self._boundary is None:
            self._boundary = occ.Compound(self._parts)
        return self._boundary

    def distance_to_boundary(self, point: Sequence[float]) -> float:
        """OCC's distance from a point to the boundary edges (faces)."""
        from netgen import occ

        return float(self._boundary_compound().Distance(occ.Vertex(_pnt(point[: self._dim]))))

    def on_boundary(self, point: Sequence[float], tol: float | None = None) -> bool:
        """Whether a point lies within ``tol`` (default :data:`BOUNDARY_TOL` times the
        diameter) of a boundary edge (face)."""
        tol = BOUNDARY_TOL * self.diameter if tol is None else tol
        return self.distance_to_boundary(point) <= tol

    def boundary_names_at(self, point: Sequence[float], tol: float | None = None) -> set[str]:
        """The names of the boundary parts within ``tol`` of a point (a corner may have
        several; none off the boundary)."""
        from netgen import occ

        tol = BOUNDARY_TOL * self.diameter if tol is None else tol
        vertex = occ.Vertex(_pnt(point[: self._dim]))
        return {part.name for part in self._parts if part.Distance(vertex) <= tol}

    def contains(self, points: Any, tol: float = 0.0) -> Any:
        """Whether a point (d,) or points (n, d) lie in the closed domain, within ``tol``."""
        p = np.asarray(points, dtype=float)
        if p.shape[-1] != self._dim:
            raise ValueError(f"points of dimension {p.shape[-1]} in a {self._dim}D OCC domain")
        flat = p.reshape(-1, self._dim)
        slack = tol + BOUNDARY_TOL * self.diameter
        inside = np.all((flat >= self._low - slack) & (flat <= self._high + slack), axis=1)
        candidates = np.flatnonzero(inside)
        inside[candidates] = (self._contains_2d(flat[candidates], slack) if self._dim == 2
                              else self._contains_3d(flat[candidates], slack))
        return bool(inside[0]) if p.ndim == 1 else inside

    def _contains_2d(self, points: np.ndarray, slack: float) -> np.ndarray:
        from netgen import occ

        return np.array([self.shape.Distance(occ.Vertex(_pnt(q))) <= slack for q in points],
                        dtype=bool)

    def _contains_3d(self, points: np.ndarray, slack: float) -> np.ndarray:
        if self._locator is None:
            self._locator = ngs.Mesh(self.netgen_geometry().GenerateMesh(
                maxh=self.diameter / 8, **meshing_threads()))
        if not len(points):
            return np.zeros(0, dtype=bool)
        located = self._locator(points[:, 0], points[:, 1], points[:, 2])["nr"] >= 0
        near = np.flatnonzero(~located)
        located[near] = [self.distance_to_boundary(q) <= slack for q in points[near]]
        return located

    def sample_points(self, n: int = 0) -> tuple[np.ndarray, ...]:
        """The points of an ``n``-per-side grid over the bounding box (0: 41 in 2D, 13 in 3D)
        that the domain contains."""
        n = n or (41 if self._dim == 2 else 13)
        axes = [np.linspace(a, b, n) for a, b in zip(self._low, self._high)]
        grid = np.stack([a.ravel() for a in np.meshgrid(*axes, indexing="ij")], axis=1)
        keep = self.contains(grid)
        return tuple(grid[keep, k] for k in range(self._dim))

    def boundary_points(self, name: str, n: int = 0) -> tuple[np.ndarray, ...]:
        """Points on the boundary parts called ``name``: ``n`` per edge (0: 51) in 2D, the
        vertices of a coarse surface mesh of the faces in 3D."""
        parts = [part for part in self._parts if part.name == name]
        if not parts:
            raise ValueError(f"{name!r} is not a boundary of the OCC domain; boundaries are "
                             f"{', '.join(self.boundary_names)}")
        points = np.concatenate([_part_points(part, self._dim, n or 51) for part in parts])
        return tuple(points[:, k] for k in range(self._dim))


def _edge_points(edge: Any, n: int) -> np.ndarray:
    t0, t1 = edge.parameter_interval
    return np.array([[q.x, q.y, q.z] for q in (edge.Value(t) for t in np.linspace(t0, t1, n))])


def _face_triangles(face: Any) -> np.ndarray:
    """(m, 3, 3) triangles of a coarse Netgen surface mesh of one face.

    (``TopoDS_Shape.Triangulation()`` returns a type pybind11 cannot convert in netgen
    6.2.2608, so the face is meshed by Netgen instead.)"""
    from netgen import occ

    box = face.bounding_box
    size = max(box[1][k] - box[0][k] for k in range(3))
    geo = occ.OCCGeometry(face, dim=3)
    ngmesh = geo.GenerateMesh(maxh=size / 6, perfstepsend=3)  # MESHSURFACE: stop at the surface
    coords = np.array([list(p.p) for p in ngmesh.Points()])
    triangles = [[v.nr - 1 for v in el.vertices] for el in ngmesh.Elements2D()]
    return coords[np.asarray(triangles, dtype=int)]


def _part_points(part: Any, dim: int, n: int) -> np.ndarray:
    if dim == 2:
        return _edge_points(part, n)[:, :2]
    return np.unique(_face_triangles(part).reshape(-1, 3), axis=0)


def _part_normals(part: Any, dim: int) -> tuple[np.ndarray, np.ndarray]:
    """Points on a part and a unit normal at each (sign not yet outward)."""
    if dim == 2:
        t0, t1 = part.parameter_interval
        ts = np.linspace(t0, t1, 9)[1:-1]
        points = np.array([[part.Value(t).x, part.Value(t).y] for t in ts])
        tangents = np.array([[part.Tangent(t).x, part.Tangent(t).y] for t in ts])
        normals = np.stack([tangents[:, 1], -tangents[:, 0]], axis=1)
    else:
        tri = _face_triangles(part)
        points = tri.mean(axis=1)
        normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    lengths = np.linalg.norm(normals, axis=1, keepdims=True)
    return points, normals / np.where(lengths > 0, lengths, 1.0)


def _is_flat(part: Any, dim: int) -> bool:
    """Whether an edge is straight (2D) or a face planar (3D)."""
    if dim == 2:
        points = _edge_points(part, 5)
        chord = np.linalg.norm(points[-1] - points[0])
        length = float(part.mass)
        return chord > 0 and abs(length - chord) <= 1e-9 * length
    _, normals = _part_normals(part, dim)
    return bool(np.all(np.abs(normals @ normals[0]) >= 1 - NORMAL_TOL))


# -- building shapes ---------------------------------------------------------------------------

SHAPES_2D = ("rectangle", "circle", "ellipse", "polygon")
SHAPES_3D = ("box", "cylinder", "sphere")
OPS = ("add", "cut", "intersect")


def _signed_area(points: Sequence[tuple[float, float]]) -> float:
    """The shoelace area of a closed 2D polygon: positive when its corners run
    counter-clockwise."""
    x, y = np.asarray(points, dtype=float).T
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _primitive(spec: Any) -> Any:
    """One netgen.occ shape of a scene's ``[[geometry.shapes]]`` entry."""
    from netgen import occ

    kind = spec.type
    if kind == "rectangle":
        (x, y), (w, h) = spec.corner, spec.size
        return occ.WorkPlane().MoveTo(x, y).Rectangle(w, h).Face()
    if kind == "circle":
        return occ.WorkPlane().Circle(*spec.center, spec.radius).Face()
    if kind == "ellipse":
        (x, y), (a, b) = spec.center, spec.radii
        plane = occ.WorkPlane().MoveTo(x, y)
        if a < b:  # the first radius is along the current direction, and must be the major one
            return plane.Direction(0, 1).Ellipse(b, a).Face()
        return plane.Ellipse(a, b).Face()
    if kind == "polygon":
        # counter-clockwise: a face built from a clockwise wire has a negative area, and
        # cutting it out of a shape leaves the shape whole (OCC splits off the polygon as a
        # second face instead, which the merge of touching faces then joins back)
        points = [tuple(point) for point in spec.points]
        if _signed_area(points) < 0:
            points.reverse()
        plane = occ.WorkPlane().MoveTo(*points[0])
        for point in points[1:]:
            plane = plane.LineTo(*point)
        return plane.Close().Face()
    if kind == "box":
        corner = np.asarray(spec.corner, dtype=float)
        return occ.Box(_pnt(corner), _pnt(corner + np.asarray(spec.size, dtype=float)))
    if kind == "cylinder":
        return occ.Cylinder(_pnt(spec.center), occ.Vec(*spec.axis), r=spec.radius, h=spec.height)
    if kind == "sphere":
        return occ.Sphere(_pnt(spec.center), spec.radius)
    raise ValueError(f"unknown shape type {kind!r}")


def shape_from_specs(specs: Iterable[Any]) -> Any:
    """The shape of ``[[geometry.shapes]]``: the first entry, then each one added (fused),
    cut or intersected in order; faces (solids) that touch are merged (``UnifySameDomain``)."""
    shape = None
    for i, spec in enumerate(specs):
        piece = _primitive(spec)
        if shape is None:
            shape = piece
        elif spec.op == "add":
            shape = shape + piece
        elif spec.op == "cut":
            shape = shape - piece
        else:
            shape = shape * piece
        if not len(shape.solids if spec.type in SHAPES_3D else shape.faces):
            what = "intersection with" if spec.op == "intersect" else spec.op
            raise EmptyShape(f"shapes[{i}] ({what} {spec.type}) leaves nothing of the domain; "
                             "make the holes and notches smaller or move them")
    if shape is None:
        raise ValueError("no shapes")
    return shape.UnifySameDomain()


CAD_SUFFIXES = {".step": "STEP", ".stp": "STEP", ".brep": "BREP", ".iges": "IGES", ".igs": "IGES"}
"""The file types :func:`read_shape` reads, by suffix (as Netgen's ``OCCGeometry`` does)."""


@contextlib.contextmanager
def _quiet_output():
    """Silence what OCC's readers print on the C level (file descriptors 1 and 2): a
    damaged file makes them write their own error lines, and ngfrac's is one line."""
    for stream in (sys.stdout, sys.stderr):
        stream.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            os.dup2(null.fileno(), 2)
            yield
    finally:
        for fd, copy in zip((1, 2), saved):
            os.dup2(copy, fd)
            os.close(copy)


def read_shape(path: str | Path, scale: float = 1.0) -> Any:
    """The shape of a STEP, BREP or IGES file (names of edges and faces kept), times
    ``scale`` about the origin. A file without solids is a 2D domain (faces in z = 0).

    Raises
    ------
    FileNotFoundError
        No such file.
    UnreadableFile
        Not one of the suffixes of :data:`CAD_SUFFIXES`, or OCC cannot read it.
    EmptyShape
        The file holds no face and no solid (only curves or points, or nothing).
    """
    from netgen import occ

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no CAD file {str(path)!r}")
    kind = CAD_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise UnreadableFile(f"{path.name!r} is not a CAD file ngfrac reads; give a "
                             f"{', '.join(sorted(CAD_SUFFIXES))} file")
    try:
        with _quiet_output():
            shape = occ.OCCGeometry(str(path)).shape
            empty = not len(shape.faces)
    except Exception as err:  # OCC raises plain Exceptions for files it cannot parse
        text = " ".join(str(err).split())
        article = "an" if kind == "IGES" else "a"
        raise UnreadableFile(f"OCC cannot read it as {article} {kind} file ({text}); export it again "
                             "from the CAD program") from None
    if empty:
        raise EmptyShape(f"the {kind} file holds no face or solid (only curves or points, or "
                         "nothing); export the part's faces (2D) or its solid (3D)")
    if scale != 1.0:
        shape = shape.Scale(occ.Pnt(0, 0, 0), scale)
    return shape


def connected_pieces(shape: Any) -> int:
    """How many separate pieces ``shape`` is: its solids (a solid shape) or faces (a planar
    one), joined where two share a face (an edge). ``shape_from_specs`` merges shapes that
    touch into one face (solid), so there a count above one means a cut split the domain or a
    shape does not touch the others; a file may hold several faces of one part, which share
    edges. OCC's hash of a sub-shape is that of the shared topological entity, whatever
    its orientation in either neighbour."""
    parts, sub = (shape.solids, "faces") if len(shape.solids) else (shape.faces, "edges")
    parent = list(range(len(parts)))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    owner: dict[int, int] = {}
    for i, part in enumerate(parts):
        for boundary in getattr(part, sub):
            j = owner.setdefault(hash(boundary), i)
            parent[root(i)] = root(j)
    return len({root(i) for i in range(len(parts))})


def split_edges(shape: Any, points: Sequence[Sequence[float]]) -> Any:
    """``shape`` (2D) with its boundary edges split at ``points``: a vertex glued onto each
    (``netgen.occ.Glue``), so that a circle becomes two arcs a selector can name apart.

    (``shape_from_specs`` cannot do it with shapes: ``UnifySameDomain`` joins arcs of one
    circle back into one edge, as it joins collinear segments.)

    Raises
    ------
    BoundaryConflict
        The shape is 3D, or a point lies on no boundary edge (within 1e-6 of the diameter).
    """
    from netgen import occ

    if len(shape.solids):
        raise BoundaryConflict("geometry.split_points splits edges of a 2D domain; the shape "
                               "is 3D: remove split_points")
    box = shape.bounding_box
    tol = 1e-6 * math.dist(tuple(box[0]), tuple(box[1]))
    edges = occ.Compound(list(shape.edges))
    for i, point in enumerate(points):
        if edges.Distance(occ.Vertex(_pnt(point))) > tol:
            raise BoundaryConflict(f"geometry.split_points[{i}] = {list(point)} lies on no "
                                   "boundary edge of the shape; give a point on the edge to split")
    return occ.Glue([shape, *(occ.Vertex(_pnt(point)) for point in points)])


# -- boundary selectors ------------------------------------------------------------------------

def _matches(domain: OccDomain, part: Any, selector: Any, tol: float,
             file_names: Mapping[Any, str]) -> bool:
    from netgen import occ

    dim = domain.dim
    if selector.named:
        return file_names.get(part, "") == selector.named
    if selector.box:
        low, high = (np.asarray(c, dtype=float) for c in selector.box)
        box = part.bounding_box
        part_low = np.array([box[0][k] + 1e-7 for k in range(dim)])
        part_high = np.array([box[1][k] - 1e-7 for k in range(dim)])
        return bool(np.all(part_low >= low - tol) and np.all(part_high <= high + tol))
    if selector.point:
        return part.Distance(occ.Vertex(_pnt(selector.point))) <= tol
    wanted = np.asarray(selector.normal, dtype=float)
    wanted = wanted / np.linalg.norm(wanted)
    points, normals = _part_normals(part, dim)
    if not np.all(np.abs(normals @ wanted) >= 1 - NORMAL_TOL):
        return False
    step = 1e-4 * domain.diameter  # which side of the part the domain lies on
    sign = np.sign(normals[0] @ wanted)
    return not domain.contains(points[0] + step * sign * normals[0])


def _check_selector_dimension(i: int, selector: Any, dim: int) -> None:
    """A box, point or normal with as many coordinates as the shape has dimensions."""
    for key in ("box", "point", "normal"):
        value = getattr(selector, key)
        if not value:
            continue
        n = len(value[0]) if key == "box" else len(value)
        if n != dim:
            text = [list(c) for c in value] if key == "box" else list(value)
            raise BoundaryConflict(f"geometry.boundaries[{i}].{key} = {text} has {n} coordinates "
                                   f"but the shape is {dim}D; give {dim}")


def name_boundaries(shape: Any, selectors: Sequence[Any], default_name: str = DEFAULT_BOUNDARY,
                    ) -> OccDomain:
    """Name the boundary parts of ``shape`` by selectors and return its domain.

    A selector has a ``name`` and one of ``named`` (the part's name in the file), ``box``
    ([low, high] corners: parts inside it), ``point`` (parts through it, within ``tol``) or
    ``normal`` (straight edges or planar faces with this outward normal).

    Raises
    ------
    BoundaryConflict
        A selector matches nothing, has coordinates of another dimension than the shape's,
        or two selectors with different names match one part.
    """
    dim = 3 if len(shape.solids) else 2
    parts = _sub_parts(shape, dim)
    file_names = {part: part.name or "" for part in parts}
    for part in parts:
        part.name = None
    probe = OccDomain(shape, default_name="")  # for containment and the diameter only
    chosen: dict[Any, tuple[str, int]] = {}
    for i, selector in enumerate(selectors):
        _check_selector_dimension(i, selector, dim)
        tol = selector.tol or 1e-6 * probe.diameter
        matched = [part for part in parts if _matches(probe, part, selector, tol, file_names)]
        if not matched:
            raise BoundaryConflict(f"geometry.boundaries[{i}] ({selector.describe()}) matches no "
                                   f"{'edge' if dim == 2 else 'face'} of the shape")
        for part in matched:
            name, j = chosen.get(part, (selector.name, i))
            if name != selector.name:
                raise BoundaryConflict(f"geometry.boundaries[{j}] ({name!r}) and "
                                       f"geometry.boundaries[{i}] ({selector.name!r}) claim the "
                                       f"same {'edge' if dim == 2 else 'face'}; make them disjoint")
            chosen[part] = (name, j)
    for part in parts:
        part.name = chosen[part][0] if part in chosen else (file_names[part] or default_name)
    return probe  # its names are the parts' (now set); it keeps what it has computed
