"""The z-sub-step as a bound-constrained minimization (``discretization.z_update = "obstacle"``).

The paper's scheme solves the z-sub-step without the non-repair bound and then projects,
``z = min(1, max(z_trial, z_old))``. That is the constrained minimizer only where the bound
is inactive or the unconstrained solution is already close to it. For AT1 it is not: the
surface term's constant source ``-3 gamma/(8 eps)`` drives the unconstrained z_trial far
below zero wherever the material is intact (``-dt/alpha2 * 3 gamma/(8 eps)``, hundreds at the
demos' alpha2 and dt), and the gradient term drags the process zone ahead of a crack tip down
with it, so the tip does not grow until the load is well above Griffith's
(docs/theory.md, "Crack models").

This module solves the sub-step's quadratic problem

    min 1/2 v.A v - f.v   over node values v >= lower

exactly, by the primal-dual active set method (Hintermueller, Ito, Kunisch 2003: a
semismooth Newton method, finite termination when A is an M-matrix). The unknowns are the
node values of z (the constraint acts on single unknowns there): ``A = T^T A_h T`` with
T of :meth:`ngfrac.fem.nodal.LagrangeNodes.coefficient_matrix`. Each iteration solves the
system on the inactive nodes only, with SciPy's SuperLU (single-threaded: bitwise the same
with any thread count). For AT1 the inactive set is the band and the process zone, a small
part of the mesh.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

if TYPE_CHECKING:
    from ..fem.nodal import LagrangeNodes

LOG = logging.getLogger(__name__)

MAX_ITERATIONS = 60
"""Active-set iterations before giving up (then the last iterate is projected)."""

VALUE_TOLERANCE = 1e-10
"""A free node joins the active set only when it falls this far below the bound (z is in
[0, 1]; without it a node at the bound up to round-off, 6e-12 below it, entered and left the
set in turn forever)."""


@dataclass
class ObstacleSolution:
    """The result of :func:`solve_lower_obstacle`.

    Attributes
    ----------
    values : numpy.ndarray
        The node values, ``>= lower`` everywhere.
    active : numpy.ndarray
        The nodes held at the bound (bool).
    iterations : int
        Active-set iterations (linear solves).
    converged : bool
        False when the active set still changed after :data:`MAX_ITERATIONS` or came back to
        an earlier one (a cycle).
    """

    values: np.ndarray
    active: np.ndarray
    iterations: int
    converged: bool


class NodalObstacle:
    """The z-step under ``z >= z_old`` at the nodes of one space, warm-started from the
    last step's active set (one object per mesh).

    Parameters
    ----------
    nodes : ngfrac.fem.nodal.LagrangeNodes
        The nodes of the z-space.
    fixed : numpy.ndarray, optional
        Nodes held at their bound, z_old = 0 there (``phase_field.damage_free``,
        :attr:`ngfrac.mesh.fields.MeshFields.damage_free_nodes`; bool).
    """

    def __init__(self, nodes: "LagrangeNodes", fixed: np.ndarray | None = None) -> None:
        self.nodes = nodes
        self._to_coefficients = nodes.coefficient_matrix()
        self._active: np.ndarray | None = None
        self.fixed = fixed

    def solve(self, ngs_matrix: object, ngs_rhs: object, z_old: object,
              result: object) -> ObstacleSolution:
        """Minimize the quadratic form of the assembled matrix and right-hand side over
        node values ``>= z_old``'s; the minimizer goes to the GridFunction ``result``."""
        matrix, rhs = node_system(ngs_matrix, ngs_rhs, self._to_coefficients)
        lower = self.nodes.values(z_old)
        active = self._active
        if active is None:  # first guess: where the energy's slope at z_old pushes z down
            active = matrix @ lower - rhs > 0
        solution = solve_lower_obstacle(matrix, rhs, lower, active, self.fixed)
        self._active = solution.active
        self.nodes.assign(result, solution.values)
        return solution


