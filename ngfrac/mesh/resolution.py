"""What a valid scene's mesh or epsilon cannot resolve: one line each (``ngfrac check`` and
``ngfrac run`` print them, ``--strict`` refuses them, :func:`ngfrac.run_scene` emits them as
:class:`ResolutionWarning`)."""
from __future__ import annotations

import math
from functools import partial

import numpy as np

from ..physics.cracks import distance_to_cracks, initial_tip
from ..scene import Scene
from ..scene.build import crack_model_of
from ..scene.checks import SAME_POINT
from .adapter import AdaptivitySizes
from .remesh import meshing_constants

__all__ = ["ResolutionWarning", "resolution_warnings", "estimated_vertices", "crack_measure"]

BAND_LEVEL = 0.1
CORE_LEVEL = 0.9
"""z levels of the crack band and core (as :mod:`ngfrac.mesh.adapter` refines them)."""


class ResolutionWarning(UserWarning):
    """The scene's mesh or epsilon cannot resolve the crack (see :func:`resolution_warnings`)."""


# -- crack geometry ------------------------------------------------------------------------------

def crack_measure(scene: "Scene", radius: float) -> float:
    """Measure of the points within ``radius`` of the initial cracks (Steiner's formula,
    without the caps of crack ends on the boundary; overlaps counted twice)."""
    geometry = scene.geometry.domain()
    on_boundary = partial(geometry.on_boundary, tol=SAME_POINT * geometry.diameter)
    total = 0.0
    for crack in scene.cracks:
        p = np.asarray(crack.points, dtype=float)
        if geometry.dim == 2:
            length = float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
            free_ends = sum(not on_boundary(q) for q in (p[0], p[-1]))
            total += 2 * radius * length + free_ends * math.pi * radius ** 2 / 2
        else:
            area = 0.5 * float(np.linalg.norm(np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)))
            edges = zip(p, np.roll(p, -1, axis=0))
            inner = sum(float(np.linalg.norm(b - a)) for a, b in edges
                        if not on_boundary(0.5 * (a + b)))
            total += 2 * radius * area + math.pi / 2 * inner * radius ** 2
    return min(total, geometry.measure)


def estimated_vertices(scene: "Scene") -> float:
    """Vertices an adaptive mesh needs for the sizes asked along the initial cracks.

    ``c * sum(measure / h^d)`` over the core (z0 >= 0.9) at h_crack, the band (z0 >= 0.1)
    at h_band, the tip disc (ball) outside the band at h_tip and the rest at hmax, with
    Netgen's vertex density c (:attr:`ngfrac.mesh.remesh.MeshingConstants.vertex_density`).
    Grading halos and the tip lane are left out, so a real mesh has more.
    """
    sizes = AdaptivitySizes.of(scene)
    domain = scene.geometry.domain()
    dim = domain.dim
    density = meshing_constants(dim).vertex_density

    eps = scene.phase_field.epsilon
    model = crack_model_of(scene)  # where its optimal profile falls to a level
    volume = domain.measure
    core = crack_measure(scene, model.half_width(eps, CORE_LEVEL))
    band = max(crack_measure(scene, model.half_width(eps, BAND_LEVEL)) - core, 0.0)
    tip = _tip_measure(scene, sizes.tip_margin, model.half_width(eps, BAND_LEVEL)) if scene.cracks else 0.0
    rest = max(volume - core - band - tip, 0.0)
    return density * (core / sizes.h_crack ** dim + band / sizes.h_band ** dim
                      + tip / sizes.h_tip ** dim + rest / sizes.hmax ** dim)


def _tip_measure(scene: "Scene", radius: float, band: float, n: int = 32) -> float:
    """Measure of the tip disc (ball) of the first crack inside the domain and outside its
    band, on an n^d grid over the disc's bounding box."""
    geometry = scene.geometry.domain()
    polygons = [c.points for c in scene.cracks]
    tip = initial_tip(polygons[0], partial(geometry.on_boundary, tol=SAME_POINT * geometry.diameter))
    axes = [tip[k] + radius * (np.arange(n) + 0.5) * 2 / n - radius for k in range(geometry.dim)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, geometry.dim)
    keep = (np.linalg.norm(grid - tip, axis=1) <= radius) & geometry.contains(grid)
    keep[keep] = distance_to_cracks(grid[keep], polygons) > band
    return float(keep.sum()) * (2 * radius / n) ** geometry.dim


def resolution_warnings(scene: "Scene") -> list[str]:
    """One line for each way the scene cannot resolve its crack; empty when it can.

    * the element size asked in the crack band (uniform: ``mesh_size``; adaptive: h_band,
      h_crack, h_tip as derived by :class:`ngfrac.mesh.adapter.AdaptivitySizes`) is above
      epsilon/2;
    * adaptive: ``max_vertices`` is below :func:`estimated_vertices`, so the cap coarsens the
      band below the sizes asked;
    * epsilon is above a tenth of the smallest extent of the domain.
    """
    eps = scene.phase_field.epsilon
    half = eps / 2
    found = []
    if not scene.adaptivity.enabled:
        if scene.mesh_size > half * (1 + 1e-12):
            found.append(f"geometry.mesh_size = {scene.mesh_size:g} is above epsilon/2 = {half:g}: "
                         "the uniform mesh cannot resolve the crack band; use mesh_size <= "
                         f"{half:g} (or 0)")
    else:
        sizes = AdaptivitySizes.of(scene)
        for name in ("h_crack", "h_band", "h_tip"):
            value = getattr(sizes, name)
            if value > half * (1 + 1e-12):
                given = getattr(scene.adaptivity, name)
                source = "" if given else " (derived, at least adaptivity.hmin)"
                found.append(f"adaptivity.{name} = {value:g}{source} is above epsilon/2 = {half:g}: "
                             f"the crack band is not resolved; lower it (and hmin) to <= {half:g}")
        needed = estimated_vertices(scene)
        cap = scene.adaptivity.max_vertices
        if needed > cap:
            found.append(f"adaptivity.max_vertices = {cap} is below the ~{needed:,.0f} vertices that "
                         f"h_crack = {sizes.h_crack:g}, h_band = {sizes.h_band:g} and h_tip = "
                         f"{sizes.h_tip:g} need along the initial cracks: the cap will coarsen the "
                         "crack band; raise max_vertices (or epsilon)")
    smallest = scene.geometry.domain().shortest_side
    if eps > smallest / 10 * (1 + 1e-12):
        found.append(f"phase_field.epsilon = {eps:g} is above a tenth of the smallest extent of the "
                     f"domain ({smallest:g}): the crack band (about {4.6 * eps:.3g} wide) fills much "
                     "of it; lower epsilon")
    return found
