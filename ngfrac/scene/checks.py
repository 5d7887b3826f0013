"""Scene checks beyond the ranges of single keys: crack geometry, finite expressions.

:class:`ngfrac.scene.Scene` refuses a scene whose cracks Netgen cannot mesh (a repeated point
made it segfault) or whose expressions are not finite. What a valid scene cannot resolve is
:func:`ngfrac.mesh.resolution.resolution_warnings`.

The geometry functions take plain coordinates and return a one-line problem (or None), so
they know nothing of the scene classes that call them.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Iterator, Mapping, Sequence

import numpy as np

if TYPE_CHECKING:
    from ..geometry.domains import Domain
    from .expressions import Expression
    from .geometry_section import Geometry
    from .sections import Scene

__all__ = ["crack_problems", "nonfinite_value", "check_times"]

SAME_POINT = 1e-9
"""Points closer than this times the domain's diameter are the same point."""

def _text(point: np.ndarray) -> str:
    return "(" + ", ".join(f"{c:.6g}" for c in point) + ")"


def _segment_distance(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray
                      ) -> tuple[float, np.ndarray]:
    """Distance between 2D segments ab and cd, and a point where they come that close."""
    def cross(u: np.ndarray, v: np.ndarray) -> float:
        return float(u[0] * v[1] - u[1] * v[0])

    d1, d2 = cross(b - a, c - a), cross(b - a, d - a)
    d3, d4 = cross(d - c, a - c), cross(d - c, b - c)
    if d1 * d2 < 0 and d3 * d4 < 0:  # a proper crossing
        s = d3 / (d3 - d4)
        return 0.0, a + s * (b - a)
    candidates = [(_point_segment(a, c, d), a), (_point_segment(b, c, d), b),
                  (_point_segment(c, a, b), c), (_point_segment(d, a, b), d)]
    return min(candidates, key=lambda item: item[0])


def _point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    length2 = float(ab @ ab)
    s = 0.0 if length2 == 0 else min(1.0, max(0.0, float((p - a) @ ab) / length2))
    return float(np.linalg.norm(p - a - s * ab))


def _repeated_point(points: np.ndarray, tol: float, word: str) -> str | None:
    for j in range(1, len(points)):
        gaps = np.linalg.norm(points[:j] - points[j], axis=1)
        k = int(np.argmin(gaps))
        if gaps[k] <= tol:
            what = "repeats" if gaps[k] == 0 else f"is {gaps[k]:.3g} from"
            fix = ("remove the repeated point (a zero-length segment)" if j == k + 1 else
                   "a crack may not visit a point twice")
            if word == "corner":
                fix = "list each corner once (the polygon closes itself)"
            return f"{word} {j} {what} {word} {k} {_text(points[k])}: {fix}"
    return None


def polyline_problem(points: Sequence[Sequence[float]], tol: float) -> str | None:
    """What makes a 2D crack polyline unmeshable, or None.

    Repeated points (a zero-length segment), a turn back onto the previous segment and
    non-adjacent segments that cross or touch are refused.
    """
    p = np.asarray(points, dtype=float)
    problem = _repeated_point(p, tol, "point")
    if problem:
        return problem
    for k in range(1, len(p) - 1):
        u, v = p[k] - p[k - 1], p[k + 1] - p[k]
        cross = abs(u[0] * v[1] - u[1] * v[0])
        if cross <= SAME_POINT * np.linalg.norm(u) * np.linalg.norm(v) and u @ v < 0:
            return (f"the polyline runs back on itself at point {k} {_text(p[k])} (segments "
                    f"{k - 1} and {k} overlap); end the crack there instead")
    for i in range(len(p) - 1):
        for j in range(i + 2, len(p) - 1):
            gap, where = _segment_distance(p[i], p[i + 1], p[j], p[j + 1])
            if gap <= tol:
                return (f"segments {i} and {j} of the polyline cross or touch near {_text(where)}; "
                        "a crack polyline may not intersect itself")
    return None


def polylines_touch(first: Sequence[Sequence[float]], second: Sequence[Sequence[float]],
                    tol: float) -> np.ndarray | None:
    """A point where two polylines cross or touch, or None."""
    a, b = np.asarray(first, dtype=float), np.asarray(second, dtype=float)
    for i in range(len(a) - 1):
        for j in range(len(b) - 1):
            gap, where = _segment_distance(a[i], a[i + 1], b[j], b[j + 1])
            if gap <= tol:
                return where
    return None


def boundary_segment(points: Sequence[Sequence[float]], sides: Mapping[str, tuple[int, float]],
                     tol: float) -> tuple[int, str] | None:
    """(segment index, side name) of the first crack segment (2D) or the side of a polygon
    (3D, index -1) that lies on a side ``name -> (axis, coordinate)`` of the domain."""
    p = np.asarray(points, dtype=float)
    for name, (axis, value) in sides.items():
        on = np.abs(p[:, axis] - value) <= tol
        if p.shape[1] == 3:
            if on.all():
                return -1, name
            continue
        for k in range(len(p) - 1):
            if on[k] and on[k + 1]:
                return k, name
    return None