def solve_lower_obstacle(matrix: sp.csr_matrix, rhs: np.ndarray, lower: np.ndarray,
                         active: np.ndarray, fixed: np.ndarray | None = None) -> ObstacleSolution:
    """Minimize ``1/2 v.A v - f.v`` over ``v >= lower`` by primal-dual active sets.

    Parameters
    ----------
    matrix : scipy.sparse.csr_matrix
        A, symmetric positive definite.
    rhs : numpy.ndarray
        f.
    lower : numpy.ndarray
        The bound.
    active : numpy.ndarray
        The first guess of the nodes at the bound (bool), e.g. the last step's set.
    fixed : numpy.ndarray, optional
        Nodes held at their bound whatever their multiplier (a Dirichlet condition, bool).

    Returns
    -------
    ObstacleSolution
    """
    n = len(rhs)
    fixed = np.zeros(n, dtype=bool) if fixed is None else np.asarray(fixed, dtype=bool)
    active = np.asarray(active, dtype=bool) | fixed
    values = np.array(lower, dtype=float)
    scale = float(np.max(np.abs(rhs))) if n else 0.0
    tol = 1e-12 * max(scale, np.finfo(float).tiny)
    iterations, converged, seen, cycled = 0, False, set(), False
    while iterations < MAX_ITERATIONS:
        iterations += 1
        values = _solve_inactive(matrix, rhs, lower, active)
        multiplier = matrix @ values - rhs  # >= 0 where the bound holds z down
        new_active = np.where(active, multiplier >= -tol, values < lower - VALUE_TOLERANCE) | fixed
        if LOG.isEnabledFor(logging.DEBUG):
            LOG.debug("active set %d: %d nodes, %d in, %d out, below %.3g, multiplier %.3g",
                      iterations, active.sum(), (new_active & ~active).sum(),
                      (active & ~new_active).sum(), float(np.max(lower - values, initial=0)),
                      float(-np.min(np.where(active, multiplier, 0), initial=0)))
        if np.array_equal(new_active, active):
            converged = True
            break
        seen.add(np.packbits(active).tobytes())
        if np.packbits(new_active).tobytes() in seen:  # a cycle: no set satisfies both tests
            cycled = True
            break
        active = new_active
    if not converged:
        LOG.warning("the z-step's active set did not settle (%s after %d iterations); the "
                    "last iterate is projected onto z >= z_old",
                    "a cycle" if cycled else "still changing", iterations)
    return ObstacleSolution(np.maximum(values, lower), active, iterations, converged)


def _solve_inactive(matrix: sp.csr_matrix, rhs: np.ndarray, lower: np.ndarray,
                    active: np.ndarray) -> np.ndarray:
    """v = lower on the active nodes, A v = f on the others."""
    values = np.array(lower, dtype=float)
    free = np.flatnonzero(~active)
    if free.size == 0:
        return values
    held = np.flatnonzero(active)
    block = matrix[free][:, free].tocsc()
    right = rhs[free] - matrix[free][:, held] @ lower[held]
    values[free] = spla.splu(block, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                             options={"SymmetricMode": True}).solve(right)
    return values


def node_system(ngs_matrix: object, ngs_rhs: object, to_coefficients: sp.csr_matrix
                ) -> tuple[sp.csr_matrix, np.ndarray]:
    """``(T^T A T, T^T f)`` from an NGSolve sparse matrix and vector of the space."""
    rows, cols, vals = ngs_matrix.COO()
    n = ngs_matrix.height
    a = sp.csr_matrix((np.asarray(vals), (np.asarray(rows), np.asarray(cols))), shape=(n, n))
    if "Symmetric" in type(ngs_matrix).__name__:  # only one triangle is stored
        a = a + a.T - sp.diags(a.diagonal())
    f = ngs_rhs.FV().NumPy()
    t = to_coefficients
    return (t.T @ a @ t).tocsr(), t.T @ f
