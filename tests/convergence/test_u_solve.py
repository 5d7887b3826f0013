"""The u-sub-step with a frozen smooth z converges at the optimal rates for orders 1-3.

Manufactured solution u = sin(pi x) sin(pi y), z = (x + y)/4 (exactly representable in P1/P2),
f = -div(((1-z)^2 + eta) mu grad u), u = 0 on all four edges.
"""
import numpy as np
import ngsolve as ngs
import pytest

from ngfrac.mesh.domains import build_mesh
from ngfrac.solve.stepper import PhaseFieldStepper

from scenes import demo_data, scene_from

ETA = 1e-6
S = "(1 - 0.25*(x + y))"
FORCE = (f"0.5*{S}*pi*(cos(pi*x)*sin(pi*y) + sin(pi*x)*cos(pi*y))"
         f" + 2*pi**2*({S}**2 + {ETA})*sin(pi*x)*sin(pi*y)")


def scene(order):
    data = demo_data()
    data["cracks"] = []
    data["loads"] = [{"boundary": b, "value": "0"} for b in ("bottom", "right", "top", "left")]
    return scene_from(data, f"discretization.order={order}", f"material.body_force=\"{FORCE}\"",
                      f"phase_field.residual_stiffness={ETA}", "material.mu=1.0")


def errors(order, h):
    sc = scene(order)
    stepper = PhaseFieldStepper(sc, mesh=build_mesh(sc.geometry, h))
    points = stepper.nodes.points
    stepper.nodes.assign(stepper.z, 0.25 * (points[:, 0] + points[:, 1]))
    stepper.solve_u()
    exact = ngs.sin(ngs.pi * ngs.x) * ngs.sin(ngs.pi * ngs.y)
    grad_exact = ngs.CoefficientFunction((ngs.pi * ngs.cos(ngs.pi * ngs.x) * ngs.sin(ngs.pi * ngs.y),
                                          ngs.pi * ngs.sin(ngs.pi * ngs.x) * ngs.cos(ngs.pi * ngs.y)))
    mesh, u = stepper.mesh, stepper.u
    l2 = np.sqrt(ngs.Integrate((u - exact) ** 2, mesh, order=2 * order + 6))
    h1 = np.sqrt(ngs.Integrate(ngs.InnerProduct(ngs.grad(u) - grad_exact, ngs.grad(u) - grad_exact),
                               mesh, order=2 * order + 6))
    return l2, h1


@pytest.mark.parametrize("order", [1, 2, 3])
def test_u_solve_rates(order):
    sizes = [0.2, 0.1, 0.05, 0.025] if order < 3 else [0.25, 0.125, 0.0625]
    table = np.array([errors(order, h) for h in sizes])
    rate_l2 = np.polyfit(np.log(sizes), np.log(table[:, 0]), 1)[0]
    rate_h1 = np.polyfit(np.log(sizes), np.log(table[:, 1]), 1)[0]
    report = "\n".join(f"h={h:<7} L2={e[0]:.3e} H1={e[1]:.3e}" for h, e in zip(sizes, table))
    message = f"order {order}: L2 rate {rate_l2:.2f}, H1 rate {rate_h1:.2f}\n{report}"
    print(message)
    assert rate_l2 > order + 1 - 0.2, message
    assert rate_h1 > order - 0.2, message