def boundary_segment_of(points: Sequence[Sequence[float]], domain: "Domain",
                        tol: float) -> tuple[int, str] | None:
    """As :func:`boundary_segment` for any domain with ``boundary_names_at(point, tol)``: a
    segment (2D) or the polygon (3D) whose ends and middle (corners and centre) all lie on
    one named boundary part."""
    p = np.asarray(points, dtype=float)

    def common(probes: Sequence[np.ndarray]) -> str | None:
        names = set.intersection(*(domain.boundary_names_at(q, tol) for q in probes))
        return min(names) if names else None

    if p.shape[1] == 3:
        name = common([*p, p.mean(axis=0)])
        return (-1, name) if name else None
    for k in range(len(p) - 1):
        name = common([p[k], 0.5 * (p[k] + p[k + 1]), p[k + 1]])
        if name:
            return k, name
    return None


def segment_outside(points: Sequence[Sequence[float]], domain: "Domain", tol: float,
                    n: int = 0) -> np.ndarray | None:
    """A point of a crack's segments (2D) or polygon edges (3D) outside a domain that need
    not be convex (``n`` points per segment; 0: 32 in 2D, 8 in 3D), or None."""
    p = np.asarray(points, dtype=float)
    n = n or (32 if p.shape[1] == 2 else 8)
    ends = list(zip(p[:-1], p[1:])) + ([(p[-1], p[0])] if p.shape[1] == 3 else [])
    s = np.linspace(0.0, 1.0, n)[:, None]
    probes = np.concatenate([a + s * (b - a) for a, b in ends])
    inside = domain.contains(probes, tol=tol)
    return None if inside.all() else probes[int(np.argmin(inside))]


