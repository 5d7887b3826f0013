"""The bound-constrained z-step (discretization.z_update = "obstacle", ngfrac/solve/obstacle.py)."""
from __future__ import annotations

import numpy as np
import ngsolve as ngs
import pytest
import scipy.sparse as sp
from netgen.geom2d import unit_square

from ngfrac.fem.nodal import LagrangeNodes
from ngfrac.solve.obstacle import VALUE_TOLERANCE, node_system, solve_lower_obstacle


def kkt_violation(matrix, rhs, lower, values):
    """The largest violation of x >= l, A x - f >= 0 where x = l, A x - f = 0 elsewhere,
    relative to |f|."""
    residual = matrix @ values - rhs
    at_bound = values <= lower + VALUE_TOLERANCE
    scale = np.max(np.abs(rhs))
    return max(float(np.max(lower - values, initial=0.0)),
               float(np.max(-residual[at_bound], initial=0.0)) / scale,
               float(np.max(np.abs(residual[~at_bound]), initial=0.0)) / scale)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_active_set_method_meets_the_kkt_conditions(seed):
    # A 1D stiffness + mass matrix (an M-matrix: the method terminates finitely) and a
    # load that pushes part of the line below the bound and part above it.
    rng = np.random.default_rng(seed)
    n, h = 400, 1.0 / 400
    main = np.full(n, 2 / h + 4 * h / 6)
    off = np.full(n - 1, -1 / h + h / 6)
    matrix = sp.diags([off, main, off], [-1, 0, 1], format="csr")
    x = np.linspace(0, 1, n)
    rhs = h * (np.sin(6 * np.pi * x + rng.uniform(0, 6)) + rng.normal(0, 0.3, n))
    lower = np.clip(rng.normal(0.0, 0.02, n), 0, None)
    solution = solve_lower_obstacle(matrix, rhs, lower, np.zeros(n, dtype=bool))
    assert solution.converged
    assert 0 < solution.active.sum() < n  # both kinds of node occur
    # round-off of a direct solve of a 400-unknown system, far below 1e-9
    assert kkt_violation(matrix, rhs, lower, solution.values) < 1e-9
    # the constrained minimum is below every other feasible point tried
    energy = lambda v: 0.5 * v @ (matrix @ v) - rhs @ v
    for _ in range(20):
        other = np.maximum(solution.values + rng.normal(0, 1e-3, n), lower)
        assert energy(other) >= energy(solution.values)


def test_the_node_system_is_the_same_quadratic_form():
    # P2 on an unstructured mesh: 1/2 v.A v - f.v in node values equals the form's energy of
    # the GridFunction with those node values.
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.15))
    fes = ngs.H1(mesh, order=2)
    z, w = fes.TnT()
    a = ngs.BilinearForm(fes, symmetric=True)
    a += (0.01 * ngs.grad(z) * ngs.grad(w) + (1 + ngs.x) * z * w) * ngs.dx
    a.Assemble()
    f = ngs.LinearForm(ngs.sin(3 * ngs.x) * w * ngs.dx).Assemble()
    nodes = LagrangeNodes(fes)
    matrix, rhs = node_system(a.mat, f.vec, nodes.coefficient_matrix())
    values = np.random.default_rng(0).uniform(0, 1, nodes.n_nodes)
    gf = ngs.GridFunction(fes)
    nodes.assign(gf, values)
    coefficients = gf.vec.FV().NumPy()
    direct = 0.5 * ngs.InnerProduct(gf.vec, (a.mat * gf.vec).Evaluate()) - ngs.InnerProduct(f.vec, gf.vec)
    in_nodes = 0.5 * values @ (matrix @ values) - rhs @ values
    assert abs(in_nodes - direct) < 1e-12 * max(1.0, abs(direct)), (in_nodes, direct)
    assert np.allclose(nodes.values(gf), values, rtol=0, atol=1e-14)
    assert coefficients.shape == (fes.ndof,)
