"""The plane-strain u-sub-step with a frozen smooth z converges at the optimal rates, orders 1-3.

Manufactured solution (paper moduli E = 50, nu = 0.29)::

    ux = sin(pi x) sin(pi y) + 0.1 y^2,   uy = x (1-x) y (1-y) + 0.2 x,   z = (x + y)/4

with f = -div(s sigma[u]), s = (1-z)^2 + eta, i.e. ``f = -s div sigma + (1-z)/2 sigma (1, 1)``
(grad s = -(1-z)/2 (1, 1)), and u = exact on all four edges (the boundary data is not zero,
so the per-component Dirichlet interpolation is tested too).
"""
import numpy as np
import ngsolve as ngs
import pytest

from ngfrac.geometry.domains import build_mesh
from ngfrac.scene import Material
from ngfrac.solve.stepper import PhaseFieldStepper

from ngfrac.testing.scenes import demo_data, scene_from

ETA = 1e-6
E, NU = 50.0, 0.29
LAM, MU = Material(E=E, nu=NU).lame

UX = "sin(pi*x)*sin(pi*y) + 0.1*y**2"
UY = "x*(1 - x)*y*(1 - y) + 0.2*x"
# first and second derivatives of UX, UY, by hand (checked against NGSolve's Diff below)
D = {"ux_x": "pi*cos(pi*x)*sin(pi*y)", "ux_y": "(pi*sin(pi*x)*cos(pi*y) + 0.2*y)",
     "uy_x": "((1 - 2*x)*y*(1 - y) + 0.2)", "uy_y": "x*(1 - x)*(1 - 2*y)",
     "ux_xx": "(-pi**2*sin(pi*x)*sin(pi*y))", "ux_yy": "(-pi**2*sin(pi*x)*sin(pi*y) + 0.2)",
     "ux_xy": "pi**2*cos(pi*x)*cos(pi*y)", "uy_xx": "(-2*y*(1 - y))", "uy_yy": "(-2*x*(1 - x))",
     "uy_xy": "(1 - 2*x)*(1 - 2*y)"}
TR = f"({D['ux_x']} + {D['uy_y']})"
SXX = f"(2*{MU!r}*{D['ux_x']} + {LAM!r}*{TR})"
SYY = f"(2*{MU!r}*{D['uy_y']} + {LAM!r}*{TR})"
SXY = f"({MU!r}*({D['ux_y']} + {D['uy_x']}))"
DIV_X = f"(2*{MU!r}*{D['ux_xx']} + {LAM!r}*({D['ux_xx']} + {D['uy_xy']}) + {MU!r}*({D['ux_yy']} + {D['uy_xy']}))"
DIV_Y = f"({MU!r}*({D['ux_xy']} + {D['uy_xx']}) + 2*{MU!r}*{D['uy_yy']} + {LAM!r}*({D['ux_xy']} + {D['uy_yy']}))"
ONE_MINUS_Z = "(1 - 0.25*(x + y))"
S = f"({ONE_MINUS_Z}**2 + {ETA!r})"
FORCE = [f"-{S}*{DIV_X} + 0.5*{ONE_MINUS_Z}*({SXX} + {SXY})",
         f"-{S}*{DIV_Y} + 0.5*{ONE_MINUS_Z}*({SXY} + {SYY})"]


def scene(order):
    data = demo_data()
    data.pop("adaptivity", None)  # the given mesh stays
    data["model"]["kind"] = "plane_strain"
    data["material"] = {"E": E, "nu": NU, "gamma": 1.0, "body_force": FORCE}
    data["cracks"] = []
    data["loads"] = [{"boundary": b, "value": [UX, UY]} for b in ("bottom", "right", "top", "left")]
    return scene_from(data, f"discretization.order={order}", f"phase_field.residual_stiffness={ETA}")


def exact():
    from ngfrac.scene.expressions import Expression
    return ngs.CoefficientFunction((Expression(UX).to_coefficient(), Expression(UY).to_coefficient()))


def test_manufactured_force_is_minus_div_of_the_degraded_stress():
    """The hand-derived f equals -div(s sigma[u]) computed by NGSolve's symbolic Diff."""
    sc = scene(1)
    mesh = build_mesh(sc.geometry, 0.25)
    u = exact()
    grad = [[u[i].Diff(v) for v in (ngs.x, ngs.y)] for i in range(2)]
    e = [[0.5 * (grad[i][j] + grad[j][i]) for j in range(2)] for i in range(2)]
    s = (1 - 0.25 * (ngs.x + ngs.y)) ** 2 + ETA
    sigma = [[s * (2 * MU * e[i][j] + (LAM * (e[0][0] + e[1][1]) if i == j else 0)) for j in range(2)]
             for i in range(2)]
    f = [-(sigma[i][0].Diff(ngs.x) + sigma[i][1].Diff(ngs.y)) for i in range(2)]
    from ngfrac.scene.expressions import Expression
    for i in range(2):
        diff = ngs.Integrate((Expression(FORCE[i]).to_coefficient() - f[i]) ** 2, mesh, order=10)
        assert np.sqrt(diff) < 1e-10


def errors(order, h):
    sc = scene(order)
    stepper = PhaseFieldStepper(sc, mesh=build_mesh(sc.geometry, h))
    points = stepper.nodes.points
    stepper.nodes.assign(stepper.z, 0.25 * (points[:, 0] + points[:, 1]))
    with ngs.TaskManager():
        stepper.solve_u()
    u_exact = exact()
    grad_exact = ngs.CoefficientFunction(tuple(u_exact[i].Diff(v) for i in range(2) for v in (ngs.x, ngs.y)),
                                         dims=(2, 2))
    mesh, u = stepper.mesh, stepper.u
    l2 = np.sqrt(ngs.Integrate(ngs.InnerProduct(u - u_exact, u - u_exact), mesh, order=2 * order + 6))
    h1 = np.sqrt(ngs.Integrate(ngs.InnerProduct(ngs.grad(u) - grad_exact, ngs.grad(u) - grad_exact),
                               mesh, order=2 * order + 6))
    return l2, h1


@pytest.mark.parametrize("order", [1, 2, 3])
def test_vector_u_solve_rates(order):
    sizes = [0.2, 0.1, 0.05, 0.025] if order < 3 else [0.25, 0.125, 0.0625]
    table = np.array([errors(order, h) for h in sizes])
    rate_l2 = np.polyfit(np.log(sizes), np.log(table[:, 0]), 1)[0]
    rate_h1 = np.polyfit(np.log(sizes), np.log(table[:, 1]), 1)[0]
    report = "\n".join(f"h={h:<7} L2={e[0]:.3e} H1={e[1]:.3e}" for h, e in zip(sizes, table))
    message = f"plane strain, order {order}: L2 rate {rate_l2:.2f}, H1 rate {rate_h1:.2f}\n{report}"
    print(message)
    assert rate_l2 > order + 1 - 0.2, message
    assert rate_h1 > order - 0.2, message