def _plane_coordinates(corners: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """2D coordinates of points in the plane through corners[0] with the given normal."""
    e1 = corners[1] - corners[0]
    e1 = e1 / np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    offset = corners - corners[0]
    return np.column_stack([offset @ e1, offset @ e2])


def polygon_problem(corners: Sequence[Sequence[float]], normal: np.ndarray, tol: float) -> str | None:
    """What makes a planar 3D crack polygon unmeshable, or None (planarity and area are
    checked by :class:`ngfrac.scene.Crack`): repeated corners, a corner where the outline
    turns back, and edges that cross or touch."""
    c = np.asarray(corners, dtype=float)
    problem = _repeated_point(c, tol, "corner")
    if problem:
        return problem
    flat = _plane_coordinates(c, normal)
    n = len(flat)
    for k in range(n):
        u, v = flat[k] - flat[k - 1], flat[(k + 1) % n] - flat[k]
        cross = abs(u[0] * v[1] - u[1] * v[0])
        if cross <= SAME_POINT * np.linalg.norm(u) * np.linalg.norm(v) and u @ v < 0:
            return (f"the outline turns back on itself at corner {k} {_text(c[k])}; "
                    "remove that corner")
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue  # adjacent through the closing edge
            gap, _ = _segment_distance(flat[i], flat[(i + 1) % n], flat[j], flat[(j + 1) % n])
            if gap <= tol:
                return (f"edges {i} and {j} of the polygon cross or touch; a crack polygon may "
                        "not intersect itself (order its corners around it)")
    return None


def polygons_touch(first: Sequence[Sequence[float]], first_normal: np.ndarray,
                   second: Sequence[Sequence[float]], second_normal: np.ndarray,
                   tol: float) -> np.ndarray | None:
    """A point common to two filled planar polygons (3D), or None.

    Two planar polygons meet iff an edge of one meets the other filled polygon: their common
    part lies on the line where the planes meet, and an end of it is on an edge of one.
    """
    a, b = np.asarray(first, dtype=float), np.asarray(second, dtype=float)
    for edges, normal_e, other, normal_o in ((a, first_normal, b, second_normal),
                                              (b, second_normal, a, first_normal)):
        for p, q in zip(edges, np.roll(edges, -1, axis=0)):
            where = _segment_meets_polygon(p, q, other, normal_o, tol)
            if where is not None:
                return where
    return None


def _segment_meets_polygon(p: np.ndarray, q: np.ndarray, corners: np.ndarray, normal: np.ndarray,
                           tol: float) -> np.ndarray | None:
    sp, sq = float((p - corners[0]) @ normal), float((q - corners[0]) @ normal)
    if abs(sp) <= tol and abs(sq) <= tol:  # in the plane: meets an edge, or lies inside
        flat = _plane_coordinates(np.vstack([corners, p, q]), normal)
        outline, fp, fq = flat[:-2], flat[-2], flat[-1]
        for k in range(len(outline)):
            gap, where = _segment_distance(fp, fq, outline[k], outline[(k + 1) % len(outline)])
            if gap <= tol:
                return p + (q - p) * _fraction(where, fp, fq)
        return p if _inside(fp, outline) else None
    if sp * sq > 0 and min(abs(sp), abs(sq)) > tol:
        return None
    point = p if abs(sp) <= tol else q if abs(sq) <= tol else p + (q - p) * (sp / (sp - sq))
    flat = _plane_coordinates(np.vstack([corners, point]), normal)
    outline, fpoint = flat[:-1], flat[-1]
    near_edge = min(_point_segment(fpoint, outline[k], outline[(k + 1) % len(outline)])
                    for k in range(len(outline)))
    return point if near_edge <= tol or _inside(fpoint, outline) else None


def _fraction(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    return min(1.0, max(0.0, float((point - a) @ ab) / float(ab @ ab)))


def _inside(point: np.ndarray, outline: np.ndarray) -> bool:
    """Even-odd rule for a point in a 2D polygon."""
    x, y = point
    inside = False
    for (x1, y1), (x2, y2) in zip(outline, np.roll(outline, -1, axis=0)):
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def crack_problems(geometry: "Geometry", cracks: Sequence[Sequence[Sequence[float]]],
                   normals: Sequence[np.ndarray] = ()) -> Iterator[str]:
    """One-line problems of the cracks in the domain (each names the crack by its index).

    Parameters
    ----------
    geometry : Geometry
        The domain (its dimension chooses polylines or polygons).
    cracks : list of polylines (2D) or planar polygons (3D)
        Points already checked to lie in the closed domain.
    normals : list of (3,) arrays
        3D: the unit normal of each polygon.
    """
    domain = geometry.domain()
    tol = SAME_POINT * domain.diameter
    sides = domain.sides() if hasattr(domain, "sides") else None  # axis-aligned: exact sides
    for i, crack in enumerate(cracks):
        problem = (polyline_problem(crack, tol) if geometry.dim == 2
                   else polygon_problem(crack, normals[i], tol))
        if problem:
            yield f"cracks[{i}]: {problem}"
            continue
        on_side = (boundary_segment(crack, sides, tol) if sides is not None
                   else boundary_segment_of(crack, domain, tol))
        outside = None if sides is not None else segment_outside(crack, domain, tol)
        if outside is not None:
            yield (f"cracks[{i}]: it leaves the domain near {_text(outside)} (a hole or notch "
                   "between its points); keep every segment inside the domain")
            continue
        if on_side:
            k, name = on_side
            what = f"segment {k}" if k >= 0 else "the polygon"
            yield (f"cracks[{i}]: {what} lies on the boundary {name!r}, where a crack changes "
                   "nothing (the boundary is traction free already); move it inside the domain")
    for i in range(len(cracks)):
        for j in range(i + 1, len(cracks)):
            where = (polylines_touch(cracks[i], cracks[j], tol) if geometry.dim == 2 else
                     polygons_touch(cracks[i], normals[i], cracks[j], normals[j], tol))
            if where is not None:
                yield (f"cracks[{i}] and cracks[{j}] cross or touch near {_text(where)}; join them "
                       "into one crack or keep them apart")


# -- expressions ---------------------------------------------------------------------------------

def check_times(t_end: float, n: int = 6) -> np.ndarray:
    """The times at which expressions are checked: n equal steps over [0, t_end]."""
    return np.linspace(0.0, t_end, n)


def nonfinite_value(expression: "Expression", coordinates: Sequence[np.ndarray],
                    times: np.ndarray | None = None) -> str | None:
    """``"nan at (x, y, t) = (...)"`` for the first sample point where ``expression`` is not
    finite, or None.

    Parameters
    ----------
    expression : Expression
    coordinates : (xs, ys) or (xs, ys, zs), 1D arrays of the sample points
    times : 1D array, optional
        Times to combine with every point (expressions in t).
    """
    names = list("xyz"[: len(coordinates)])
    columns = [np.asarray(c, dtype=float)[:, None] for c in coordinates]
    variables = dict(zip(names, columns))
    if times is not None:
        variables["t"] = np.asarray(times, dtype=float)[None, :]
        names.append("t")
    shape = (len(columns[0]), 1 if times is None else len(times))
    values = np.broadcast_to(expression.evaluate_numpy(variables), shape)
    bad = ~np.isfinite(values)
    if not bad.any():
        return None
    point, time = np.unravel_index(int(np.argmax(bad)), shape)
    where = [float(c[point, 0]) for c in columns] + ([float(times[time])] if times is not None else [])
    return (f"{values[point, time]} at ({', '.join(names)}) = "
            f"({', '.join(f'{w:.4g}' for w in where)})")


# -- resolution ----------------------------------------------------------------------------------
