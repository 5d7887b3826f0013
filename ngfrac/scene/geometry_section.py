"""The ``[geometry]`` section (with its ``[[geometry.shapes]]`` and ``[[geometry.boundaries]]``)
and the ``[[cracks]]``: the domain a scene describes and its initial cracks.

:meth:`Geometry.domain` builds the :class:`~ngfrac.geometry.domains.Domain` of the section
(a rectangle, a box, or a CAD shape: :func:`occ_domain_of`).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..geometry.domains import Box, Rectangle
from .coercion import REQUIRED, SceneError, Section, dotted_key, plain, require

if TYPE_CHECKING:
    from ..geometry.domains import Domain

__all__ = ["GEOMETRY_KINDS", "OCC_KEYS", "SHAPE_TYPES_2D", "SHAPE_TYPES_3D", "AxisAlignedKind",
           "BoundarySelector", "BoxKind", "Crack", "Geometry", "GeometryKind", "OccKind",
           "RectangleKind", "Shape", "occ_domain_of"]


SHAPE_TYPES_2D = ("rectangle", "circle", "ellipse", "polygon")
"""``[[geometry.shapes]]`` types of a 2D OCC domain."""

SHAPE_TYPES_3D = ("box", "cylinder", "sphere")
"""``[[geometry.shapes]]`` types of a 3D OCC domain."""


@dataclass(frozen=True)
class Shape(Section):
    """One ``[[geometry.shapes]]`` entry of an OCC domain, combined with those before it.

    ``rectangle``: ``corner = [x, y]``, ``size = [w, h]``. ``circle``: ``center``, ``radius``.
    ``ellipse``: ``center``, ``radii = [rx, ry]``. ``polygon``: ``points = [[x, y], ...]``.
    ``box``: ``corner = [x, y, z]``, ``size = [w, h, d]``. ``cylinder``: ``center`` (of the
    base), ``axis``, ``radius``, ``height``. ``sphere``: ``center``, ``radius``. ``op``:
    ``"add"`` (union), ``"cut"`` (difference: holes, notches) or ``"intersect"``.
    """

    SECTION: ClassVar[str] = "geometry.shapes"
    KEYS: ClassVar[dict[str, tuple[str, ...]]] = {
        "rectangle": ("corner", "size"), "circle": ("center", "radius"),
        "ellipse": ("center", "radii"), "polygon": ("points",), "box": ("corner", "size"),
        "cylinder": ("center", "axis", "radius", "height"), "sphere": ("center", "radius")}
    type: str = REQUIRED  # type: ignore[assignment]
    op: str = "add"
    corner: tuple[float, ...] = ()
    size: tuple[float, ...] = ()
    center: tuple[float, ...] = ()
    radius: float = 0.0
    radii: tuple[float, ...] = ()
    points: tuple[tuple[float, ...], ...] = ()
    axis: tuple[float, ...] = ()
    height: float = 0.0

    def validate(self) -> None:
        s = self.SECTION
        require(self.type in self.KEYS, s, "type", self.type,
                f"choose one of {', '.join(self.KEYS)}")
        require(self.op in ("add", "cut", "intersect"), s, "op", self.op,
                "choose 'add' (union), 'cut' (difference) or 'intersect'")
        needed = self.KEYS[self.type]
        for f in dataclasses.fields(self):
            if f.name in ("type", "op"):
                continue
            given = getattr(self, f.name) != f.default
            require(given == (f.name in needed), s, f.name, getattr(self, f.name),
                    f"a {self.type} takes {', '.join(needed)}" if given
                    else f"a {self.type} needs {f.name}")
        n = self.dim
        for key in ("corner", "center", "axis"):
            if key in needed:
                require(len(getattr(self, key)) == n, s, key, list(getattr(self, key)),
                        f"give {n} coordinates")
        for key in ("size", "radii"):
            if key in needed:
                require(len(getattr(self, key)) == (2 if key == "radii" else n)
                        and min(getattr(self, key)) > 0, s, key, list(getattr(self, key)),
                        "give positive lengths, one per axis")
        for key in ("radius", "height"):
            if key in needed:
                require(getattr(self, key) > 0, s, key, getattr(self, key), "must be > 0")
        if self.type == "polygon":
            require(len(self.points) >= 3 and all(len(p) == 2 for p in self.points), s,
                    "points", [list(p) for p in self.points],
                    "a polygon needs at least three corners [[x, y], ...]")
        if self.type == "cylinder":
            require(any(self.axis), s, "axis", list(self.axis), "the axis must not be zero")

    @property
    def dim(self) -> int:
        """2 for the plane shapes, 3 for the solids."""
        return 3 if self.type in SHAPE_TYPES_3D else 2


@dataclass(frozen=True)
class BoundarySelector(Section):
    """One ``[[geometry.boundaries]]`` entry: ``name`` for the edges (2D) or faces (3D) that
    one selector picks: ``named`` (their name in the CAD file), ``box = [[x0, y0], [x1, y1]]``
    (those inside the box), ``point = [x, y]`` (those through the point, within ``tol``) or
    ``normal = [nx, ny]`` (straight edges, planar faces, with this outward normal)."""

    SECTION: ClassVar[str] = "geometry.boundaries"
    SELECTORS: ClassVar[tuple[str, ...]] = ("named", "box", "point", "normal")
    name: str = REQUIRED  # type: ignore[assignment]
    named: str = ""
    box: tuple[tuple[float, ...], ...] = ()
    point: tuple[float, ...] = ()
    normal: tuple[float, ...] = ()
    tol: float = 0.0
    """Distance tolerance of ``box`` and ``point``; 0: 1e-6 times the domain's diameter."""

    def validate(self) -> None:
        s = self.SECTION
        require(bool(self.name) and self.name != "crack", s, "name", self.name,
                "give a name other than '' and 'crack' (the initial cracks' edges)")
        given = [k for k in self.SELECTORS if getattr(self, k)]
        require(len(given) == 1, s, "name", self.name,
                f"give exactly one of {', '.join(self.SELECTORS)} (given: {', '.join(given) or 'none'})")
        if self.box:
            require(len(self.box) == 2 and len(self.box[0]) == len(self.box[1]) in (2, 3), s,
                    "box", [list(p) for p in self.box], "give [[x0, y0], [x1, y1]] (3D: [x, y, z])")
        if self.normal:
            require(any(self.normal), s, "normal", list(self.normal), "must not be zero")
        require(self.tol >= 0, s, "tol", self.tol, "must be >= 0 (0: 1e-6 of the diameter)")

    def describe(self) -> str:
        """The selector as the scene writes it, for messages."""
        key = next(k for k in self.SELECTORS if getattr(self, k))
        value = getattr(self, key)
        text = repr(value) if isinstance(value, str) else str(plain(value))
        return f"name = {self.name!r}, {key} = {text}"


