"""PF-CZM (Wu 2017; Wu & Nguyen 2018): the degradation and its laws against closed forms, the
optimal profile's cost, the epsilon limit, and a bar in uniaxial tension run through the
stepper: the peak is f_t at two epsilons, the elastic phase is exact, and (slow) one band
dissipates G_f times its area.

The bar: plane stress, nu = 0, E = G_f = f_t = 1 (l_ch = 1), length 1, pulled at its right end
with the left end fixed. Without a seed the state stays homogeneous (u = t x, z uniform: P1
represents it exactly), so the force over the height is the stress. Its peak is f_t: at z = 0
the drive -1/2 g'(0) W = a1 W/2 meets the constant source 2 G_f/(pi eps) at W = f_t^2/E for
every eps. The staggered step lags: z of step k uses u of step k - 1, and the force of step k
is g(z of step k - 1) E u_k, so the discrete peak overshoots by at most two increments,
2 du E/L = 1 % here; alpha2/dt = 0.02 is 500x below
G_f/eps = 10 (rate-independent).
"""
from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pytest

from ngfrac import PhaseFieldStepper, Scene
from ngfrac.physics.crack_models import CONVEX_A1, CRACK_MODELS, PFCZM, SOFTENING_LAWS
from ngfrac.scene import SceneError
from ngfrac.scene.build import crack_model_of

LAWS = tuple(SOFTENING_LAWS)
DU = 0.005
"""Load increment of the bar (its end displacement per step, L = 1)."""
START = 0.97
"""The bar's end displacement at t = 0 (elastic): the run starts just below the peak."""
H = 0.05
DU_BAND = 2.5e-4
"""Load increment of the slow band test (L = 0.1: 0.25 % of the length per step)."""


def test_pfczm_is_registered_and_built_from_the_scene():
    assert CRACK_MODELS["PF-CZM"] is PFCZM
    model = crack_model_of(bar_scene(0.1, softening="cornelissen"))
    assert isinstance(model, PFCZM) and model.softening == "cornelissen"
    assert model.l_ch == pytest.approx(1.0) and model.a1 == pytest.approx(4 / (math.pi * 0.1))
    assert model.c_w == pytest.approx(math.pi) and not model.quadratic_degradation


def test_the_three_laws_parameters():
    assert SOFTENING_LAWS["linear"] == (2.0, -0.5, 0.0)
    p, a2, a3 = SOFTENING_LAWS["exponential"]
    assert (p, a3) == (2.5, 0.0) and a2 == pytest.approx(0.1748, abs=1e-4)
    assert SOFTENING_LAWS["cornelissen"] == (2.0, 1.3868, 0.6567)


@pytest.mark.parametrize("law", LAWS)
def test_degradation_ends_and_slopes(law):
    """g(0) = 1, g(1) = 0 (+ eta), g'(0) = -a1, and g', g'' against central differences
    (step 1e-6: truncation ~1e-12 times g''', round-off ~1e-10 relative)."""
    model = PFCZM(3.0, 0.5, 2.0, 0.05, law)  # l_ch = 0.375, a1 = 9.55
    eta = 1e-6
    assert model.degradation(0.0, eta) == pytest.approx(1 + eta, rel=1e-15)
    assert model.degradation(1.0, eta) == pytest.approx(eta, rel=1e-12)
    h = 1e-6
    slope0 = (model.degradation(h, 0.0) - model.degradation(0.0, 0.0)) / h
    assert slope0 == pytest.approx(-model.a1, rel=1e-4)  # one-sided: error g''(0) h / 2
    assert model.degradation_slope(0.0) == pytest.approx(-model.a1, rel=1e-14)
    z = np.linspace(0.01, 0.98, 25)
    slope = (model.degradation(z + h, 0.0) - model.degradation(z - h, 0.0)) / (2 * h)
    np.testing.assert_allclose(model.degradation_slope(z), slope, rtol=1e-7, atol=1e-8)
    curvature = (model.degradation_slope(z + h) - model.degradation_slope(z - h)) / (2 * h)
    np.testing.assert_allclose(model.degradation_curvature(z), curvature, rtol=1e-6, atol=1e-6)
    assert np.all(np.diff(model.degradation(np.linspace(0, 1, 1001), 0.0)) < 0)  # decreasing


