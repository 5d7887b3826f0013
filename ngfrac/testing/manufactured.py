"""The u-sub-step's manufactured solution: a frozen smooth z, u = sin(pi x) sin(pi y).

z = (x + y)/4 (exactly representable in P1/P2), f = -div(((1-z)^2 + eta) mu grad u),
u = 0 on all four edges. Shared by tests/convergence/test_u_solve.py and
docs/make_verification.py.
"""
from __future__ import annotations

import numpy as np
import ngsolve as ngs

from ..geometry.domains import build_mesh
from ..scene import Scene
from ..solve.stepper import PhaseFieldStepper
from .scenes import demo_data, scene_from

__all__ = ["ETA", "FORCE", "u_scene", "u_errors"]

ETA = 1e-6
"""The residual stiffness eta of the manufactured problem."""
_S = "(1 - 0.25*(x + y))"
FORCE = (f"0.5*{_S}*pi*(cos(pi*x)*sin(pi*y) + sin(pi*x)*cos(pi*y))"
         f" + 2*pi**2*({_S}**2 + {ETA})*sin(pi*x)*sin(pi*y)")
"""The body force f of the manufactured solution (mu = 1)."""


def u_scene(order: int) -> Scene:
    """The slit demo's square without cracks, u = 0 on its edges, the body force FORCE."""
    data = demo_data()
    data["cracks"] = []
    data["loads"] = [{"boundary": b, "value": "0"} for b in ("bottom", "right", "top", "left")]
    return scene_from(data, f"discretization.order={order}", f"material.body_force=\"{FORCE}\"",
                      f"phase_field.residual_stiffness={ETA}", "material.mu=1.0")


def u_errors(order: int, h: float) -> tuple[float, float]:
    """The L2 and H1 errors of the u-solve of order ``order`` on a uniform mesh of size h."""
    sc = u_scene(order)
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