OCC_KEYS = ("shapes", "boundaries", "file", "scale", "default_boundary", "split_points")
"""The keys of ``geometry.kind = "occ"`` only."""


class GeometryKind:
    """How one ``geometry.kind`` is checked and built from the ``[geometry]`` section
    (subclass per kind, its name in :data:`GEOMETRY_KINDS`); the domain itself is a class of
    :mod:`ngfrac.geometry` (the :class:`~ngfrac.geometry.domains.Domain` protocol)."""

    name: ClassVar[str]
    choice: ClassVar[str]
    """The kind as the message for an unknown kind offers it: ``'box' (3D)``."""
    required_keys: ClassVar[tuple[str, ...]] = ()
    """Keys this kind needs (NaN when not given)."""
    foreign_keys: ClassVar[tuple[str, ...]] = ()
    """Keys of other kinds that this kind refuses and ``to_dict`` leaves out."""

    def validate(self, geometry: "Geometry") -> None:
        """The kind's own checks of the section (after ``kind`` and ``mesh_size``)."""

    def domain(self, geometry: "Geometry") -> "Domain":
        """The domain of a validated section."""
        raise NotImplementedError

    def describe(self, geometry: "Geometry") -> str:
        """The domain as messages name it (``cracks[i].points ... lies outside the domain``)."""
        raise NotImplementedError

    def dimension_problem(self, geometry: "Geometry", model_kind: str,
                          kinds_3d: tuple[str, ...], kinds_2d: tuple[str, ...]) -> str | None:
        """Why the domain's dimension does not fit ``model.kind`` (3D models
        ``kinds_3d``, 2D ones ``kinds_2d``), or None."""
        return None


