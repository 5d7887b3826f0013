"""A crack model is one class and an elastic model is one class: both defined here, in a test
file, run through the stepper, and the stepper's numbers are checked against closed forms.

Homogeneous anti-plane shear of a uncracked square (u = t on top, 0 at the bottom, sides
free) keeps u = t y and z uniform, which P1/P2 represent exactly. With the paper's coupling
the z-step of step k uses W = sigma:e of u^{k-1}, here ``mu_y (t_{k-1}/H)^2``, and the
linearized drive of :meth:`ngfrac.physics.crack_models.CrackModel.drive_factors`:

    alpha2 (z_k - z_{k-1})/dt = -(gamma/eps) z_k + W (explicit - implicit z_k),
    implicit = max(g''(z_{k-1})/2, 0),  explicit = -g'(z_{k-1})/2 + implicit z_{k-1}

(AT2: implicit = explicit = 1, the paper's exact drive W (1 - z)); z_k = max(that, z_{k-1}).
The top reaction is ``g(z_{k-1}) mu_y t_k/H * width`` and E_el = ``1/2 g(z_k) mu_y (t_k/H)^2``
times the area. The stepper computes these by assembly and sparse solves, so they agree to
round-off: 1e-10 relative.
"""
from __future__ import annotations

from typing import Any, Sequence

import ngsolve as ngs
import pytest

from ngfrac import PhaseFieldStepper, Scene
from ngfrac.physics.crack_models import AT2, CrackModel
from ngfrac.physics.elastic import AntiPlane, boundary_work, dirichlet_loads

ROUND_OFF = 1e-10
ETA, GAMMA, EPS, ALPHA2, DT, H, WIDTH = 1e-6, 1.0, 0.1, 1e-3, 0.5, 1.0, 1.0


class CubicDegradation(AT2):
    """AT2's surface term with ``g(z) = (1 - z)^3 + eta``: not quadratic, so the z-step takes
    the linearized drive and the quadrature two orders more."""

    name = "cubic (test)"
    quadratic_degradation = False

    def degradation(self, z: Any, eta: float) -> Any:
        return (1 - z) ** 3 + eta

    def degradation_slope(self, z: Any) -> Any:
        return -3 * (1 - z) ** 2

    def degradation_curvature(self, z: Any) -> Any:
        return 6 * (1 - z)


class OrthotropicAntiPlane:
    """Anti-plane shear with shear moduli mu_x, mu_y: ``sigma = (mu_x u_x, mu_y u_y)``."""

    name = "mode3 orthotropic (test)"
    n_components = 1
    component_names = ("z",)

    def __init__(self, mu_x: float, mu_y: float) -> None:
        self.moduli = ngs.CoefficientFunction((mu_x, 0, 0, mu_y), dims=(2, 2))

    def space(self, mesh: ngs.Mesh, order: int, loads: Sequence[Any]) -> ngs.FESpace:
        return ngs.H1(mesh, order=order,
                      dirichlet="|".join(load.boundary for load in dirichlet_loads(loads)))

    def stress(self, u: Any) -> Any:
        return self.moduli * ngs.grad(u)

    def stress_strain(self, u: Any, v: Any) -> Any:
        return ngs.InnerProduct(self.stress(u), ngs.grad(v))

    def energy_density(self, u: Any) -> Any:
        return self.stress_strain(u, u)

    def boundary_values(self, mesh: ngs.Mesh, loads: Sequence[Any], t: ngs.Parameter) -> Any:
        return mesh.BoundaryCF({load.boundary: load.value.to_coefficient(t)
                                for load in dirichlet_loads(loads)}, default=0)

    def set_boundary(self, gf: ngs.GridFunction, cf: Any) -> None:
        gf.Set(cf, ngs.BND)

    def body_force(self, material: Any, t: ngs.Parameter) -> Any | None:
        return None

    def boundary_force(self, mesh: ngs.Mesh, loads: Sequence[Any], t: ngs.Parameter,
                       v: Any) -> Any | None:
        return boundary_work(mesh, loads, t, v)


def shear_scene() -> Scene:
    return Scene.from_dict({
        "model": {"kind": "mode3"},
        "material": {"mu": 1.0, "gamma": GAMMA},
        "phase_field": {"epsilon": EPS, "alpha2": ALPHA2, "residual_stiffness": ETA},
        "geometry": {"width": WIDTH, "height": H, "mesh_size": 0.25},
        "loads": [{"boundary": "top", "value": "t"}, {"boundary": "bottom", "value": "0"}],
        "time": {"dt": DT, "t_end": 3 * DT},
        "adaptivity": {"enabled": False},
        "output": {"vtk_every": 0},
    })


def expected(model: CrackModel, mu_y: float, steps: int) -> list[tuple[float, float, float]]:
    """(z_k, top force, E_el) of steps 1..steps from the closed form of the module docstring."""
    z, rows = 0.0, []
    for k in range(1, steps + 1):
        w_prev = mu_y * ((k - 1) * DT / H) ** 2
        implicit = max(0.5 * model.degradation_curvature(z), 0.0)
        explicit = -0.5 * model.degradation_slope(z) + implicit * z
        trial = w_prev * explicit / (ALPHA2 / DT + GAMMA / EPS + w_prev * implicit) \
            + ALPHA2 / DT * z / (ALPHA2 / DT + GAMMA / EPS + w_prev * implicit)
        force = model.degradation(z, ETA) * mu_y * k * DT / H * WIDTH
        z = min(1.0, max(trial, z))
        energy = 0.5 * model.degradation(z, ETA) * mu_y * (k * DT / H) ** 2 * WIDTH * H
        rows.append((z, force, energy))
    return rows


@pytest.mark.parametrize("crack_model, elastic_model, mu_y", [
    (AT2(), None, 1.0),                               # the paper's path, as a reference
    (CubicDegradation(), None, 1.0),                  # a crack model defined here
    (AT2(), OrthotropicAntiPlane(5.0, 2.0), 2.0),     # an elastic model defined here
    (CubicDegradation(), OrthotropicAntiPlane(5.0, 2.0), 2.0),
], ids=["AT2", "cubic", "orthotropic", "cubic-orthotropic"])
def test_a_model_defined_outside_ngfrac_runs_through_the_stepper(crack_model, elastic_model, mu_y):
    stepper = PhaseFieldStepper(shear_scene(), crack_model=crack_model, elastic_model=elastic_model)
    records = list(stepper.run())
    assert len(records) == 3
    for record, (z, force, energy) in zip(records, expected(crack_model, mu_y, 3)):
        values = stepper.z_node_values() if record is records[-1] else None
        if values is not None:
            assert values.max() - values.min() <= ROUND_OFF * z  # z stays uniform
            assert values.mean() == pytest.approx(z, rel=ROUND_OFF)
        assert record.forces["Fz_top"] == pytest.approx(force, rel=ROUND_OFF)
        assert record.E_el == pytest.approx(energy, rel=ROUND_OFF)
    assert records[-1].E_el > 0 and 0 < z < 1  # the closed form is not trivial here


def test_the_cubic_model_takes_the_linearized_drive_and_more_quadrature():
    """What differs from AT2 is decided by the model, not by a name elsewhere."""
    cubic = PhaseFieldStepper(shear_scene(), crack_model=CubicDegradation())
    paper = PhaseFieldStepper(shear_scene())
    assert cubic.fields.integration_order == paper.fields.integration_order + 2
    assert cubic.crack_model.drive_factors(cubic.z) is not None
    assert paper.crack_model.drive_factors(paper.z) is None
