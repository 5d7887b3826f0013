"""3D meshes: the box as an OCC geometry with crack faces, uniform and adaptive tetrahedral meshes.

The box ``[x0, x0 + width] x [y0, y0 + height] x [z0, z0 + depth]`` is a ``netgen.occ.Box``
whose faces are named left (x = x0), right (x = x1), bottom (y = y0), top (y = y1), back
(z = z0) and front (z = z1). Each initial crack, a planar polygon, is glued into the solid as
an interior face named ``crack`` (``netgen.occ.Glue``), so the tetrahedra have faces on it,
as the triangles of a 2D mesh have edges on a slit (theory.md, "Crack-aligned meshes"). A
polygon with an edge on a box face splits that face; both parts keep the face's name.

Adaptive meshes are regenerated from a size field, as in 2D (:mod:`ngfrac.mesh.remesh`): the
sizes are sampled at points, each point restricts Netgen's local h
(``MeshingParameters.RestrictH``) and ``OCCGeometry.GenerateMesh(mp=...)`` meshes the glued
geometry from scratch. The 2D pipeline is dimension-generic except for three constants that
differ in 3D, measured here on the unit cube with a crack plane (``pytest -s
tests/ngfrac/test_3d_meshing.py -k calibrate`` prints them again):

* :data:`VERTEX_DENSITY_3D`: ``nv ~ c * int h^-3 dx`` over the graded requested field;
* :data:`SIZE_RATIO_3D`: sizes are sent to Netgen divided by it (Netgen realises graded
  fields coarser than asked, as in 2D);
* ``optsteps3d = 1`` (the default 3 costs about twice the time for a slightly better
  smallest dihedral angle).

Marked bisection (``SetRefinementFlag`` + ``Mesh.Refine``) also works on these meshes in
6.2.2608 and keeps the crack faces, but it cannot coarsen and made 4.6-6.2x the vertices of a
regenerated mesh for the same field (3,988 / 12,085 / 39,508 against 872 / 2,477 / 6,383 for
hmin = 0.04 / 0.02 / 0.01 around the demo's crack; docs/theory.md, "3D").

The vertex cap is a hard limit exactly as in 2D: a mesh with too many vertices is discarded,
the constant re-measured on it, and the mesh generated again. As in 2D the constant measured
on the last mesh of a run predicts the next one (:class:`ngfrac.mesh.remesh.VertexDensity`).
"""
from __future__ import annotations

import logging
import time
from typing import Any, Sequence

import numpy as np
import ngsolve as ngs
import netgen.meshing as ngm

from .domains import MeshingError
from .remesh import (NETGEN_GRADING, ElementGeometry, VertexDensity, _sample, cap_vertices,
                      element_grader, predict_vertices)
from ..scene import Geometry

log = logging.getLogger(__name__)

CRACK_FACE = "crack"
"""Name of the interior mesh faces that follow the initial cracks."""

VERTEX_DENSITY_3D = 4.3
"""c in ``nv ~ c * int h(x)^-3 dx`` for 3D Netgen meshes (h = graded requested size)."""

SIZE_RATIO_3D = 1.15
"""Netgen meshes graded 3D fields this much coarser than asked; sizes are divided by it."""

OPTIMIZE_STEPS_3D = 1
"""Netgen's ``optsteps3d`` for adaptive meshes."""

FACE_NAMES = {"left": (0, "min"), "right": (0, "max"), "bottom": (1, "min"),
              "top": (1, "max"), "back": (2, "min"), "front": (2, "max")}
"""Box face name -> (axis, which end)."""


def occ_geometry(geometry: Geometry, cracks: Sequence[Sequence[Sequence[float]]] = ()) -> Any:
    """The OCC geometry of a box with named faces and the crack polygons as interior faces.

    Parameters
    ----------
    geometry : Geometry
        A scene geometry of kind ``box``.
    cracks : list of planar polygons [[x, y, z], ...]
        Initial cracks; each becomes an interior face named ``crack``.

    Returns
    -------
    netgen.occ.OCCGeometry
    """
    from netgen import occ

    if geometry.dim != 3:
        raise ValueError(f"occ_geometry needs a box, got geometry.kind = {geometry.kind!r}")
    x0, y0, z0 = geometry.origin
    box = occ.Box(occ.Pnt(x0, y0, z0),
                  occ.Pnt(x0 + geometry.width, y0 + geometry.height, z0 + geometry.depth))
    axes = (occ.X, occ.Y, occ.Z)
    for name, (axis, end) in FACE_NAMES.items():
        faces = box.faces.Min(axes[axis]) if end == "min" else box.faces.Max(axes[axis])
        faces.name = name
    if not cracks:
        return occ.OCCGeometry(box)
    tol = 1e-10 * max(geometry.extent)
    for polygon in cracks:  # OCC segfaults on an edge from a point to itself
        corners = np.asarray(polygon, dtype=float)
        gaps = np.linalg.norm(corners - np.roll(corners, -1, axis=0), axis=1)
        if np.any(gaps <= tol):
            k = int(np.argmin(gaps))
            raise MeshingError(f"a crack polygon has a zero-length edge at corner {k} "
                               f"{corners[k].tolist()}; remove the repeated corner (ngfrac check "
                               "finds it)")
    faces = []
    try:
        for polygon in cracks:
            corners = [occ.Pnt(*map(float, p)) for p in polygon]
            wire = occ.Wire([occ.Segment(a, b) for a, b in zip(corners, corners[1:] + corners[:1])])
            face = occ.Face(wire)
            face.name = CRACK_FACE
            faces.append(face)
        return occ.OCCGeometry(occ.Glue([box, *faces]))
    except Exception as err:  # OCC raises plain Exceptions for degenerate wires and faces
        raise MeshingError(f"OCC could not glue the crack polygons into the box ({err}); run "
                           "ngfrac check on the scene") from None


