"""Tractions and pressures (``loads[i].kind``) against closed forms (z = 0, stiffness 1 + eta).

- A plate W x H on rollers (bottom, left) with a traction s on the right: uniaxial stress
  sigma_xx = s, so u_x = s x / ((1 + eta) E'), u_y = -nu' s y / ((1 + eta) E') with
  E' = E/(1 - nu^2), nu' = nu/(1 - nu) (plane strain). The solution is linear, P2 holds it,
  so the match is to solver round-off.
- A pressure p on the right is the traction -p n = (-p, 0) there: the same u.
- The reactions balance the applied traction: F_x(left) = -s H (R vanishes at the free dofs
  and a(u, 1) = 0).
"""
import numpy as np
import ngsolve as ngs
import pytest

from ngfrac.geometry.domains import build_mesh
from ngfrac.post.reactions import reaction_forces
from ngfrac.scene import SceneError
from ngfrac.solve.stepper import PhaseFieldStepper
from ngfrac.testing.scenes import demo_data, scene_from

W, H, S, ETA = 2.0, 0.5, 0.02, 1e-6
E, NU = 50.0, 0.29
ROLLERS = [{"boundary": "bottom", "value": ["free", "0"]},
           {"boundary": "left", "value": ["0", "free"]}]


def data_for(loads, kind="plane_strain"):
    data = demo_data()
    data.pop("adaptivity", None)
    data["model"]["kind"] = kind
    data["material"] = {"mu": 1.5} if kind == "mode3" else {"E": E, "nu": NU}
    data["cracks"] = []
    data["loads"] = loads
    return data


def solved(loads, kind="plane_strain", h=0.1):
    scene = scene_from(data_for(loads, kind), f"geometry.width={W}", f"geometry.height={H}",
                       f"phase_field.residual_stiffness={ETA}", "discretization.order=2")
    stepper = PhaseFieldStepper(scene, mesh=build_mesh(scene.geometry, h))
    with ngs.TaskManager():
        stepper.solve_u()
    return stepper


def displacement_at(stepper, points):
    mesh = stepper.mesh
    return np.array([stepper.u(mesh(*p)) for p in points])


POINTS = [(0.3, 0.1), (1.7, 0.45), (W, H), (1.0, 0.25)]


def uniaxial(points):
    modulus, ratio = E / (1 - NU ** 2), NU / (1 - NU)
    return np.array([[S * x, -ratio * S * y] for x, y in points]) / ((1 + ETA) * modulus)


def test_traction_gives_uniform_stress():
    stepper = solved(ROLLERS + [{"boundary": "right", "kind": "traction", "value": [f"{S}", "0"]}])
    error = np.abs(displacement_at(stepper, POINTS) - uniaxial(POINTS)).max()
    assert error < 1e-10 * S * W / E, error


def test_pressure_equals_the_traction_minus_p_n():
    pressure = solved(ROLLERS + [{"boundary": "right", "kind": "pressure", "value": f"{-S}"}])
    traction = solved(ROLLERS + [{"boundary": "right", "kind": "traction", "value": [f"{S}", "0"]}])
    difference = np.abs(pressure.u.vec.FV().NumPy() - traction.u.vec.FV().NumPy()).max()
    assert difference < 1e-12 * S * W / E, difference


def test_pressure_on_the_top_pushes_down():
    stepper = solved([{"boundary": "bottom", "value": ["0", "0"]},
                      {"boundary": "top", "kind": "pressure", "value": f"{S}"}])
    assert stepper.u(stepper.mesh(1.0, H))[1] < 0