class AxisAlignedKind(GeometryKind):
    """The rectangle and the box: width, height (a box also depth) and an origin."""

    required_keys = ("width", "height")
    foreign_keys = OCC_KEYS

    def validate(self, geometry: "Geometry") -> None:
        s = geometry.SECTION
        for key in OCC_KEYS:
            value = getattr(geometry, key)
            require(value == Geometry.__dataclass_fields__[key].default, s, key, plain(value),
                    "only geometry.kind = 'occ' takes it")
        require(geometry.width > 0, s, "width", geometry.width, "must be > 0")
        require(geometry.height > 0, s, "height", geometry.height, "must be > 0")

    def describe(self, geometry: "Geometry") -> str:
        return " x ".join(f"[{o}, {o + e}]" for o, e in zip(geometry.origin, geometry.extent))

    def dimension_problem(self, geometry: "Geometry", model_kind: str,
                          kinds_3d: tuple[str, ...], kinds_2d: tuple[str, ...]) -> str | None:
        if model_kind in kinds_3d and geometry.dim != 3:
            return (f"model.kind = {model_kind!r} is 3D but geometry.kind = {self.name!r} is 2D; "
                    "set geometry.kind = 'box' (with depth)")
        if model_kind not in kinds_3d and geometry.dim == 3:
            return (f"geometry.kind = {self.name!r} is 3D but model.kind = {model_kind!r} is 2D; "
                    f"set model.kind = {kinds_3d[0]!r}")
        return None


class RectangleKind(AxisAlignedKind):
    """``geometry.kind = "rectangle"``: :class:`ngfrac.geometry.domains.Rectangle`."""

    name = "rectangle"
    choice = "'rectangle' (2D)"

    def validate(self, geometry: "Geometry") -> None:
        super().validate(geometry)
        s = geometry.SECTION
        require(len(geometry.origin) == 2, s, "origin", list(geometry.origin), "give [x, y]")
        require(geometry.depth == 0, s, "depth", geometry.depth,
                "only a box has a depth; set geometry.kind = 'box' or remove depth")

    def domain(self, geometry: "Geometry") -> "Domain":
        return Rectangle(geometry.width, geometry.height, tuple(geometry.origin))


class BoxKind(AxisAlignedKind):
    """``geometry.kind = "box"``: :class:`ngfrac.geometry.domains.Box`."""

    name = "box"
    choice = "'box' (3D)"

    def validate(self, geometry: "Geometry") -> None:
        super().validate(geometry)
        s = geometry.SECTION
        if geometry.origin is Geometry.__dataclass_fields__["origin"].default:
            object.__setattr__(geometry, "origin", (0.0, 0.0, 0.0))  # not given: the 3D zero
        require(len(geometry.origin) == 3, s, "origin", list(geometry.origin),
                "a box needs [x, y, z]")
        require(geometry.depth > 0, s, "depth", geometry.depth, "a box needs depth > 0")

    def domain(self, geometry: "Geometry") -> "Domain":
        return Box(geometry.width, geometry.height, geometry.depth, tuple(geometry.origin))


