"""Reaction forces from the residual match closed forms (z = 0, so the stiffness is 1 + eta).

- Plane strain/stress plate W x H, rollers on the bottom and left, top pulled up by Delta, right
  free: uniaxial stress, ``F_y(top) = (1 + eta) E' Delta/H W`` with E' = E/(1 - nu^2) (plane
  strain) or E (plane stress). The solution is linear, so the finite elements reproduce it and the
  reaction is exact to round-off.
- Mode III strip, u = 0 on the bottom and Delta on the top: ``F_z(top) = (1 + eta) mu Delta/H W``.
- Any body force: the reactions balance it, ``sum of F = -int f`` (R vanishes at free dofs and
  a(u, 1) = 0), whatever the mesh.
"""
import numpy as np
import ngsolve as ngs
import pytest

from ngfrac.geometry.domains import build_mesh
from ngfrac.post.reactions import reaction_columns, reaction_forces
from ngfrac.solve.stepper import PhaseFieldStepper

from ngfrac.testing.scenes import demo_data, scene_from

W, H, DELTA, ETA = 2.0, 0.5, 0.01, 1e-6
E, NU = 50.0, 0.29


def stepper_for(kind, loads, body_force=None, h=0.1, order=2):
    data = demo_data()
    data.pop("adaptivity", None)  # the given mesh stays
    data["model"]["kind"] = kind
    data["material"] = {"mu": 1.5} if kind == "mode3" else {"E": E, "nu": NU}
    if body_force is not None:
        data["material"]["body_force"] = body_force
    data["cracks"] = []
    data["loads"] = loads
    scene = scene_from(data, f"geometry.width={W}", f"geometry.height={H}",
                       f"phase_field.residual_stiffness={ETA}", f"discretization.order={order}")
    stepper = PhaseFieldStepper(scene, mesh=build_mesh(scene.geometry, h))
    with ngs.TaskManager():
        stepper.solve_u()
    return stepper


UNIAXIAL = [{"boundary": "top", "value": ["free", f"{DELTA}"]},
            {"boundary": "bottom", "value": ["free", "0"]},
            {"boundary": "left", "value": ["0", "free"]}]


@pytest.mark.parametrize("kind, modulus", [("plane_strain", E / (1 - NU ** 2)), ("plane_stress", E)])
def test_uniaxial_plate(kind, modulus):
    stepper = stepper_for(kind, UNIAXIAL)
    forces = reaction_forces(stepper.u_problem, stepper.scene.loads)
    expected = (1 + ETA) * modulus * DELTA / H * W
    assert forces["top"][1] == pytest.approx(expected, rel=1e-10)
    assert forces["bottom"][1] == pytest.approx(-expected, rel=1e-10)
    assert forces["top"][0] == forces["bottom"][0] == 0.0  # free components carry no reaction
    assert abs(forces["left"][0]) < 1e-10 * expected       # sigma_xx = 0 in uniaxial stress
    columns = reaction_columns(stepper.u_problem, stepper.scene.loads)
    assert list(columns)[:4] == ["Fx_top", "Fy_top", "ux_top", "uy_top"]
    assert columns["Fy_top"] == forces["top"][1]
    assert columns["uy_top"] == pytest.approx(DELTA, rel=1e-12)


def test_mode3_shear_strip():
    stepper = stepper_for("mode3", [{"boundary": "top", "value": f"{DELTA}"},
                                    {"boundary": "bottom", "value": "0"}])
    forces = reaction_forces(stepper.u_problem, stepper.scene.loads)
    expected = (1 + ETA) * 1.5 * DELTA / H * W
    assert forces["top"][0] == pytest.approx(expected, rel=1e-10)
    assert forces["bottom"][0] == pytest.approx(-expected, rel=1e-10)
    assert list(reaction_columns(stepper.u_problem, stepper.scene.loads)) == ["Fz_top", "uz_top", "Fz_bottom", "uz_bottom"]


def test_reactions_balance_the_body_force():
    """Gravity on a plate clamped at top and bottom, with a curved (non-exact) solution."""
    g = 3.0
    loads = [{"boundary": "top", "value": ["0", "0"]}, {"boundary": "bottom", "value": ["0", "0"]}]
    stepper = stepper_for("plane_strain", loads, body_force=["0.5*y", f"-{g}"], h=0.15)
    forces = reaction_forces(stepper.u_problem, stepper.scene.loads)
    total = forces["top"] + forces["bottom"]
    weight = np.array([0.5 * H ** 2 / 2 * W, -g * W * H])  # int f dx
    assert np.allclose(total, -weight, rtol=1e-9, atol=1e-12)
    assert forces["top"][1] > 0 and forces["bottom"][1] > 0  # both edges hold the plate up


def test_reaction_is_exact_at_every_order():
    for order in (1, 3):
        stepper = stepper_for("plane_strain", UNIAXIAL, h=0.2, order=order)
        expected = (1 + ETA) * E / (1 - NU ** 2) * DELTA / H * W
        assert reaction_forces(stepper.u_problem, stepper.scene.loads)["top"][1] == pytest.approx(expected, rel=1e-10)


@pytest.mark.parametrize("alpha1", [0.0, 0.5])
def test_reactions_after_steps_balance_the_rate_term(alpha1):
    """A slit plate under the paper's g = (t, t) on the top, two steps: sum of F = alpha1 int du/dt.

    The residual uses the matrix of the u-solve (z^{k-1}), after z has moved on to z^k.
    """
    data = demo_data()
    data.pop("adaptivity", None)
    data["model"]["kind"] = "plane_strain"
    data["material"] = {"E": E, "nu": NU}
    data["loads"] = [{"boundary": "top", "value": ["t", "t"]},
                     {"boundary": "bottom", "value": ["0", "0"]}]
    scene = scene_from(data, "phase_field.epsilon=0.04", "geometry.mesh_size=0.05", "time.dt=0.01",
                       f"phase_field.alpha1={alpha1}")
    stepper = PhaseFieldStepper(scene)
    for _ in range(2):
        stepper.step(diagnose=False)
    forces = reaction_forces(stepper.u_problem, stepper.scene.loads)
    rate = ngs.Integrate(alpha1 * (stepper.u - stepper.u_prev) / scene.time.dt, stepper.mesh, order=6)
    assert np.allclose(forces["top"] + forces["bottom"], rate, rtol=1e-8, atol=1e-9 * abs(forces["top"]).max())
    assert forces["top"][1] > 0 and forces["top"][0] > 0  # pulled up and to the right
