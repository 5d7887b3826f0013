"""Moving the state to a new mesh: u by projection, z and its bound at the Lagrange nodes.

``u`` goes over with ``GridFunction.Set`` of the old GridFunction (NGSolve evaluates it on the
new mesh's integration points: an element-wise L2 projection, averaged at shared dofs). On a
nested refinement this is exact; on a regenerated mesh its L2 error is within 1.0-1.7x of the
best approximation (the global L2 projection) in the new space, P1-P3 measured. In 3D, where
that point search per integration point made most of a mesh change, u of order 1 or 2 goes
over at its Lagrange nodes like z (``transfer(..., method="nodes")``).

``z`` and the non-repair bound go over by *evaluating* the old fields at the new Lagrange
nodes (vertices and, for P2, edge midpoints), then::

    z_new = min(1, max(0, z_old(x_i)))      bound_new = min(1, max(0, bound_old(x_i)))
    z_new = max(z_new, bound_new)           at every node x_i

so ``0 <= z_new <= 1`` and ``z_new >= bound_new`` hold exactly at the nodes, the form in which
the stepper enforces them. On a nested refinement the node values reproduce the same P1/P2
polynomial, so the transfer is exact (to rounding); on a regenerated mesh it is Lagrange
interpolation of the old field. For P1 both clip and max are no-ops (interpolation of values
in [0, 1] with z >= bound stays so); for P2 they catch the over- and undershoots of the
quadratic.

A transfer loses crack length where the new mesh has no edges on the crack (the kink of the
profile at d = 0): refine the core; docs/adaptivity.md ("What a transfer costs") has the
measured losses and timings. Use :func:`crack_length` before and after to see what a transfer
did to the crack.

Points the old mesh does not cover (none for rectangles; only for curved or moved
boundaries) take the value at the nearest old vertex, with a warning.
"""
from __future__ import annotations

import logging
from typing import Any, Literal

import numpy as np
import ngsolve as ngs
from scipy.spatial import cKDTree

from ..physics.crack_models import CrackModel
from ..fem.nodal import LagrangeNodes
from ..fem.threads import SHARED_CHOOSER, integrate

log = logging.getLogger(__name__)


def transfer(gf_old: ngs.GridFunction, fes_new: ngs.FESpace,
             method: Literal["set", "nodes"] = "set") -> ngs.GridFunction:
    """Move a GridFunction to a space on another mesh.

    Parameters
    ----------
    gf_old : ngsolve.GridFunction
        Any field on the old mesh (e.g. the displacement u).
    fes_new : ngsolve.FESpace
        The space on the new mesh.
    method : {"set", "nodes"}
        ``"set"``: ``GridFunction.Set`` (local L2 projection, any space). ``"nodes"``:
        Lagrange interpolation at the nodes of a P1/P2 ``fes_new``, scalar (``H1``) or a
        ``VectorH1`` of such components: one point search per node instead of one per
        integration point (about 2x faster in 2D; a 3D mesh change's transfer 12-16x:
        docs/benchmarks.md, section 16).

    Returns
    -------
    ngsolve.GridFunction
        A new GridFunction in ``fes_new`` with the name of ``gf_old``.
    """
    gf_new = ngs.GridFunction(fes_new, gf_old.name)
    if method == "set":
        with SHARED_CHOOSER("transfer"):
            gf_new.Set(gf_old)
    elif method == "nodes":
        parts = tuple(gf_new.components) or (gf_new,)  # a VectorH1's components, or itself
        nodes = LagrangeNodes(parts[0].space)
        assign_nodes(nodes, parts, gf_old(locate(gf_old.space.mesh, nodes.points)))
    else:
        raise ValueError(f"method must be 'set' or 'nodes', got {method!r}")
    return gf_new


