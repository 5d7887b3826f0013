"""Residual estimator: exact zeros, boundary terms, reliability and robustness."""

import numpy as np
import pytest
from netgen.csg import unit_cube
from ngsolve import BND, CF, BilinearForm, GridFunction, H1, Integrate, LinearForm, Mesh
from ngsolve import dx, grad, pi, sin, sqrt, x, y, z

from estimator_problems import (
    SMOOTH_SOURCE,
    solve_layer,
    solve_smooth_poisson,
    square_mesh,
    table,
    total,
)
from estimators import residual_estimator


def test_zero_for_exact_quadratic_with_dirichlet_boundary():
    mesh = square_mesh(0.3)
    gf = GridFunction(H1(mesh, order=2))
    gf.Set(x * x + x * y)
    # -div((1 + x) grad u) + 3 u = f for u = x^2 + x y
    source = -((2 * x + y) + (1 + x) * 2) + 3 * (x * x + x * y)
    eta = residual_estimator(gf, 1 + x, 3.0, source, dirichlet=".*",
                             diffusion_gradient=CF((1, 0)))
    assert eta.shape == (mesh.ne,)
    assert eta.max() < 1e-10
    # Without grad A the variable-coefficient residual is not seen as zero.
    assert residual_estimator(gf, 1 + x, 3.0, source, dirichlet=".*").max() > 1e-3


def test_boundary_flux_counts_on_neumann_facets_only():
    mesh = square_mesh(0.3)
    gf = GridFunction(H1(mesh, order=1))
    gf.Set(x)  # no residual, no jumps; A du/dn = -1 on "left", +1 on "right"
    area = Integrate(CF(1), mesh, element_wise=True).NumPy()
    facet_count = {name: np.zeros(mesh.ne) for name in mesh.GetBoundaries()}
    for bel in mesh.Elements(BND):
        (owner,) = mesh[bel.edges[0]].elements
        facet_count[bel.mat][owner.nr] += 1
    # NGSolve's facet h_E is the height 2|T|/|E|, so h_E ||1||_E^2 = 2|T| per facet.
    cases = [(None, ["left", "right"]), ("left", ["right"]), ("left|right", [])]
    for dirichlet, neumann in cases:
        expected = 2 * area * sum((facet_count[name] for name in neumann), np.zeros(mesh.ne))
        eta = residual_estimator(gf, 1.0, 0.0, 0.0, dirichlet=dirichlet)
        np.testing.assert_allclose(eta**2, expected, atol=1e-12, err_msg=f"dirichlet={dirichlet}")


@pytest.mark.parametrize("order, levels, bounds", [(1, 5, (1.0, 10.0)), (2, 4, (1.0, 15.0))])
def test_reliable_with_constant_ratio_on_smooth_problem(order, levels, bounds):
    mesh = square_mesh(0.25)
    rows = []
    for _ in range(levels):
        sol = solve_smooth_poisson(mesh, order)
        estimate = total(residual_estimator(sol.gf, 1.0, 0.0, SMOOTH_SOURCE, dirichlet=".*"))
        rows.append((sol.ndof, sol.error, estimate, estimate / sol.error))
        mesh.Refine()
    report = table(f"P{order}: ndof  true_H1_err  estimate  ratio", rows)
    ratio = np.array([r[3] for r in rows])
    assert np.all((ratio > bounds[0]) & (ratio < bounds[1])), report
    assert ratio.max() / ratio.min() < 1.5, report


def test_reliable_in_3d():
    exact = sin(pi * x) * sin(pi * y) * sin(pi * z)
    exact_grad = CF((exact.Diff(x), exact.Diff(y), exact.Diff(z)))
    source = 3 * pi**2 * exact
    mesh = Mesh(unit_cube.GenerateMesh(maxh=0.3))
    rows = []
    for _ in range(2):
        space = H1(mesh, order=1, dirichlet=".*")
        u, v = space.TnT()
        a = BilinearForm(grad(u) * grad(v) * dx).Assemble()
        f = LinearForm(source * v * dx(bonus_intorder=4)).Assemble()
        gf = GridFunction(space)
        gf.vec.data = a.mat.Inverse(space.FreeDofs(), "sparsecholesky") * f.vec
        diff = grad(gf) - exact_grad
        error = float(sqrt(Integrate(diff * diff, mesh, order=6)))
        estimate = total(residual_estimator(gf, 1.0, 0.0, source, dirichlet=".*"))
        rows.append((space.ndof, error, estimate, estimate / error))
        mesh.Refine()
    ratio = np.array([r[3] for r in rows])
    assert np.all((ratio > 1.0) & (ratio < 10.0)), table("ndof  err  est  ratio", rows)


def test_robust_scaling_is_uniform_in_eps():
    rows = []
    for eps in (0.1, 0.02, 0.005):
        mesh = square_mesh(0.25)
        for _ in range(3):
            mesh.Refine()
        sol = solve_layer(mesh, eps)
        robust = total(residual_estimator(sol.gf, eps**2, 1.0, 0.0, dirichlet=".*",
                                          scaling="robust"))
        standard = total(residual_estimator(sol.gf, eps**2, 1.0, 0.0, dirichlet=".*"))
        rows.append((eps, sol.error, robust / sol.error, standard / sol.error))
    report = table("eps  energy_err  robust_ratio  standard_ratio", rows)
    robust_ratio = np.array([r[2] for r in rows])
    standard_ratio = np.array([r[3] for r in rows])
    assert np.all((robust_ratio > 0.5) & (robust_ratio < 10.0)), report
    # The standard weights do not measure the eps-energy norm: the ratio drifts with eps.
    assert standard_ratio.max() / standard_ratio.min() > 5.0, report


def test_unknown_scaling_rejected():
    gf = GridFunction(H1(square_mesh(0.5), order=1))
    with pytest.raises(ValueError, match="scaling"):
        residual_estimator(gf, 1.0, 0.0, 1.0, scaling="verfuerth")