class OccKind(GeometryKind):
    """``geometry.kind = "occ"``: shapes or a CAD file, :class:`ngfrac.geometry.cad.OccDomain`
    (:func:`occ_domain_of`)."""

    name = "occ"
    choice = "'occ' (CAD shapes or a file)"

    def validate(self, geometry: "Geometry") -> None:
        """Shapes or a file, no rectangle keys; building the domain checks the selectors."""
        s = geometry.SECTION
        for key in ("width", "height", "depth"):
            value = getattr(geometry, key)
            require(math.isnan(value) or value == 0, s, key, value,
                    "an occ domain takes its extent from its shapes or file; remove it")
        require(geometry.origin == (0.0, 0.0), s, "origin", list(geometry.origin),
                "an occ domain has no origin; move its shapes")
        require(bool(geometry.shapes) != bool(geometry.file), s, "shapes",
                [f"{shape.type}" for shape in geometry.shapes],
                "give [[geometry.shapes]] or geometry.file, not both (nor neither)")
        require(geometry.scale > 0, s, "scale", geometry.scale, "must be > 0")
        for point in geometry.split_points:
            require(len(point) == 2, s, "split_points", [list(p) for p in geometry.split_points],
                    "give points [x, y] on the edges of a 2D domain")
        require(bool(geometry.default_boundary) and geometry.default_boundary != "crack", s,
                "default_boundary", geometry.default_boundary,
                "give a name other than '' and 'crack'")
        if geometry.shapes:
            require(geometry.shapes[0].op == "add", s, "shapes[0].op", geometry.shapes[0].op,
                    "the first shape starts the domain: use op = 'add'")
            dims = {shape.dim for shape in geometry.shapes}
            require(len(dims) == 1, s, "shapes", [shape.type for shape in geometry.shapes],
                    f"mix no plane shapes ({', '.join(SHAPE_TYPES_2D)}) with solids "
                    f"({', '.join(SHAPE_TYPES_3D)})")
        geometry.domain()  # raises SceneError for a selector that matches nothing or a conflict

    def domain(self, geometry: "Geometry") -> "Domain":
        return occ_domain_of(geometry)

    def describe(self, geometry: "Geometry") -> str:
        return "(the occ shape)"

    def dimension_problem(self, geometry: "Geometry", model_kind: str,
                          kinds_3d: tuple[str, ...], kinds_2d: tuple[str, ...]) -> str | None:
        """A CAD file or shapes of the other dimension than the model's."""
        dim = geometry.dim
        source = f"geometry.file = {geometry.file!r}" if geometry.file else "geometry.shapes"
        models_2d = ", ".join(repr(k) for k in kinds_2d)
        if model_kind in kinds_3d and dim != 3:
            return (f"{source} is 2D (faces, no solid) but model.kind = {model_kind!r} is 3D; "
                    f"give a solid or a 2D model.kind ({models_2d})")
        if model_kind not in kinds_3d and dim == 3:
            return (f"{source} is 3D (a solid) but model.kind = {model_kind!r} is 2D; set "
                    f"model.kind = {kinds_3d[0]!r} or give a planar face in z = 0")
        return None


GEOMETRY_KINDS: dict[str, GeometryKind] = {kind.name: kind()
                                          for kind in (RectangleKind, BoxKind, OccKind)}
"""The values of ``geometry.kind``, in the order messages list them."""