def locate(mesh: ngs.Mesh, points: np.ndarray) -> np.ndarray:
    """Mesh points for an (n, d) array of coordinates, vectorised (``mesh(xs, ys)``).

    Points outside ``mesh`` are replaced by the nearest mesh vertex (logged as a warning).
    Returns NGSolve's structured array of mesh points, for ``gf(result)``.
    """
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != mesh.dim:
        raise ValueError(f"points must have shape (n, {mesh.dim}), got {points.shape}")
    located = mesh(*points.T)
    missing = np.flatnonzero(located["nr"] < 0)
    if len(missing):
        vertices = np.array(mesh.ngmesh.Coordinates())[:, : mesh.dim]
        distance, nearest = cKDTree(vertices).query(points[missing])
        log.warning("%d of %d points lie outside the old mesh; they take the value at the "
                    "nearest old vertex (up to %.3g from it)", len(missing), len(points),
                    distance.max())
        located[missing] = mesh(*vertices[nearest].T)
    return located


def assign_nodes(nodes: LagrangeNodes, parts: tuple[ngs.GridFunction, ...],
                 values: Any) -> None:
    """Give each GridFunction of ``parts`` (the components of one field, all in spaces with
    the Lagrange nodes ``nodes``) its column of ``values``, evaluated at those nodes
    (``gf(located)``: shape (n,) or (n, len(parts)))."""
    values = np.asarray(values, dtype=float).reshape(nodes.n_nodes, len(parts))
    for i, part in enumerate(parts):
        nodes.assign(part, values[:, i])


def evaluate(gf: ngs.GridFunction, located: np.ndarray) -> np.ndarray:
    """Values of a scalar GridFunction at points from :func:`locate`, shape (n,)."""
    return np.asarray(gf(located), dtype=float).reshape(len(located))


def transfer_phase_field(z_old: ngs.GridFunction, bound_old: ngs.GridFunction,
                         fes_new: ngs.FESpace) -> tuple[ngs.GridFunction, ngs.GridFunction]:
    """Transfer the phase field and its non-repair bound at the Lagrange nodes of ``fes_new``.

    Parameters
    ----------
    z_old : ngsolve.GridFunction
        The phase field (P1 or P2 H1, or anything that can be evaluated) on the old mesh.
    bound_old : ngsolve.GridFunction
        The lower bound of z (the previous z, or an irreversibility field), on the old mesh;
        it may be ``z_old`` itself.
    fes_new : ngsolve.FESpace
        H1 space of order 1 or 2 on the new mesh.

    Returns
    -------
    z_new, bound_new : ngsolve.GridFunction
        In ``fes_new``, with ``0 <= bound_new <= z_new <= 1`` at every node.
    """
    nodes = LagrangeNodes(fes_new)
    located = locate(z_old.space.mesh, nodes.points)
    z = evaluate(z_old, located)
    if bound_old is z_old:
        bound = z.copy()
    else:
        if bound_old.space.mesh is not z_old.space.mesh:
            located = locate(bound_old.space.mesh, nodes.points)
        bound = evaluate(bound_old, located)
    log.debug("phase-field transfer: z in [%.3g, %.3g] before clipping, bound in [%.3g, %.3g]",
              z.min(), z.max(), bound.min(), bound.max())
    z = np.clip(z, 0.0, 1.0)
    bound = np.clip(bound, 0.0, 1.0)
    raised = int(np.count_nonzero(bound > z))
    if raised:
        log.debug("phase-field transfer: bound lifted z at %d of %d nodes (by up to %.3g)",
                  raised, len(z), float(np.max(bound - z)))
    z = np.maximum(z, bound)
    z_new = ngs.GridFunction(fes_new, z_old.name)
    bound_new = ngs.GridFunction(fes_new, bound_old.name)
    nodes.assign(z_new, z)
    nodes.assign(bound_new, bound)
    return z_new, bound_new


def crack_length(z: ngs.GridFunction, epsilon: float, crack_model: CrackModel) -> float:
    """The Gamma-limit crack length ``int w dx``, ``w`` the crack model's surface density
    (AT2's ``1/2 (eps |grad z|^2 + z^2 / eps)`` by default)."""
    return integrate(crack_model.surface_density(z, epsilon), z.space.mesh)
