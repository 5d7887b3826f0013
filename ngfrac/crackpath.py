"""Where a crack went: its path beyond the initial crack, the kink angle, and what LEFM predicts.

Two sources of a path:

- the phase field itself (:func:`ridge_path`): on arcs of growing radius around the initial
  tip, the point where z is largest (the ridge of z) marks where the crack crossed the arc;
- the tip history (:func:`history_path`): the ``tip_x, tip_y`` columns of ``history.csv``.

The kink angle is the direction of a least-squares line through the initial tip fitted to the
path points between two radii (a few epsilon beyond the tip, outside the initial band),
measured from the direction of the initial crack's last segment, counter-clockwise positive.

The prediction (:func:`mts_kink_angle`): for stress intensity factors K_I > 0, K_II, the
maximum-hoop-stress criterion (Erdogan-Sih) kinks by theta with
``K_I sin(theta) + K_II (3 cos(theta) - 1) = 0``, i.e.
``theta = 2 atan((K_I - sqrt(K_I^2 + 8 K_II^2)) / (4 K_II))``; to first order in the kink
this is also the angle at which the kinked crack has K_II = 0 (Cotterell-Rice), so both
criteria are "annihilate mode II at the tip".
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

__all__ = ["CrackPath", "initial_tip", "ridge_path", "history_path", "fit_direction",
           "kink_angle", "mts_kink_angle", "measure_kink", "deviation_from_line"]


@dataclass(frozen=True)
class CrackPath:
    """Points of a crack path beyond an initial tip, ordered by distance from it.

    ``origin`` is the initial tip, ``reference`` the unit direction of the initial crack at
    its tip (from the mouth to the tip); ``points`` is an (n, 2) array.
    """

    origin: np.ndarray
    reference: np.ndarray
    points: np.ndarray

    @property
    def distances(self) -> np.ndarray:
        """Distance of each point from the initial tip."""
        return np.linalg.norm(self.points - self.origin, axis=1)

    def between(self, rmin: float, rmax: float) -> "CrackPath":
        """The part of the path with rmin <= distance <= rmax."""
        d = self.distances
        keep = (d >= rmin) & (d <= rmax)
        return CrackPath(self.origin, self.reference, self.points[keep])

    def angles(self) -> np.ndarray:
        """Direction of each point as seen from the tip, relative to ``reference`` (degrees)."""
        return _relative_degrees(self.points - self.origin, self.reference)

    def text(self, every: int = 1) -> str:
        """The path as a small table (r, x, y, angle), for messages and printing."""
        rows = [f"{'r':>7} {'x':>7} {'y':>7} {'angle':>7}"]
        for r, (x, y), a in list(zip(self.distances, self.points, self.angles()))[::every]:
            rows.append(f"{r:7.3f} {x:7.3f} {y:7.3f} {a:7.1f}")
        return "\n".join(rows)


def initial_tip(polyline: Sequence[Sequence[float]]) -> tuple[np.ndarray, np.ndarray]:
    """The tip of an initial crack polyline (written mouth to tip) and its unit direction."""
    points = np.asarray(polyline, dtype=float)
    direction = points[-1] - points[-2]
    return points[-1], direction / np.linalg.norm(direction)


def _relative_degrees(vectors: np.ndarray, reference: np.ndarray) -> np.ndarray:
    vectors = np.atleast_2d(vectors)
    cross = reference[0] * vectors[:, 1] - reference[1] * vectors[:, 0]
    dot = vectors @ reference
    return np.degrees(np.arctan2(cross, dot))


def ridge_path(mesh, z, origin: Sequence[float], reference: Sequence[float],
               radii: Sequence[float], level: float = 0.5, half_opening: float = 150.0,
               n_angles: int = 721) -> CrackPath:
    """The ridge of z on arcs around the initial tip.

    For each radius r the arc ``origin + r (cos phi, sin phi)``, phi within ``half_opening``
    degrees of ``reference`` (the initial crack behind the tip is left out), is sampled at
    ``n_angles`` points; where z is largest on it (refined by a parabola through the three
    best samples) is the path point, kept when that largest z is at least ``level``. Points
    outside the mesh are skipped.

    Parameters
    ----------
    mesh, z : ngsolve.Mesh and the phase field (a GridFunction or CoefficientFunction)
    origin, reference : the initial tip and the unit direction of the initial crack there
    radii : increasing radii of the arcs (start beyond the initial band, ~2 epsilon)
    level : smallest ridge value that counts as cracked
    """
    origin = np.asarray(origin, dtype=float)
    reference = np.asarray(reference, dtype=float) / np.linalg.norm(reference)
    base = math.atan2(reference[1], reference[0])
    phis = base + np.radians(np.linspace(-half_opening, half_opening, n_angles))
    step = phis[1] - phis[0]
    found = []
    for r in radii:
        xs, ys = origin[0] + r * np.cos(phis), origin[1] + r * np.sin(phis)
        located = mesh(xs, ys)
        inside = located["nr"] >= 0
        if not np.any(inside):
            continue
        values = np.full(len(phis), -np.inf)
        values[inside] = np.asarray(z(located[inside])).ravel()
        best = int(np.argmax(values))
        if values[best] < level:
            continue
        phi = phis[best]
        if 0 < best < len(phis) - 1 and np.all(np.isfinite(values[best - 1:best + 2])):
            left, mid, right = values[best - 1:best + 2]
            curvature = left - 2 * mid + right
            if curvature < 0:
                phi += 0.5 * step * (left - right) / curvature
        found.append((origin[0] + r * math.cos(phi), origin[1] + r * math.sin(phi)))
    return CrackPath(origin, reference, np.array(found, dtype=float).reshape(-1, 2))


def history_path(history: Mapping[str, np.ndarray], origin: Sequence[float],
                 reference: Sequence[float]) -> CrackPath:
    """The tip positions of a history (``tip_x``, ``tip_y``) as a path, in order of distance
    from the initial tip; rows without a tip and repeated positions are dropped."""
    origin = np.asarray(origin, dtype=float)
    points = np.column_stack([history["tip_x"], history["tip_y"]])
    points = points[np.all(np.isfinite(points), axis=1)]
    moved = np.linalg.norm(points - origin, axis=1) > 0
    points = np.unique(points[moved], axis=0)
    order = np.argsort(np.linalg.norm(points - origin, axis=1))
    reference = np.asarray(reference, dtype=float)
    return CrackPath(origin, reference / np.linalg.norm(reference), points[order])


def fit_direction(path: CrackPath) -> np.ndarray:
    """Unit direction of the least-squares line through ``path.origin`` fitted to the points
    (the principal axis of their offsets), pointing away from the origin."""
    offsets = path.points - path.origin
    if len(offsets) == 0:
        raise ValueError("the path has no points in the range asked for: the crack did not "
                         "grow that far (run longer or lower the radii)")
    _, _, vt = np.linalg.svd(offsets, full_matrices=False)
    direction = vt[0]
    return direction if np.sum(offsets @ direction) >= 0 else -direction


def kink_angle(path: CrackPath, rmin: float, rmax: float) -> float:
    """The kink angle in degrees: the fitted direction of the path between ``rmin`` and
    ``rmax`` from the initial tip, relative to the initial crack (counter-clockwise > 0)."""
    direction = fit_direction(path.between(rmin, rmax))
    return float(_relative_degrees(direction, path.reference)[0])


def mts_kink_angle(k1: float, k2: float) -> float:
    """The maximum-hoop-stress kink angle in degrees for K_I = k1 >= 0 and K_II = k2.

    ``theta = 2 atan((k1 - sqrt(k1^2 + 8 k2^2)) / (4 k2))``: 0 in pure mode I, -70.5 degrees
    in pure mode II with k2 > 0 (the kink turns away from the direction the upper face slides).
    """
    if k1 < 0:
        raise ValueError(f"k1 = {k1} < 0: a closed crack has no hoop-stress kink angle")
    if k2 == 0:
        return 0.0
    return math.degrees(2 * math.atan((k1 - math.sqrt(k1 * k1 + 8 * k2 * k2)) / (4 * k2)))


def measure_kink(stepper, rmin: float, rmax: float, n_radii: int = 25,
                 level: float = 0.5) -> tuple[float, CrackPath]:
    """The kink angle of a stepper's current crack from the ridge of z.

    Uses the first initial crack of the scene; arcs at ``n_radii`` radii from ``rmin`` to
    ``rmax``. Returns the angle in degrees and the ridge path.
    """
    origin, reference = initial_tip(stepper.scene.cracks[0].points)
    path = ridge_path(stepper.mesh, stepper.z, origin, reference,
                      np.linspace(rmin, rmax, n_radii), level=level)
    return kink_angle(path, rmin, rmax), path


def deviation_from_line(path: CrackPath, angle: float) -> np.ndarray:
    """Distance of each path point from the ray through the initial tip at ``angle`` degrees
    relative to the initial crack (signed, counter-clockwise side > 0)."""
    ref = path.reference
    a = math.radians(angle) + math.atan2(ref[1], ref[0])
    direction = np.array([math.cos(a), math.sin(a)])
    offsets = path.points - path.origin
    return direction[0] * offsets[:, 1] - direction[1] * offsets[:, 0]
