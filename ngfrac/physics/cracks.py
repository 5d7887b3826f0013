"""Initial cracks: distance to polylines (2D) or filled planar polygons (3D), the optimal
profile exp(-d/epsilon), the initial tip; the direction of a crack at its tip. The crack set
of a z field and its tip are in :mod:`ngfrac.post.crackset`."""
from __future__ import annotations

from typing import Callable, Sequence

import numpy as np


def distance_to_polylines(points: np.ndarray, polylines: Sequence[Sequence[Sequence[float]]]) -> np.ndarray:
    """Euclidean distance from each point to the union of the polylines.

    Parameters
    ----------
    points : (n, d) array
    polylines : list of lists of points
        Each polyline has at least two points.
    """
    points = np.asarray(points, dtype=float)
    best = np.full(len(points), np.inf)
    for line in polylines:
        line = np.asarray(line, dtype=float)
        for a, b in zip(line[:-1], line[1:]):
            ab = b - a
            length2 = float(ab @ ab)
            if length2 == 0.0:
                s = np.zeros(len(points))
            else:
                s = np.clip((points - a) @ ab / length2, 0.0, 1.0)
            d = np.linalg.norm(points - a - s[:, None] * ab, axis=1)
            np.minimum(best, d, out=best)
    return best


def distance_to_polygons(points: np.ndarray, polygons: Sequence[Sequence[Sequence[float]]]) -> np.ndarray:
    """Euclidean distance from each 3D point to the union of filled planar polygons.

    For a point whose projection onto a polygon's plane falls inside the polygon the distance
    is the offset from the plane; otherwise it is the distance to the polygon's boundary
    (the closed polyline of its corners).

    Parameters
    ----------
    points : (n, 3) array
    polygons : list of lists of 3D points
        Each polygon has at least three corners, in order around it, and is planar.
    """
    points = np.asarray(points, dtype=float)
    best = np.full(len(points), np.inf)
    for polygon in polygons:
        corners = np.asarray(polygon, dtype=float)
        normal = 0.5 * np.cross(corners, np.roll(corners, -1, axis=0)).sum(axis=0)
        normal /= np.linalg.norm(normal)
        # an orthonormal frame (e1, e2) of the plane, for the point-in-polygon test
        e1 = corners[1] - corners[0]
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(normal, e1)
        offset = (points - corners[0]) @ normal
        inside = _inside_polygon(np.column_stack([(points - corners[0]) @ e1, (points - corners[0]) @ e2]),
                                 np.column_stack([(corners - corners[0]) @ e1, (corners - corners[0]) @ e2]))
        edge = distance_to_polylines(points, [np.vstack([corners, corners[:1]])])
        np.minimum(best, np.where(inside, np.abs(offset), edge), out=best)
    return best


def _inside_polygon(points: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Even-odd rule for (n, 2) points in a simple polygon with (m, 2) corners."""
    inside = np.zeros(len(points), dtype=bool)
    x, y = points[:, 0], points[:, 1]
    for (xa, ya), (xb, yb) in zip(corners, np.roll(corners, -1, axis=0)):
        crosses = (ya > y) != (yb > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_cross = xa + (y - ya) * (xb - xa) / (yb - ya)
        inside ^= crosses & (x < x_cross)
    return inside


def distance_to_cracks(points: np.ndarray, cracks: Sequence[Sequence[Sequence[float]]]) -> np.ndarray:
    """Distance to the initial cracks: polylines for 2D points, filled polygons for 3D points."""
    points = np.asarray(points, dtype=float)
    if points.shape[1] == 3:
        return distance_to_polygons(points, cracks)
    return distance_to_polylines(points, cracks)


def initial_tip(crack: Sequence[Sequence[float]],
                on_boundary: Callable[[np.ndarray], bool] | None = None) -> np.ndarray:
    """Where the tip of an initial crack is before it grows.

    2D: the last point of the polyline (written from the mouth to the tip). 3D: the middle
    of the crack front, i.e. the mean of the midpoints of the polygon's edges that do not lie
    on the domain boundary, weighted by length; all edges if none is on the boundary (an
    interior crack: its centre).

    Parameters
    ----------
    crack : polyline (2D) or planar polygon (3D)
    on_boundary : callable, optional
        Whether a point lies on the domain boundary, e.g.
        :meth:`ngfrac.geometry.domains.Domain.on_boundary`; asked at each edge's midpoint (3D).

    Returns
    -------
    (d,) array
    """
    corners = np.asarray(crack, dtype=float)
    if corners.shape[1] == 2:
        return corners[-1]
    ends = np.roll(corners, -1, axis=0)
    middles = 0.5 * (corners + ends)
    lengths = np.linalg.norm(ends - corners, axis=1)
    front = np.array([not (on_boundary and on_boundary(m)) for m in middles])
    if not front.any():
        front[:] = True
    return (middles[front] * lengths[front, None]).sum(axis=0) / lengths[front].sum()


def optimal_profile(distance: np.ndarray, epsilon: float) -> np.ndarray:
    """z = exp(-d/epsilon): the 1D minimizer of the surface energy with z = 1 on the crack."""
    return np.exp(-np.asarray(distance) / epsilon)


def crack_direction(points: np.ndarray, z_values: np.ndarray, tip: np.ndarray, radius: float,
                    threshold: float = 0.5) -> np.ndarray | None:
    """The direction in which a crack runs at its tip, or None when it cannot be told.

    The unit vector from the centroid of the cracked nodes (``z >= threshold``) within
    ``radius`` of ``tip`` to the tip: behind a tip the crack fills the disc's back half, so
    the centroid lies about radius/2 behind it. None if the tip is not finite or the centroid
    is closer to the tip than radius/10 (no crack behind the tip, e.g. an isolated spot).

    Parameters
    ----------
    points, z_values : numpy.ndarray
        Node coordinates (n, d) and the node values of z.
    tip : (d,) array
    radius : float
        How far behind the tip to look (a few epsilon).
    """
    tip = np.asarray(tip, dtype=float)[: points.shape[1]]
    if not np.all(np.isfinite(tip)):
        return None
    near = (np.asarray(z_values) >= threshold) & (np.linalg.norm(points - tip, axis=1) <= radius)
    if not np.any(near):
        return None
    offset = tip - points[near].mean(axis=0)
    length = float(np.linalg.norm(offset))
    return offset / length if length > radius / 10 else None
