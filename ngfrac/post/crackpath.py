"""Where a crack went: its path beyond the initial crack, the kink angle, and what LEFM predicts.

Two sources of a path:

- the phase field itself (:func:`ridge_path`): on arcs of growing radius around the initial
  tip, the point where z is largest (the ridge of z) marks where the crack crossed the arc;
- the tip history (:func:`history_path`): the ``tip_x, tip_y`` columns of ``history.csv``.

The kink angle is the direction of a least-squares line through the initial tip fitted to the
path points between two radii (a few epsilon beyond the tip, outside the initial band),
measured from the direction of the initial crack's last segment, counter-clockwise positive.

A reference LEFM solution (:func:`sharp_crack_solution`) cuts the first initial crack of a scene
(or a given one) open (a slit from the left edge) and solves linear elasticity on a mesh
graded at its tip;
its K_I, K_II come from the crack-face displacement jump (:func:`stress_intensity_from_jump`),
and :func:`griffith_onset` turns G into the load at which a sharp crack starts to grow.

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
from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

if TYPE_CHECKING:
    import ngsolve as ngs

    from ..scene import Scene

__all__ = ["CrackPath", "tip_and_direction", "ridge_path", "connected_part", "final_ridge",
           "crack_path_rows", "history_path", "fit_direction",
           "kink_angle", "stress_intensity_from_jump", "mts_kink_angle", "measure_kink",
           "deviation_from_line", "slit_mesh", "SharpCrack", "sharp_crack_solution",
           "griffith_onset"]


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


def tip_and_direction(polyline: Sequence[Sequence[float]]) -> tuple[np.ndarray, np.ndarray]:
    """The tip of a 2D crack polyline and the unit direction of its last segment.

    Parameters
    ----------
    polyline : sequence of (x, y)
        An initial crack, written from the mouth to the tip.

    Returns
    -------
    tip, direction : numpy.ndarray
        The last point (as :func:`ngfrac.physics.cracks.initial_tip` in 2D) and the unit
        vector from the last but one point to it: the ``origin`` and ``reference`` of a
        :class:`CrackPath`.
    """
    points = np.asarray(polyline, dtype=float)
    direction = points[-1] - points[-2]
    return points[-1], direction / np.linalg.norm(direction)


def _relative_degrees(vectors: np.ndarray, reference: np.ndarray) -> np.ndarray:
    vectors = np.atleast_2d(vectors)
    cross = reference[0] * vectors[:, 1] - reference[1] * vectors[:, 0]
    dot = vectors @ reference
    return np.degrees(np.arctan2(cross, dot))


def ridge_path(mesh: ngs.Mesh, z: Any, origin: Sequence[float], reference: Sequence[float],
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
    radii : increasing radii of the arcs (from about epsilon, where the initial band ends)
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


def connected_part(path: CrackPath, max_jump: float) -> CrackPath:
    """The path from its first point up to the first jump longer than ``max_jump`` (points
    farther on belong to damage elsewhere, not to the crack that grew from the tip)."""
    points = path.points
    if len(points) == 0:
        return path
    gaps = np.linalg.norm(np.diff(np.vstack([path.origin, points]), axis=0), axis=1)
    jumps = np.flatnonzero(gaps > max_jump)
    end = int(jumps[0]) if len(jumps) else len(points)
    return CrackPath(path.origin, path.reference, points[:end])


def final_ridge(scene: Scene, mesh: ngs.Mesh, z: Any, level: float = 0.5) -> CrackPath | None:
    """The ridge of z beyond the first initial crack's tip, as one connected polyline (2D).

    Arcs every epsilon/2 from 2 epsilon (inside that the initial band's flanks reach
    z = 1/2 on the arcs) to the farthest corner of the domain (:func:`ridge_path`), cut at the
    first jump longer than 2 epsilon + the arc spacing (:func:`connected_part`). None for 3D
    scenes and scenes without an initial crack.

    See Also
    --------
    ngfrac.post.crackset.CrackSet : its ``path`` is the grown crack read from the node graph
        (the ridge test), which gives ``grown_length``; this arc ridge is what
        ``crack_path.csv`` holds. The two measure the same path in two ways.
    """
    if scene.geometry.dim != 2 or not scene.cracks:
        return None
    eps = scene.phase_field.epsilon
    origin, reference = tip_and_direction(scene.cracks[0].points)
    # the farthest point of the domain from the initial tip is a mesh vertex (a corner of a
    # rectangle, any shape's extreme point up to the mesh)
    vertices = np.array(mesh.ngmesh.Coordinates())[:, :2]
    reach = float(np.max(np.linalg.norm(vertices - origin, axis=1)))
    spacing = eps / 2
    radii = np.arange(2 * eps, reach, spacing)
    path = ridge_path(mesh, z, origin, reference, radii, level=level)
    return connected_part(path, 2 * eps + spacing)


def crack_path_rows(history: Mapping[str, np.ndarray], ridge: CrackPath | None, step: int,
                    t: float) -> tuple[list[str], list[list[object]]]:
    """The header and rows of ``crack_path.csv``: ``kind, step, t, x, y`` (3D: ``, z``).

    ``kind = tip``: one row per history row with a tip (its step, t and tip position);
    ``kind = ridge``: the points of ``ridge`` (the final ridge of z, :func:`final_ridge`), in
    order from the initial tip, all with the last ``step`` and ``t``.
    """
    axes = [c for c in ("tip_x", "tip_y", "tip_z") if c in history]
    header = ["kind", "step", "t"] + [c[-1] for c in axes]
    tips = np.column_stack([history[c] for c in axes])
    rows: list[list[object]] = []
    for k, time_, point in zip(history["step"], history["t"], tips):
        if np.all(np.isfinite(point)):
            rows.append(["tip", int(k), float(time_), *map(float, point)])
    if ridge is not None:
        for point in ridge.points:
            rows.append(["ridge", int(step), float(t), *map(float, point),
                         *([math.nan] * (len(axes) - 2))])
    return header, rows


def history_path(history: Mapping[str, np.ndarray], origin: Sequence[float],
                 reference: Sequence[float], max_jump: float = math.inf) -> CrackPath:
    """The tip positions of a history (``tip_x``, ``tip_y``) as a path.

    The history's tip is the cracked point farthest from the initial crack, so when damage
    elsewhere (a loaded corner, a weak spot) reaches z = 1/2 first it jumps there. The path
    keeps, in time order, only the tips within ``max_jump`` of the last kept one (starting at
    the initial tip), so such jumps are left out. Rows without a tip and positions at the
    initial tip are dropped; points are returned in order of distance from the initial tip.
    """
    origin = np.asarray(origin, dtype=float)
    points = np.column_stack([history["tip_x"], history["tip_y"]])
    points = points[np.all(np.isfinite(points), axis=1)]
    points = points[np.linalg.norm(points - origin, axis=1) > 0]
    kept, last = [], origin
    for point in points:
        if np.linalg.norm(point - last) <= max_jump:
            kept.append(point)
            last = point
    points = np.unique(np.array(kept).reshape(-1, 2), axis=0)
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


def stress_intensity_from_jump(distance: np.ndarray, jump: np.ndarray, mu: float, kappa: float,
                               degree: int = 2) -> tuple[float, float]:
    """K_I and K_II from the crack-face displacement jump behind a tip (LEFM, plane problems).

    Near the tip ``[u_n] = (kappa + 1)/mu K_I sqrt(r/(2 pi))`` and ``[u_t]`` the same with K_II
    (jump = upper face minus lower face, in the crack's normal n and tangent t); the apparent
    K(r) = mu/(kappa + 1) sqrt(2 pi/r) [u] is fitted by a polynomial in r and taken at r = 0.

    Parameters
    ----------
    distance : (m,) distances r behind the tip
    jump : (m, 2) jumps (tangential, normal) at those distances
    mu, kappa : shear modulus and Kolosov constant (plane strain: 3 - 4 nu)
    """
    r = np.asarray(distance, dtype=float)
    apparent = mu / (kappa + 1) * np.sqrt(2 * np.pi / r)[:, None] * np.asarray(jump, dtype=float)
    k2 = np.polyfit(r, apparent[:, 0], degree)[-1]
    k1 = np.polyfit(r, apparent[:, 1], degree)[-1]
    return float(k1), float(k2)


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


def _given_or_first_crack(scene: Scene, crack: Sequence[Sequence[float]] | None,
                          hint: str) -> Sequence[Sequence[float]]:
    """``crack``, or the points of the scene's first ``[[cracks]]``; without either a ValueError
    that asks for ``hint``."""
    if crack is not None:
        return crack
    if not scene.cracks:
        raise ValueError(f"the scene has no [[cracks]]: give {hint}")
    return scene.cracks[0].points


def measure_kink(stepper: Any, rmin: float, rmax: float, n_radii: int = 25,
                 level: float = 0.5, *,
                 crack: Sequence[Sequence[float]] | None = None) -> tuple[float, CrackPath]:
    """The kink angle of a stepper's current crack from the ridge of z.

    Measured from the tip of ``crack`` (the initial crack's points; default: the scene's first
    ``[[cracks]]``, give it for a notch cut out of the geometry); arcs at ``n_radii`` radii
    from ``rmin`` to ``rmax``. Returns the angle in degrees and the ridge path.
    """
    crack = _given_or_first_crack(stepper.scene, crack, "the initial crack as crack=...")
    origin, reference = tip_and_direction(crack)
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


def slit_mesh(box: Sequence[Sequence[float]], crack: Sequence[Sequence[float]],
              h_tip: float = 1e-3, opening: float = 1e-6) -> ngs.Mesh:
    """A mesh of the rectangle ``box`` = [[x0, y0], [x1, y1]] with a straight crack from its
    left edge cut open.

    The faces (boundary ``crack``) meet at the tip and are ``2 opening`` apart at the mouth, a
    wedge too thin to matter; elements are graded to ``h_tip`` at the tip (at most 0.3 times
    the distance to it). The sides keep their names bottom, right, top, left.
    """
    import ngsolve as ngs
    from netgen.geom2d import SplineGeometry

    (x0, y0), (x1, y1) = (tuple(float(c) for c in corner) for corner in box)
    mouth, tip = np.asarray(crack[0], dtype=float), np.asarray(crack[-1], dtype=float)
    if len(crack) != 2 or abs(mouth[0] - x0) > 1e-12 or not y0 < mouth[1] < y1:
        raise ValueError("slit_mesh handles one straight crack from the left edge")
    geo = SplineGeometry()
    outline = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, mouth[1] + opening), tuple(tip),
               (x0, mouth[1] - opening)]
    points = [geo.AppendPoint(*p) for p in outline]
    names = ["bottom", "right", "top", "left", "crack", "crack", "left"]
    coarse = min(x1 - x0, y1 - y0) / 20
    for i, name in enumerate(names):
        geo.Append(["line", points[i], points[(i + 1) % len(points)]], bc=name,
                   maxh=min(coarse, 0.01) if name == "crack" else coarse)
    mesh = ngs.Mesh(geo.GenerateMesh(maxh=coarse))
    for _ in range(60):
        coords = np.array(mesh.ngmesh.Coordinates())[:, :2]
        corners = coords[mesh.ngmesh.Elements2D().NumPy()["nodes"][:, :3].astype(int) - 1]
        size = np.max([np.linalg.norm(corners[:, i] - corners[:, j], axis=1)
                       for i, j in ((0, 1), (1, 2), (2, 0))], axis=0)
        distance = np.linalg.norm(corners.mean(axis=1) - tip, axis=1)
        marked = size > np.maximum(h_tip, 0.3 * distance)
        if not marked.any():
            break
        for element, flag in zip(mesh.Elements(ngs.VOL), marked):
            mesh.SetRefinementFlag(element, bool(flag))
        mesh.Refine()
    # two chains of n1 and n2 segments meeting at the tip have n1 + n2 + 1 vertices; Netgen
    # merges points of very thin wedges, which closes (part of) the slit
    faces = [el.vertices for el in mesh.Elements(ngs.BND) if el.mat == "crack"]
    if len({v.nr for vs in faces for v in vs}) != len(faces) + 1:
        raise ValueError(f"Netgen closed part of the slit with opening = {opening:g}")
    return mesh


@dataclass(frozen=True)
class SharpCrack:
    """LEFM solution of a scene with its first crack cut open, at one time t.

    ``K_I``, ``K_II`` from the crack-face jump; ``energy`` = 1/2 int sigma:e; ``reactions``
    maps ``F<c>_<boundary>`` to the force on each loaded boundary (the integral of the
    traction, from the residual as in :mod:`ngfrac.post.reactions`); ``G`` = (K_I^2 + K_II^2)/E'.
    """

    K_I: float
    K_II: float
    G: float
    energy: float
    reactions: dict

    @property
    def kink_deg(self) -> float:
        """The maximum-hoop-stress kink angle (degrees)."""
        return mts_kink_angle(self.K_I, self.K_II)


def _residual_forces(model: Any, fes: Any, loads: Sequence[Any], residual: Any,
                     free: np.ndarray) -> dict[str, float]:
    """``F<c>_<boundary>``: the residual tested with the indicator of each loaded boundary's
    fixed component (0 for a free component)."""
    import ngsolve as ngs

    mesh = fes.mesh
    reactions = {}
    for load in loads:
        for i, (c, is_free) in enumerate(zip(model.component_names, load.free)):
            if is_free:
                reactions[f"F{c}_{load.boundary}"] = 0.0
                continue
            w = ngs.GridFunction(fes)
            w.components[i].Set(1.0, ngs.BND, definedon=mesh.Boundaries(load.boundary))
            w.vec.FV().NumPy()[free] = 0.0
            reactions[f"F{c}_{load.boundary}"] = float(ngs.InnerProduct(residual, w.vec))
    return reactions


def sharp_crack_solution(scene: Scene, t: float = 1.0, order: int = 3, h_tip: float = 1e-3,
                         fit_range: tuple[float, float] = (0.005, 0.05), *,
                         crack: Sequence[Sequence[float]] | None = None,
                         box: Sequence[Sequence[float]] | None = None) -> SharpCrack:
    """Linear elasticity (no phase field) with the scene's loads at time ``t`` on
    :func:`slit_mesh`; plane strain or plane stress.

    The sharp crack is ``crack`` (two points, from the left edge), by default the scene's
    first ``[[cracks]]``; the rectangle is ``box`` = [[x0, y0], [x1, y1]], by default the
    scene's rectangle geometry. Give both for a scene whose notch is cut out of an ``occ``
    geometry. K_I, K_II come from :func:`stress_intensity_from_jump` with the jump between
    ``fit_range`` behind the tip. For loads linear in t, K and the forces scale with t and
    G and the energy with t^2.
    """
    import ngsolve as ngs

    from ..scene.build import elastic_model_of

    model = elastic_model_of(scene)
    if model.n_components != 2:
        raise ValueError("sharp_crack_solution is for the plane models")
    if not all(load.is_dirichlet for load in scene.loads) or scene.phase_field.pressurized:
        raise ValueError("sharp_crack_solution takes displacement loads only (no tractions, "
                         "pressures or crack pressure)")
    crack = _given_or_first_crack(scene, crack, "the sharp crack as crack=[[x, y], [x, y]] (and "
                                  "the rectangle as box=[[x0, y0], [x1, y1]])")
    if box is None:
        g = scene.geometry
        if g.kind != "rectangle":
            raise ValueError(f"geometry.kind = {g.kind!r} is not a rectangle: give the rectangle "
                             "as box=[[x0, y0], [x1, y1]]")
        box = (g.origin, (g.origin[0] + g.width, g.origin[1] + g.height))
    size = max(box[1][0] - box[0][0], box[1][1] - box[0][1])
    for opening in (1e-6 * size, 1e-5 * size, 1e-4 * size):  # Netgen fails on some thin wedges
        try:
            mesh = slit_mesh(box, crack, h_tip, opening)
            break
        except Exception as err:  # netgen raises plain Exceptions
            failure = err
    else:
        raise RuntimeError(f"Netgen could not mesh the slit ({failure})")
    fes = model.space(mesh, order, scene.loads)
    u, v = fes.TnT()
    a = ngs.BilinearForm(model.stress_strain(u, v) * ngs.dx, symmetric=True)
    gfu = ngs.GridFunction(fes)
    model.set_boundary(gfu, model.boundary_values(mesh, scene.loads, ngs.Parameter(t)))
    free = np.array(fes.FreeDofs(), dtype=bool)
    gfu.vec.FV().NumPy()[free] = 0.0
    with ngs.TaskManager():
        a.Assemble()
        residual = (-a.mat * gfu.vec).Evaluate()
        gfu.vec.data += a.mat.Inverse(fes.FreeDofs(), inverse="sparsecholesky") * residual
        residual.data = a.mat * gfu.vec
    reactions = _residual_forces(model, fes, scene.loads, residual, free)
    energy = 0.5 * ngs.Integrate(model.energy_density(gfu), mesh, order=2 * order)
    mouth, tip = np.asarray(crack[0], dtype=float), np.asarray(crack[-1], dtype=float)
    tangent = (tip - mouth) / np.linalg.norm(tip - mouth)
    normal = np.array([-tangent[1], tangent[0]])
    r = np.linspace(*fit_range, 30)
    # just outside the faces, which are opening * r / length off the crack line
    gap = (2 * opening * r / np.linalg.norm(tip - mouth) + 1e-9 * size)[:, None]

    def at(points):
        return np.array([gfu(mesh(*p)) for p in points])

    behind = tip - r[:, None] * tangent
    jump = at(behind + gap * normal) - at(behind - gap * normal)
    jump_local = np.column_stack([jump @ tangent, jump @ normal])
    mu, kappa = model.mu, model.kolosov
    k1, k2 = stress_intensity_from_jump(r, jump_local, mu, kappa)
    # E' = 8 mu / (kappa + 1): E/(1 - nu^2) in plane strain, E in plane stress
    G = (k1 * k1 + k2 * k2) * (kappa + 1) / (8 * mu)
    return SharpCrack(K_I=k1, K_II=k2, G=float(G), energy=float(energy), reactions=reactions)


def griffith_onset(scene: Scene, force: str, h_core: float | None = None, *,
                   crack: Sequence[Sequence[float]] | None = None,
                   box: Sequence[Sequence[float]] | None = None) -> dict[str, float]:
    """Where the scene's sharp crack starts to grow by Griffith: t_c with G(t_c) = gamma.

    For loads linear in t, ``G(t) = G1 t^2`` and the reaction ``F(t) = F1 t`` (G1, F1 from
    :func:`sharp_crack_solution` at t = 1, ``force`` a key of its reactions, e.g. "Fy_top").
    Also for ``gamma_eff = gamma (1 + h_core/(2 epsilon))``, the toughness of a band whose core
    is one element of size h_core wide (default: the adaptive core size max(hmin, epsilon/10),
    or the uniform mesh size). ``crack`` and ``box`` as for :func:`sharp_crack_solution`.
    Returns t_c, F_c, t_c_eff, F_c_eff, G1, F1, K_I, K_II, kink_deg.
    """
    sharp = sharp_crack_solution(scene, t=1.0, crack=crack, box=box)
    gamma = scene.material.gamma.value()
    eps = scene.phase_field.epsilon
    if h_core is None:
        a = scene.adaptivity
        h_core = max(a.hmin, a.h_crack or eps / 10) if a.enabled else scene.mesh_size
    gamma_eff = gamma * (1 + h_core / (2 * eps))
    f1 = sharp.reactions[force]
    t_c, t_eff = math.sqrt(gamma / sharp.G), math.sqrt(gamma_eff / sharp.G)
    return {"G1": sharp.G, "F1": f1, "K_I": sharp.K_I, "K_II": sharp.K_II,
            "kink_deg": sharp.kink_deg, "gamma_eff": gamma_eff, "t_c": t_c, "F_c": f1 * t_c,
            "t_c_eff": t_eff, "F_c_eff": f1 * t_eff}