def build_mesh_3d(geometry: Geometry, maxh: float,
                  cracks: Sequence[Sequence[Sequence[float]]] = ()) -> ngs.Mesh:
    """A quasi-uniform tetrahedral mesh of a box, with faces on the crack polygons."""
    try:
        ngmesh = occ_geometry(geometry, cracks).GenerateMesh(maxh=maxh)
    except MeshingError:
        raise
    except Exception as err:  # netgen raises plain Exceptions for bad geometries
        raise MeshingError(f"Netgen could not mesh the box with its cracks ({err}) at maxh = "
                           f"{maxh:g}; run ngfrac check on the scene, or change the crack "
                           "polygons or the mesh size") from None
    return ngs.Mesh(ngmesh)


def generate_3d(ngeo: Any, points: np.ndarray, sizes: np.ndarray, *, maxh: float,
                grading: float = NETGEN_GRADING, size_ratio: float = SIZE_RATIO_3D,
                optimize_steps: int = OPTIMIZE_STEPS_3D) -> ngm.Mesh:
    """One Netgen run: ``RestrictH(point, size / size_ratio)`` for every size below maxh."""
    mp = ngm.MeshingParameters(maxh=maxh, grading=grading, optsteps3d=optimize_steps)
    active = sizes < maxh
    for (x, y, z), h in zip(points[active].tolist(), (sizes[active] / size_ratio).tolist()):
        mp.RestrictH(x, y, z, h)
    try:
        return ngeo.GenerateMesh(mp=mp)
    except Exception as err:  # netgen raises plain Exceptions
        raise MeshingError(f"Netgen could not remesh the box ({err}) with maxh = {maxh:g} and "
                           f"sizes down to {float(sizes.min()):g}; raise adaptivity.hmin") from None


def adapt_mesh_3d(mesh: ngs.Mesh, ngeo: Any, sizes: np.ndarray, *, hmax: float,
                  max_vertices: int, grading: float = NETGEN_GRADING,
                  density: VertexDensity | None = None, max_attempts: int = 8) -> ngs.Mesh:
    """Grade, cap, sample and remesh in 3D: the new mesh for element sizes given on ``mesh``
    (the 3D twin of :func:`ngfrac.mesh.remesh.adapt_mesh`), with at most ``max_vertices`` vertices.

    The cap acts on the graded element field (:func:`ngfrac.mesh.remesh.cap_vertices` with
    :func:`ngfrac.mesh.remesh.element_grader`): Netgen grades in 3D too, and its grading halo
    holds most of the vertices of a fine crack band, so a prediction that ignores grading
    (coarsening the coarse part only) barely changes the real count. If Netgen still
    makes too many vertices, the constant is re-measured on that mesh, the margin tightened
    and the mesh generated again.

    Parameters
    ----------
    mesh : ngsolve.Mesh
        The current (3D) mesh, on which ``sizes`` lives (one per element).
    ngeo : netgen.occ.OCCGeometry
        The domain of the new mesh (:func:`occ_geometry`).
    sizes : (ne,) array
        Requested element sizes.
    hmax : float
        Size wherever nothing asks for less.
    max_vertices : int
        Hard upper bound of the vertex count.
    grading : float
        Netgen's grading.
    density : VertexDensity, optional
        The constant c learned from the previous meshes of the run (pass one instance to every
        call, as in 2D); until it has measured a 3D mesh, :data:`VERTEX_DENSITY_3D` is used.
    max_attempts : int
        Generations before giving up with a :class:`~ngfrac.mesh.domains.MeshingError`.
    """
    density = density if density is not None else VertexDensity()
    geom = ElementGeometry.of(mesh)
    if geom.dim != 3:
        raise ValueError(f"adapt_mesh_3d needs a 3D mesh, got dimension {geom.dim}")
    grade = element_grader(geom, grading)
    requested = np.minimum(np.asarray(sizes, dtype=float), hmax)
    c = density.value if density.measured else VERTEX_DENSITY_3D
    margin, nv = 0.95, 0
    for attempt in range(1, max_attempts + 1):
        capped = cap_vertices(requested, geom.measures, margin * max_vertices, hmax=hmax,
                              density=c, dim=3, grade=grade)
        field = _sample(geom, capped)
        started = time.perf_counter()
        ngmesh = generate_3d(ngeo, field.points, field.sizes,
                             maxh=max(hmax, float(capped.max())), grading=grading)
        nv = len(ngmesh.Points())
        integral = predict_vertices(capped, geom.measures, density=1.0, dim=3)
        log.info("remesh 3D attempt %d: %d vertices (cap %d, predicted %.0f) in %.2f s", attempt,
                 nv, max_vertices, c * integral, time.perf_counter() - started)
        density.update(nv, integral)
        if nv <= max_vertices:
            return ngs.Mesh(ngmesh)
        c = density.value
        margin *= 0.95
    raise MeshingError(f"remesh: no 3D mesh with <= {max_vertices} vertices after {max_attempts} "
                       f"attempts (last had {nv}); raise max_vertices or hmax")