@pytest.mark.parametrize("law", LAWS)
def test_g_is_convex_exactly_up_to_the_epsilon_limit(law):
    """The limit is where g stops being convex on [0, 1]: a1 >= p + a2 (:data:`CONVEX_A1`;
    linear: Wu's eps <= 8 l_ch/(3 pi)). At the limit the smallest g'' is 0 (at z = 0), 2 %
    beyond it negative."""
    p, a2, _ = SOFTENING_LAWS[law]
    assert CONVEX_A1[law] == p + a2
    z = np.linspace(0.0, 0.999, 20001)
    inside = PFCZM(1.0, 1.0, 1.0, PFCZM(1.0, 1.0, 1.0, 1e-3, law).epsilon_limit(), law)
    assert inside.degradation_curvature(z).min() >= -1e-9
    beyond = PFCZM(1.0, 1.0, 1.0, 1e-3, law)
    beyond.a1 = CONVEX_A1[law] * 0.98
    assert beyond.degradation_curvature(z).min() < -1e-3
    if law == "linear":
        assert inside.epsilon_limit() == pytest.approx(8 / (3 * math.pi))


def test_the_optimal_profile_costs_one_per_unit_length():
    """w = ((2z - z^2)/eps + eps z'^2)/pi of z = 1 - sin(|x|/eps) integrates to 1 (trapezoid
    rule on 2e5 intervals: error ~1e-9; the kink at pi eps/2 is where z' = 0 already)."""
    eps = 0.07
    model = PFCZM(1.0, 1.0, 1.0, eps)
    x = np.linspace(0.0, 3 * eps, 200001)
    z = model.profile(x, eps)
    dz = np.gradient(z, x)
    density = ((2 * z - z * z) / eps + eps * dz * dz) / math.pi
    assert 2 * np.trapezoid(density, x) == pytest.approx(1.0, abs=1e-6)
    assert model.profile(np.array([math.pi * eps / 2, 1.0]), eps).tolist() == [0.0, 0.0]
    assert model.half_width(eps) == pytest.approx(eps * math.pi / 6)  # 1 - sin(pi/6) = 1/2


@pytest.mark.parametrize("law, limit", [("linear", 8 / (3 * math.pi)),
                                        ("exponential", 4 / (math.pi * (2 ** (5 / 3) - 0.5))),
                                        ("cornelissen", 4 / (math.pi * 3.3868))])
def test_epsilon_above_the_limit_is_refused(law, limit):
    eps = 1.01 * limit
    with pytest.raises(SceneError, match=rf"^phase_field\.epsilon = {eps!r} is not allowed: PF-CZM "
                                         rf"with the {law} law needs epsilon <= {limit:.4g}"):
        bar_scene(eps, softening=law)
    bar_scene(0.99 * limit, softening=law)  # below: accepted


@pytest.mark.parametrize("change, match", [
    ({"material": {"strength": None}}, r"^material\.strength is missing"),
    ({"material": {"strength": -1.0}}, r"^material\.strength = -1\.0 is not allowed"),
    ({"material": {"gamma": "1 + 0.1*x"}}, r"^material\.gamma = '1 \+ 0\.1\*x' is not allowed"),
    ({"phase_field": {"softening": "bilinear"}}, r"^phase_field\.softening = 'bilinear'"),
    ({"phase_field": {"drive": "rankine", "model": "AT2"}}, r"^phase_field\.drive = 'rankine'"),
    ({"phase_field": {"drive": "stress"}}, r"^phase_field\.drive = 'stress'"),
])
def test_bad_pfczm_input_is_one_line(change, match):
    with pytest.raises(SceneError, match=match) as info:
        bar_scene(0.1, **{k: v for k, v in change.get("phase_field", {}).items()},
                  material=change.get("material"))
    assert "\n" not in str(info.value)