def test_reactions_balance_the_traction():
    stepper = solved(ROLLERS + [{"boundary": "right", "kind": "traction",
                                 "value": [f"{S}*(1 + y)", f"{S}*0"]},
                                {"boundary": "top", "kind": "traction", "value": ["0", f"{S}*x"]}],
                     h=0.13)
    forces = reaction_forces(stepper.u_problem, stepper.scene.loads)
    assert set(forces) == {"bottom", "left"}  # only Dirichlet boundaries have reactions
    applied_x = S * (H + H ** 2 / 2)
    applied_y = S * W ** 2 / 2
    assert forces["left"][0] == pytest.approx(-applied_x, rel=1e-10)
    assert forces["bottom"][1] == pytest.approx(-applied_y, rel=1e-10)


def test_mode3_traction():
    # u = 0 on the bottom, shear traction tau on the top: u = tau y / ((1 + eta) mu)
    stepper = solved([{"boundary": "bottom", "value": "0"},
                      {"boundary": "top", "kind": "traction", "value": f"{S}"}], kind="mode3")
    assert stepper.u(stepper.mesh(1.3, H)) == pytest.approx(S * H / ((1 + ETA) * 1.5), rel=1e-10)


BAD = {
    "traction on a missing boundary": (
        ROLLERS + [{"boundary": "rigth", "kind": "traction", "value": ["1", "0"]}],
        r"^loads\[2\]\.boundary = 'rigth' is not a boundary of the geometry \(did you mean 'right'\?\)"),
    "traction with three components": (
        ROLLERS + [{"boundary": "right", "kind": "traction", "value": ["1", "0", "0"]}],
        r"^loads\[2\]\.value = .* has 3 entries, but model\.kind = 'plane_strain' needs 2"),
    "traction with a free component": (
        ROLLERS + [{"boundary": "right", "kind": "traction", "value": ["1", "free"]}],
        r"^loads\[2\]\.value = .* a traction gives every component"),
    "pressure with a vector value": (
        ROLLERS + [{"boundary": "right", "kind": "pressure", "value": ["1", "0"]}],
        r"^loads\[2\]\.value = .* a pressure is one expression"),
    "unknown kind": (
        ROLLERS + [{"boundary": "right", "kind": "force", "value": ["1", "0"]}],
        r"^loads\[2\]\.kind = 'force' is not allowed: choose 'displacement', 'traction', 'pressure'"),
    "only tractions": (
        [{"boundary": "right", "kind": "traction", "value": ["1", "0"]}],
        r"^loads: a scene needs at least one \[\[loads\]\] entry with kind = 'displacement'"),
    "a component prescribed nowhere": (
        [{"boundary": "bottom", "value": ["free", "0"]},
         {"boundary": "right", "kind": "traction", "value": ["1", "0"]}],
        r"^loads: ux is prescribed on no boundary"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_loads_are_refused_in_one_line(case):
    loads, message = BAD[case]
    with pytest.raises(SceneError, match=message) as err:
        scene_from(data_for(loads))
    assert "\n" not in str(err.value)


def test_mode3_pressure_is_refused():
    loads = [{"boundary": "bottom", "value": "0"}, {"boundary": "top", "kind": "pressure", "value": "1"}]
    with pytest.raises(SceneError, match=r"^loads\[1\]\.kind = 'pressure' needs a plane or 3D model"):
        scene_from(data_for(loads, kind="mode3"))


def test_crack_pressure_needs_t_only_and_a_vector_model():
    loads = [{"boundary": "bottom", "value": "0"}]
    with pytest.raises(SceneError, match=r"^phase_field\.crack_pressure = 'x\*t' is not allowed"):
        scene_from(data_for(loads, kind="mode3"), 'phase_field.crack_pressure="x*t"')
    with pytest.raises(SceneError, match=r"^phase_field\.crack_pressure = '2\*t' needs a plane"):
        scene_from(data_for(loads, kind="mode3"), 'phase_field.crack_pressure="2*t"')


# -- the pressurized crack (phase_field.crack_pressure) ----------------------------------------
def pressurized_stepper(*overrides):
    from ngfrac.testing.scenes import DEMOS

    from ngfrac.scene import apply_overrides, read_scene_data
    from ngfrac.scene import Scene

    data = apply_overrides(read_scene_data(DEMOS / "sneddon.toml"),
                           ["adaptivity.enabled=false", "geometry.origin=[-4.0, -4.0]",
                            "geometry.width=8.0", "geometry.height=8.0", "geometry.mesh_size=0.1",
                            "phase_field.epsilon=0.3", *overrides])
    stepper = PhaseFieldStepper(Scene.from_dict(data))
    return stepper, stepper.step()


def test_crack_pressure_opens_the_crack_and_its_energy_is_consistent():
    # At the u-minimizer of 1/2 a(u, u) + int p u.grad z, a(u, u) = -int p u.grad z = p V
    # (Clapeyron), so E_el = p V / 2 and E_total = E_surf - p V / 2 (z frozen by alpha2).
    from ngfrac.post.pressurized import opening_profile

    stepper, record = pressurized_stepper()
    p = 1e-3 * record.t
    assert record.crack_volume > 0
    assert "crack_volume" in record.header()
    assert record.E_el == pytest.approx(p * record.crack_volume / 2, rel=1e-5)
    assert record.E_total == pytest.approx(record.E_surf - p * record.crack_volume / 2, rel=1e-5)
    profile = opening_profile(stepper.u, stepper.z, stepper.scene.cracks[0].points,
                              3.0, stepper.domain.contains, extend=2.5)
    assert profile.w[len(profile.w) // 2] > 0
    # lines over [-2.5, 2.5] l0 and +-10 eps hold all of the band (l0 + 5 eps): int w ds = V
    assert profile.volume == pytest.approx(record.crack_volume, rel=1e-2)


def test_no_crack_pressure_no_column():
    stepper, record = pressurized_stepper('phase_field.crack_pressure="0"')
    assert "crack_volume" not in record.header()
    assert stepper.u_problem.f_u is None  # nothing assembled for the load


def test_crack_pressure_drives_z():
    # the z-source -p u.grad w is >= 0 at an opening crack: z rises faster with pressure
    # (coupling "paper": the second step's z sees the u of the first, the first u0 = 0)
    import ngsolve as ngs

    totals = []
    for p in ("0", "1e3*t"):
        stepper, _ = pressurized_stepper(f'phase_field.crack_pressure="{p}"',
                                         "phase_field.alpha2=1.0", "time.dt=0.01")
        stepper.step(diagnose=False)
        totals.append(ngs.Integrate(stepper.z, stepper.mesh))
    assert totals[1] > totals[0] * (1 + 1e-6), totals


def test_traction_in_3d_gives_uniaxial_stress():
    # a box on rollers (bottom, left, back) pulled by a traction s on the top: sigma_yy = s,
    # u_y = s y / ((1 + eta) E), u_x = -nu s x / ((1 + eta) E), exact for P2
    data = demo_data("box3d")
    data.pop("adaptivity", None)
    data["cracks"] = []
    data["material"] = {"E": E, "nu": NU}
    data["loads"] = [{"boundary": "bottom", "value": ["free", "0", "free"]},
                     {"boundary": "left", "value": ["0", "free", "free"]},
                     {"boundary": "back", "value": ["free", "free", "0"]},
                     {"boundary": "top", "kind": "traction", "value": ["0", f"{S}", "0"]}]
    scene = scene_from(data, f"phase_field.residual_stiffness={ETA}", "discretization.order=2")
    stepper = PhaseFieldStepper(scene, mesh=build_mesh(scene.geometry, 0.5))
    with ngs.TaskManager():
        stepper.solve_u()
    x, y, z = 0.7, 0.9, 0.05
    u = np.array(stepper.u(stepper.mesh(x, y, z)))
    expected = np.array([-NU * S * x, S * y, -NU * S * z]) / ((1 + ETA) * E)
    assert np.abs(u - expected).max() < 1e-10 * S / E, (u, expected)