@dataclass(frozen=True)
class Geometry(Section):
    """The domain: an axis-parallel rectangle (2D) or box (3D), or a CAD shape (``occ``).

    ``rectangle``: [x0, x0 + width] x [y0, y0 + height], boundaries bottom (y = y0), right,
    top, left. ``box``: [x0, x0 + width] x [y0, y0 + height] x [z0, z0 + depth], faces left
    (x = x0), right (x = x0 + width), bottom (y = y0), top (y = y0 + height), back (z = z0),
    front (z = z0 + depth). ``occ``: ``[[geometry.shapes]]`` (:class:`Shape`) or a CAD
    ``file`` (STEP, BREP, IGES; times ``scale``), boundaries named by ``[[geometry.boundaries]]``
    (:class:`BoundarySelector`) and the file; the rest is ``default_boundary``
    (:mod:`ngfrac.geometry.cad`). ``split_points`` split boundary edges (2D) before they are named.
    """

    SECTION: ClassVar[str] = "geometry"
    OCC_KEYS: ClassVar[tuple[str, ...]] = OCC_KEYS
    BOUNDARIES: ClassVar[tuple[str, ...]] = ("bottom", "right", "top", "left")
    BOUNDARIES_3D: ClassVar[tuple[str, ...]] = ("left", "right", "bottom", "top", "back", "front")
    width: float = math.nan
    """Required for a rectangle or a box."""
    height: float = math.nan
    kind: str = "rectangle"
    origin: tuple[float, ...] = (0.0, 0.0)
    depth: float = 0.0
    """Extent in z of a box; 0 (not given) for a rectangle."""
    mesh_size: float = 0.0
    """Uniform maximal element size; 0 means epsilon/2."""
    shapes: tuple[Shape, ...] = ()
    boundaries: tuple[BoundarySelector, ...] = ()
    file: str = ""
    scale: float = 1.0
    default_boundary: str = "free"
    split_points: tuple[tuple[float, ...], ...] = ()
    """Points on boundary edges of a 2D occ domain where an edge is split in two (e.g. a
    hole's circle into two arcs, so that selectors can name each)."""

    def validate(self) -> None:
        s = self.SECTION
        kind = GEOMETRY_KINDS.get(self.kind)
        for key in kind.required_keys if kind else ():
            if math.isnan(getattr(self, key)):
                raise SceneError(f"missing key {dotted_key(s, key)!r}; it is required")
        choices = [k.choice for k in GEOMETRY_KINDS.values()]
        require(kind is not None, s, "kind", self.kind,
                f"choose {', '.join(choices[:-1])} or {choices[-1]}")
        require(self.mesh_size >= 0, s, "mesh_size", self.mesh_size,
                "must be > 0 (or 0 for epsilon/2)")
        kind.validate(self)

    @property
    def kind_of(self) -> "GeometryKind":
        """The :class:`GeometryKind` of ``kind`` (:data:`GEOMETRY_KINDS`)."""
        return GEOMETRY_KINDS[self.kind]

    @property
    def dim(self) -> int:
        """2 or 3: the domain's (a rectangle's 2, a box's 3, an occ domain's own)."""
        return self.domain().dim

    @property
    def extent(self) -> tuple[float, ...]:
        """(width, height) or (width, height, depth); an occ domain's bounding box."""
        return self.domain().extent

    @property
    def shortest_side(self) -> float:
        return min(self.extent)

    @property
    def boundary_names(self) -> tuple[str, ...]:
        return self.domain().boundary_names

    def describe(self) -> str:
        """The domain as messages name it: ``[0, 1] x [0, 2]``, or ``(the occ shape)``."""
        return self.kind_of.describe(self)

    def domain(self) -> "Domain":
        """The domain this section describes (:meth:`GeometryKind.domain`): its boundary and
        containment tests, measure and sample points live there. It is built once per
        section (for an occ domain OCC work) and kept, so every caller gets the one object."""
        built = self.__dict__.get("_domain")
        if built is None:
            built = self.kind_of.domain(self)
            object.__setattr__(self, "_domain", built)
        return built

    def __getstate__(self) -> dict[str, Any]:
        """Copies and pickles leave out the built domain (OCC shapes do not pickle); they
        build it again from the keys (``shapes`` or ``file``)."""
        return {k: v for k, v in self.__dict__.items() if k != "_domain"}

    IN_CODE: ClassVar[str] = "<shape in code>"
    """The ``file`` of a geometry made by :meth:`of_domain`."""

    @classmethod
    def of_domain(cls, domain: "Domain", mesh_size: float = 0.0) -> "Geometry":
        """An occ geometry section for a domain built in code (an
        :class:`~ngfrac.geometry.cad.OccDomain` of any netgen.occ shape), for a :class:`Scene`.

        Its ``file`` is :attr:`IN_CODE`: such a scene cannot be written to and read from TOML,
        and ``dataclasses.replace``, copies and pickles of this section lose the domain
        (``dataclasses.replace`` of the scene keeps the section and so the domain).
        """
        geometry = cls.__new__(cls)
        object.__setattr__(geometry, "_domain", domain)
        cls.__init__(geometry, kind="occ", file=cls.IN_CODE, mesh_size=mesh_size)
        return geometry

    def to_dict(self) -> dict[str, Any]:
        """The keys as a scene file writes them: no occ keys for a rectangle or box, none of
        a shape's or selector's keys at their defaults."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, float) and math.isnan(value):
                continue
            if f.name in self.kind_of.foreign_keys:
                continue
            if f.name in ("shapes", "boundaries"):
                value = [{g.name: plain(getattr(item, g.name)) for g in dataclasses.fields(item)
                          if getattr(item, g.name) != g.default} for item in value]
            out[f.name] = plain(value)
        return out


@dataclass(frozen=True)
class Crack(Section):
    """An initial crack; the initial phase field is exp(-dist/epsilon).

    2D: a polyline ``[[x, y], ...]`` (at least two points, from the mouth to the tip).
    3D: a planar polygon ``[[x, y, z], ...]`` (at least three corners, in order around it);
    the crack is the filled polygon and dist the distance to it.
    """

    SECTION: ClassVar[str] = "cracks"
    PLANAR_TOL: ClassVar[float] = 1e-9
    points: tuple[tuple[float, ...], ...] = REQUIRED  # type: ignore[assignment]

    def validate(self) -> None:
        s = self.SECTION
        require(len(self.points) >= 2, s, "points", self.points,
                "a crack needs at least two points [[x0, y0], [x1, y1], ...]")
        dim = len(self.points[0])
        for point in self.points:
            require(len(point) in (2, 3) and len(point) == dim, s, "points", list(point),
                    "each point is [x, y] (2D) or [x, y, z] (3D), all of the same length")
        if dim == 3:
            require(len(self.points) >= 3, s, "points", [list(p) for p in self.points],
                    "a 3D crack is a planar polygon with at least three corners [[x, y, z], ...]")
            corners = np.asarray(self.points, dtype=float)
            normal = self.normal
            size = float(np.ptp(corners, axis=0).max())
            require(float(np.linalg.norm(normal)) > 0, s, "points",
                    [list(p) for p in self.points],
                    "the polygon has no area; give corners that span a plane")
            offsets = np.abs((corners - corners[0]) @ normal)
            require(offsets.max() <= self.PLANAR_TOL * size, s, "points",
                    [list(p) for p in self.points],
                    f"a 3D crack must be planar (a corner is {offsets.max():.3g} off the plane "
                    "of the others)")

    @property
    def dim(self) -> int:
        return len(self.points[0])

    @property
    def normal(self) -> np.ndarray:
        """Unit normal of a 3D polygon (Newell's method); zeros if it has no area."""
        corners = np.asarray(self.points, dtype=float)
        nxt = np.roll(corners, -1, axis=0)
        normal = 0.5 * np.cross(corners, nxt).sum(axis=0)
        length = float(np.linalg.norm(normal))
        scale = float(np.ptp(corners, axis=0).max()) ** 2
        return normal / length if length > 1e-12 * scale else np.zeros(3)


def occ_domain_of(geometry: "Geometry") -> "Domain":
    """The :class:`~ngfrac.geometry.cad.OccDomain` of a ``geometry.kind = "occ"`` section: its
    shapes or file, with the boundaries named by its selectors.

    Raises
    ------
    SceneError
        A selector matches nothing, two names claim one part, the file is missing or cannot
        be read, or the shapes (the file) leave no face or solid or several separate pieces.
    """
    from ..geometry.cad import (BoundaryConflict, EmptyShape, UnreadableFile, connected_pieces,
                      name_boundaries, read_shape, shape_from_specs, split_edges)

    try:
        shape = (read_shape(geometry.file, geometry.scale) if geometry.file
                 else shape_from_specs(geometry.shapes))
    except (FileNotFoundError, UnreadableFile) as err:
        raise SceneError(f"geometry.file = {geometry.file!r}: {err}") from None
    except EmptyShape as err:
        prefix = f"geometry.file = {geometry.file!r}: " if geometry.file else "geometry."
        raise SceneError(f"{prefix}{err}") from None
    except Exception as err:  # OCC raises plain Exceptions for bad shapes or files
        what = f"file = {geometry.file!r}" if geometry.file else "shapes"
        text = " ".join(str(err).split())  # one line: OCC's messages span several
        raise SceneError(f"geometry.{what}: OCC could not build the shape ({text})") from None
    pieces = connected_pieces(shape)
    if pieces > 1:  # each piece would need its own supports: a singular u-problem otherwise
        source = f"geometry.file = {geometry.file!r} holds" if geometry.file else "geometry.shapes make"
        raise SceneError(f"{source} {pieces} separate pieces (a cut through the domain, or a "
                         "shape that touches no other); ngfrac meshes one connected part: "
                         "join or remove the pieces")
    try:
        if geometry.split_points:
            shape = split_edges(shape, geometry.split_points)
        return name_boundaries(shape, geometry.boundaries, geometry.default_boundary)
    except BoundaryConflict as err:
        raise SceneError(str(err)) from None