def bar_scene(eps: float, softening: str = "linear", model: str = "PF-CZM",
              material: dict | None = None, drive: str = "energy", **phase_field) -> Scene:
    """The uniaxial bar of the module docstring (one row of elements: z stays uniform)."""
    mat = {"E": 1.0, "nu": 0.0, "gamma": 1.0, "strength": 1.0}
    for key, value in (material or {}).items():
        if value is None:
            mat.pop(key)
        else:
            mat[key] = value
    pf = {"epsilon": eps, "alpha2": 1e-4, "model": model, "softening": softening,
          "drive": drive, **phase_field}
    return Scene.from_dict({
        "model": {"kind": "plane_stress"}, "material": mat, "phase_field": pf,
        "geometry": {"width": 1.0, "height": H, "mesh_size": 0.05},
        "loads": [{"boundary": "left", "value": ["0", "0"]},
                  {"boundary": "right", "value": [f"{START} + t", "0"]}],
        "time": {"dt": DU, "t_end": 30 * DU}, "adaptivity": {"enabled": False},
        "output": {"vtk_every": 0}, "discretization": {"order": 1}})


@functools.lru_cache(maxsize=None)
def bar_run(eps: float, drive: str = "energy") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(end displacement, stress = force/H, largest z) per step of the bar, t = 0 included."""
    stepper = PhaseFieldStepper(bar_scene(eps, drive=drive))
    rows = [(START, stepper.forces["Fx_right"] / H, 0.0)]
    for record in stepper.run():
        rows.append((START + record.t, record.forces["Fx_right"] / H,
                     float(stepper.z_node_values().max())))
    return tuple(np.array(column) for column in zip(*rows))


@pytest.mark.parametrize("eps", [0.1, 0.05])
def test_the_bar_peaks_at_f_t_at_two_epsilons(eps):
    """Peak stress / f_t - 1 in [0, 3 %] (the issue's tolerance; the model's own peak is f_t
    exactly, the staggered step adds at most two increments, 1 %), then it softens."""
    _, stress, z = bar_run(eps)
    peak = stress.max()
    assert 0.0 <= peak - 1.0 <= 0.03, f"peak {peak:.5f} f_t at eps = {eps}"
    assert peak <= (1 + 2 * DU) * (1 + 1e-6) + 1e-12  # two increments, stiffness 1 + eta
    assert stress[-1] < peak - 0.005 and z[-1] > 0  # past the peak: softening with damage


@pytest.mark.parametrize("eps", [0.1, 0.05])
def test_the_homogeneous_softening_follows_the_closed_form(eps):
    """Linear law, homogeneous equilibrium: -1/2 g'(d) E e^2 = 2 G_f (1 - d)/(pi eps) gives
    (1 - d)^2 = (E e/f_t - a1/2)/(1 - a1/2). z of step k answers u of step k - 1; the
    linearized drive and alpha2/dt = 0.02 leave 2 % (measured: < 1 %)."""
    u, _, z = bar_run(eps)
    a1 = 4 / (math.pi * eps)
    damaged = z[1:] > 1e-3
    expected = 1 - np.sqrt((u[:-1][damaged] - a1 / 2) / (1 - a1 / 2))
    assert damaged.sum() >= 10
    np.testing.assert_allclose(z[1:][damaged], expected, rtol=0.02)


def test_the_onset_of_damage_is_at_f_t():
    """z stays exactly 0 (P1: the node values are the dofs) while the stress of the drive's u
    (the previous step's, with coupling = "paper") is below f_t (1 - 1e-3), and is positive
    at every step whose drive is above f_t (1 + 1e-3); at f_t itself (u = 1 up to
    round-off) z is 0 up to 1e-14."""
    u, _, z = bar_run(0.1)
    driving = u[:-1]  # the stress E u/L of the u of step k's drive (step k-1's), undamaged
    below, above = driving < 1.0 - 1e-3, driving > 1.0 + 1e-3
    assert below.sum() >= 5 and above.sum() >= 10
    assert np.all(z[1:][below] == 0.0)
    assert np.all(z[1:][above] > 1e-4)
    assert np.all(z[1:][~below & ~above] <= 1e-14)


def test_the_rankine_drive_equals_the_energy_drive_in_uniaxial_tension():
    """nu = 0, uniaxial stress: <sigma_1>^2/E = sigma^2/E = sigma:e, so the runs agree to
    round-off (1e-10 relative)."""
    _, energy_stress, energy_z = bar_run(0.1)
    _, rankine_stress, rankine_z = bar_run(0.1, "rankine")
    np.testing.assert_allclose(rankine_stress, energy_stress, rtol=1e-10)
    np.testing.assert_allclose(rankine_z, energy_z, rtol=1e-8, atol=1e-14)


@pytest.mark.slow
@pytest.mark.parametrize("coupling, du", [("staggered", DU_BAND), ("alternate", 16 * DU_BAND)])
def test_one_band_dissipates_g_f_times_its_area(coupling, du):
    """A bar that fails through one band dissipates G_f times its cross-section, within 5 %.

    L = 0.1 < 2 l_ch (l_ch = E G_f/f_t^2 = 0.1: no snap-back under displacement control),
    eps = 0.01 (a1 = 12.7), P2 with h = eps/4 in a strip two elements high, a z0 bump of 0.01
    (width eps) at mid-length seeds the band (the rest stays elastic). The end is pulled from
    0.9 of the peak displacement to 3 w_c/2 = 0.3 (w_c = 2 G_f/f_t, the linear law's opening),
    where the force is 1 % of its peak. Dissipated = work of the end force (trapezoid rule)
    minus the elastic energy left. The staggered scheme's error is first order in the load
    increment (measured, P1 h = eps/4: 1.21, 1.11, 1.08 G_f H at du = 2e-3, 1e-3, 5e-4 with
    coupling = "staggered"; 1.39, 1.20, 1.11 with "paper"), so that run uses du = DU_BAND
    (docs/theory.md has the measured numbers). The alternate passes remove the lag: 16 DU_BAND
    = 4e-3 gives 1.017 (staggered at 4e-3: 1.430; alternate at 2e-3: 1.014; P2, the default
    alternate_tolerance 1e-4)."""
    E, G_f, f_t, eps, length, height = 1.0, 0.1, 1.0, 0.01, 0.1, 0.005
    peak_u = f_t * length / E
    u0, u_end = 0.9 * peak_u, 1.5 * 2 * G_f / f_t
    scene = Scene.from_dict({
        "model": {"kind": "plane_stress"},
        "material": {"E": E, "nu": 0.0, "gamma": G_f, "strength": f_t},
        "phase_field": {"epsilon": eps, "alpha2": 1e-6, "model": "PF-CZM"},
        "geometry": {"width": length, "height": height, "mesh_size": eps / 4},
        "loads": [{"boundary": "left", "value": ["0", "0"]},
                  {"boundary": "right", "value": [f"{u0} + t", "0"]}],
        "time": {"dt": du, "t_end": u_end - u0},
        "adaptivity": {"enabled": False}, "output": {"vtk_every": 0},
        "discretization": {"order": 2, "order_z": 2, "coupling": coupling}})
    stepper = PhaseFieldStepper(scene)
    f = stepper.fields
    x = f.nodes.points[:, 0]
    f.nodes.assign(f.z, 0.01 * np.exp(-((x - length / 2) / eps) ** 2))
    with stepper.u_problem.static():  # u0 in equilibrium with the seed
        stepper.u_problem.solve("0")
    f.u_prev.vec.data = f.u.vec
    displacement, force = [u0], [stepper.forces["Fx_right"]]
    work_before = 0.5 * u0 * force[0]  # elastic up to u0: the seed softens it by < 1e-3
    for record in stepper.run():
        displacement.append(u0 + record.t)
        force.append(record.forces["Fx_right"])
    dissipated = work_before + np.trapezoid(force, displacement) - record.E_el
    assert max(force) / height == pytest.approx(f_t, rel=0.03)
    assert force[-1] < 0.02 * max(force), "the bar has not failed"
    assert dissipated / (G_f * height) == pytest.approx(1.0, rel=0.05)


def test_one_alternate_pass_is_the_staggered_step():
    """``coupling = "alternate"`` with ``alternate_passes = 1`` is the staggered scheme, bit
    for bit (the passes add nothing else); with passes, the bar's z of each step answers its
    own u (the homogeneous closed form at u_k, not u_{k-1}) over the first five damaged steps
    (later the passes let the uniform softening state localize, as a softening bar does):
    within 1e-5 relative, the stopping change 1e-8 at z ~ 3e-3 (measured 7.5e-8; staggered
    1.9e-2, paper 0.26)."""
    def run(**discretization):
        scene = bar_scene(0.1)
        scene = dataclasses.replace(scene, discretization=dataclasses.replace(
            scene.discretization, **discretization))
        stepper = PhaseFieldStepper(scene)
        rows = [(START + r.t, r.forces["Fx_right"], float(stepper.z_node_values().max()))
                for r in stepper.run()]
        return np.array(rows), stepper.timer.calls

    staggered, _ = run(coupling="staggered")
    one_pass, calls = run(coupling="alternate", alternate_passes=1)
    assert np.array_equal(staggered, one_pass) and "alternate: extra passes" not in calls
    settled, calls = run(coupling="alternate", alternate_tolerance=1e-8, alternate_passes=50)
    assert calls["alternate: extra passes"] > 0
    u, z = settled[:, 0], settled[:, 2]
    damaged = np.flatnonzero(z > 1e-3)[:5]
    a1 = 4 / (math.pi * 0.1)
    expected = 1 - np.sqrt((u[damaged] - a1 / 2) / (1 - a1 / 2))
    np.testing.assert_allclose(z[damaged], expected, rtol=1e-5)


@pytest.mark.parametrize("n", [2, 3])
def test_largest_principal_stress_is_the_largest_eigenvalue(n):
    """The closed forms against numpy.linalg.eigvalsh for a few symmetric matrices (1e-12)."""
    import ngsolve as ngs
    from netgen.geom2d import unit_square

    from ngfrac.physics.crack_models import largest_principal_stress

    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=1.0))
    rng = np.random.default_rng(25)
    for _ in range(5):
        a = rng.normal(size=(n, n))
        sym = a + a.T
        value = largest_principal_stress(ngs.CF(tuple(sym.ravel()), dims=(n, n)), n)(mesh(0.3, 0.3))
        assert value == pytest.approx(np.linalg.eigvalsh(sym)[-1], abs=1e-12 * np.abs(sym).max())


@pytest.mark.parametrize("drive", ["energy", "rankine"])
def test_mode3_onset_is_at_the_shear_strength(drive):
    """Mode III takes mu for E (l_ch = mu G_f/f_t^2): homogeneous shear u = (0.97 + t) y on a
    unit square (mu = 1) keeps z exactly 0 while the drive's shear stress is below f_t
    (1 - 1e-3) and damages above f_t (1 + 1e-3), with either drive (|tau|^2/mu both)."""
    scene = Scene.from_dict({
        "model": {"kind": "mode3"},
        "material": {"mu": 1.0, "gamma": 1.0, "strength": 1.0},
        "phase_field": {"epsilon": 0.1, "alpha2": 1e-4, "model": "PF-CZM", "drive": drive},
        "geometry": {"width": 1.0, "height": 1.0, "mesh_size": 0.5},
        "loads": [{"boundary": "top", "value": f"{START} + t"}, {"boundary": "bottom", "value": "0"}],
        "time": {"dt": DU, "t_end": 12 * DU}, "adaptivity": {"enabled": False},
        "output": {"vtk_every": 0}, "discretization": {"order": 1}})
    stepper = PhaseFieldStepper(scene)
    assert stepper.crack_model.young == 1.0
    driving, z = [START], []
    for record in stepper.run():
        driving.append(START + record.t)
        z.append(stepper.z_node_values().max())
    driving, z = np.array(driving[:-1]), np.array(z)
    below, above = driving < 1 - 1e-3, driving > 1 + 1e-3
    assert below.sum() >= 5 and above.sum() >= 3
    assert np.all(z[below] == 0.0) and np.all(z[above] > 1e-4)


def bent_square(order_z: int) -> Scene:
    """A unit square (plane stress, nu = 0, E = G_f = f_t = 1, eps = 0.05) on a coarse mesh
    (h = 0.25 = 5 eps, as an adaptive run's first mesh) with P2 displacements u = (0.4 x^2, 0)
    on its whole boundary: the stress varies over each element and stays below f_t."""
    return Scene.from_dict({
        "model": {"kind": "plane_stress"},
        "material": {"E": 1.0, "nu": 0.0, "gamma": 1.0, "strength": 1.0},
        "phase_field": {"epsilon": 0.05, "alpha2": 1e-4, "model": "PF-CZM", "drive": "rankine"},
        "geometry": {"width": 1.0, "height": 1.0, "mesh_size": 0.25},
        "loads": [{"boundary": b, "value": ["0.4*x*x", "0"]}
                  for b in ("left", "right", "bottom", "top")],
        "time": {"dt": 0.01, "t_end": 0.02}, "adaptivity": {"enabled": False},
        "output": {"vtk_every": 0}, "discretization": {"order": 2, "order_z": order_z}})


def largest_sigma_1(stepper: PhaseFieldStepper) -> float:
    """max sigma_1 of C:e(u) over the mesh (linear on each triangle for P2 u, sigma_1 convex:
    the maximum is at an element's vertex)."""
    import ngsolve as ngs
    from ngfrac.physics.crack_models import largest_principal_stress
    mesh, u = stepper.fields.mesh, stepper.fields.u
    sigma_1 = largest_principal_stress(stepper.model.stress(u), 2)
    corners = ngs.IntegrationRule([(0, 0), (1, 0), (0, 1)], [0, 0, 0])
    return float(np.max(sigma_1(mesh.MapToAllElements(corners, ngs.VOL))))


@pytest.mark.parametrize("order_z", [1, pytest.param(2, marks=pytest.mark.xfail(
    strict=True, reason="P2 z: the constant source has no load at the vertex nodes (a P2 "
    "vertex function integrates to 0), the drive's int W phi_v can be > 0, so the nodal "
    "obstacle lets z grow below f_t (docs/theory.md, PF-CZM)"))])
def test_elastic_phase_is_exact_under_a_non_uniform_stress(order_z):
    """Below f_t everywhere z stays exactly 0 with P1 z (hat functions >= 0: every node's
    load int (a1 W/2 - 2 G_f/(pi eps)) phi_i is < 0, so z = 0 is the obstacle problem's
    minimizer); with P2 z it does not on a coarse mesh (measured: sigma_1 <= 0.80 f_t, z up
    to 0.016 after two steps)."""
    stepper = PhaseFieldStepper(bent_square(order_z))
    for _ in stepper.run():
        assert largest_sigma_1(stepper) < 1.0
    assert stepper.z_node_values().max() == 0.0



@pytest.mark.parametrize("model, order_z, expected", [("PF-CZM", 0, 1), ("PF-CZM", 2, 2),
                                                      ("AT2", 0, 2), ("AT1", 0, 2)])
def test_z_is_p1_under_pf_czm_unless_asked(model, order_z, expected):
    """PF-CZM's default z is P1 (its elastic phase is exact only there: the test above);
    discretization.order_z = 2 still gives P2, and the AT models keep z of u's order (P2)."""
    material = {"E": 1.0, "nu": 0.0, "gamma": 1.0}
    if model == "PF-CZM":
        material["strength"] = 1.0
    scene = Scene.from_dict({
        "model": {"kind": "plane_stress"}, "material": material,
        "phase_field": {"epsilon": 0.05, "alpha2": 1e-4, "model": model},
        "geometry": {"width": 1.0, "height": 1.0, "mesh_size": 0.25},
        "loads": [{"boundary": "left", "value": ["0", "0"]}],
        "time": {"dt": 0.01, "t_end": 0.02}, "adaptivity": {"enabled": False},
        "output": {"vtk_every": 0}, "discretization": {"order": 2, "order_z": order_z}})
    assert scene.discretization.z_order_for(crack_model_of(scene)) == expected
    assert PhaseFieldStepper(scene).fields.fes_z.globalorder == expected
