"""Initial cracks: distance to polylines, the optimal profile exp(-d/epsilon), the tip."""
from __future__ import annotations

from typing import Sequence

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


def optimal_profile(distance: np.ndarray, epsilon: float) -> np.ndarray:
    """z = exp(-d/epsilon): the 1D minimizer of the surface energy with z = 1 on the crack."""
    return np.exp(-np.asarray(distance) / epsilon)


def crack_tip(points: np.ndarray, z_values: np.ndarray,
              polylines: Sequence[Sequence[Sequence[float]]], band: float,
              threshold: float = 0.5) -> np.ndarray:
    """The crack tip: the point of {z >= threshold} farthest from the initial crack set.

    Points within ``band`` of the initial cracks belong to the initial crack's own band, so
    while nothing lies beyond it the tip is the last point of the first polyline (write crack
    points from the mouth to the tip). Returns NaNs when nothing is cracked at all.

    Parameters
    ----------
    points, z_values : node coordinates (n, d) and node values of z
    polylines : the initial cracks
    band : float
        Half width of the initial band, e.g. ``epsilon*ln(1/threshold) + h``.
    """
    cracked = np.asarray(z_values) >= threshold
    if not polylines:
        if not np.any(cracked):
            return np.full(points.shape[1], np.nan)
        candidates = points[cracked]
        return candidates[int(np.argmax(np.linalg.norm(candidates - candidates[0], axis=1)))]
    initial_tip = np.asarray(polylines[0][-1], dtype=float)
    if not np.any(cracked):
        return initial_tip
    candidates = points[cracked]
    distance = distance_to_polylines(candidates, polylines)
    farthest = int(np.argmax(distance))
    return candidates[farthest] if distance[farthest] > band else initial_tip
