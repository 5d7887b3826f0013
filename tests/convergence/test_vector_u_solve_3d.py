"""The 3D u-sub-step with a frozen smooth z converges at the optimal rates, orders 1-3.

Manufactured solution on the unit cube (E = 50, nu = 0.29)::

    ux = sin(pi x) sin(pi y) sin(pi z) + 0.1 y^2
    uy = x (1-x) y (1-y) z + 0.2 x
    uz = cos(pi x) y z (1-z) - 0.1 z^2          z_phase = (x + y + z)/6

with f = -div(s sigma[u]), s = (1-z_phase)^2 + eta, computed by NGSolve's symbolic ``Diff``
and compared once with a hand-derived component; u = exact on all six faces (not zero, so the
per-component Dirichlet interpolation is exercised). Measured rates against Netgen's maxh
(``pytest -s --runslow``): L2 2.17 / 2.93 / 4.47 and H1 1.07 / 1.95 / 3.31 for orders 1 / 2 / 3
(p + 1 and p; order 3 a little above on these coarse meshes).
"""
import numpy as np
import ngsolve as ngs
import pytest

from ngfrac.scene.expressions import Expression
from ngfrac.geometry.domains import build_mesh
from ngfrac.scene import Material, Scene
from ngfrac.solve.stepper import PhaseFieldStepper

ETA = 1e-6
E, NU = 50.0, 0.29
LAM, MU = Material(E=E, nu=NU).lame
U = ["sin(pi*x)*sin(pi*y)*sin(pi*z) + 0.1*y**2",
     "x*(1 - x)*y*(1 - y)*z + 0.2*x",
     "cos(pi*x)*y*z*(1 - z) - 0.1*z**2"]
XYZ = (ngs.x, ngs.y, ngs.z)


def scene(order):
    faces = ("left", "right", "bottom", "top", "back", "front")
    return Scene.from_dict({
        "model": {"kind": "elasticity_3d"},
        "material": {"E": E, "nu": NU, "gamma": 1.0},
        "phase_field": {"epsilon": 0.1, "alpha2": 1e-3, "residual_stiffness": ETA},
        "geometry": {"kind": "box", "width": 1.0, "height": 1.0, "depth": 1.0},
        "loads": [{"boundary": b, "value": U} for b in faces],
        "time": {"dt": 0.1, "t_end": 0.1},
        "discretization": {"order": order},
    })


def exact():
    return ngs.CoefficientFunction(tuple(Expression(u).to_coefficient() for u in U))


def degradation():
    return (1 - (ngs.x + ngs.y + ngs.z) / 6) ** 2 + ETA


def manufactured_force():
    """f = -div(s sigma[u]) by symbolic differentiation."""
    u = exact()
    grad = [[u[i].Diff(v) for v in XYZ] for i in range(3)]
    e = [[0.5 * (grad[i][j] + grad[j][i]) for j in range(3)] for i in range(3)]
    trace = e[0][0] + e[1][1] + e[2][2]
    s = degradation()
    sigma = [[s * (2 * MU * e[i][j] + (LAM * trace if i == j else 0)) for j in range(3)] for i in range(3)]
    return ngs.CoefficientFunction(tuple(-sum(sigma[i][j].Diff(XYZ[j]) for j in range(3))
                                         for i in range(3)))


def test_symbolic_force_matches_a_hand_derived_component():
    """f_y by hand: uy is a polynomial, so its part of -div(s sigma) is short to write out."""
    mesh = build_mesh(scene(1).geometry, 0.5)
    f = manufactured_force()
    # sigma_yj = s (mu (d_j uy + d_y uj) + lam tr e delta_yj); f_y = -sum_j d_j sigma_yj
    u = exact()
    g = [[u[i].Diff(v) for v in XYZ] for i in range(3)]
    s = degradation()
    ds = [-(1 - (ngs.x + ngs.y + ngs.z) / 6) / 3] * 3  # d_j s
    tr = g[0][0] + g[1][1] + g[2][2]
    sig = [MU * (g[1][j] + g[j][1]) + (LAM * tr if j == 1 else 0) for j in range(3)]
    div = sum(sig[j].Diff(XYZ[j]) for j in range(3))
    by_hand = -(s * div + sum(ds[j] * sig[j] for j in range(3)))
    assert np.sqrt(ngs.Integrate((f[1] - by_hand) ** 2, mesh, order=10)) < 1e-9


def errors(order, h):
    sc = scene(order)
    stepper = PhaseFieldStepper(sc, mesh=build_mesh(sc.geometry, h))
    points = stepper.nodes.points
    stepper.nodes.assign(stepper.z, points.sum(axis=1) / 6)
    # the manufactured f is a CoefficientFunction, not a scene expression: set the u-form's
    # right-hand side directly (the same form the stepper builds from material.body_force)
    v = stepper.fes_u.TestFunction()
    stepper.u_problem.f_u = ngs.LinearForm(manufactured_force() * v * stepper.dx)
    with ngs.TaskManager():
        stepper.solve_u()
    u_exact = exact()
    grad_exact = ngs.CoefficientFunction(tuple(u_exact[i].Diff(v) for i in range(3) for v in XYZ),
                                         dims=(3, 3))
    mesh, u = stepper.mesh, stepper.u
    l2 = np.sqrt(ngs.Integrate(ngs.InnerProduct(u - u_exact, u - u_exact), mesh, order=2 * order + 4))
    h1 = np.sqrt(ngs.Integrate(ngs.InnerProduct(ngs.grad(u) - grad_exact, ngs.grad(u) - grad_exact),
                               mesh, order=2 * order + 4))
    return l2, h1, mesh.nv


SIZES = {1: [0.3, 0.2, 0.12, 0.08], 2: [0.4, 0.25, 0.15, 0.1], 3: [0.3, 0.2, 0.15, 0.12]}


@pytest.mark.parametrize("order", [1, 2, pytest.param(3, marks=pytest.mark.slow)])
def test_vector_u_solve_rates_3d(order):
    """Order 3 takes ~100 s (P3 on 855 vertices with the order-10 rule), so it is a slow study."""
    sizes = SIZES[order]
    table = np.array([errors(order, h) for h in sizes])
    rate_l2 = np.polyfit(np.log(sizes), np.log(table[:, 0]), 1)[0]
    rate_h1 = np.polyfit(np.log(sizes), np.log(table[:, 1]), 1)[0]
    report = "\n".join(f"h={h:<6} nv={int(e[2]):<6} L2={e[0]:.3e} H1={e[1]:.3e}"
                       for h, e in zip(sizes, table))
    message = f"3D elasticity, order {order}: L2 rate {rate_l2:.2f}, H1 rate {rate_h1:.2f}\n{report}"
    print(message)
    assert rate_l2 > order + 1 - 0.2, message
    assert rate_h1 > order - 0.2, message
