"""Elastic models: moduli, the scene spelling of vector loads, per-component Dirichlet data."""
import copy

import numpy as np
import ngsolve as ngs
import pytest

from ngfrac.geometry.domains import build_mesh
from ngfrac.physics.elastic import AntiPlane, PlaneStrain, PlaneStress
from ngfrac.scene.build import elastic_model_of
from ngfrac.io.output import to_toml
from ngfrac.scene import Material, Scene, SceneError, load_scene

from ngfrac.testing.scenes import demo_data


def plane_data(kind="plane_strain"):
    """The slit demo as a plane model: E = 50, nu = 0.29, top pulled up, bottom on rollers."""
    data = demo_data()
    data.pop("adaptivity", None)  # a uniform mesh
    data["model"]["kind"] = kind
    data["material"] = {"E": 50.0, "nu": 0.29, "gamma": 1.0}
    data["loads"] = [{"boundary": "top", "value": ["0", "10*t"]},
                     {"boundary": "bottom", "value": ["free", "0"]}]
    return data


def build(data):
    """Validate a scene and its model (which checks what spans sections)."""
    scene = Scene.from_dict(data)
    return scene, elastic_model_of(scene)


def bad(data, match):
    with pytest.raises(SceneError, match=match) as info:
        build(data)
    assert "\n" not in str(info.value)
    return str(info.value)


def test_paper_moduli_give_the_3d_lame_constants():
    lam, mu = Material(E=50.0, nu=0.29).lame
    assert lam == pytest.approx(26.76, abs=5e-3) and mu == pytest.approx(19.38, abs=5e-3)
    _, model = build(plane_data())
    assert isinstance(model, PlaneStrain) and (model.lam, model.mu) == (lam, mu)


def test_plane_stress_uses_lambda_star():
    lam, mu = Material(E=50.0, nu=0.29).lame
    _, model = build(plane_data("plane_stress"))
    assert isinstance(model, PlaneStress)
    assert model.lam == pytest.approx(2 * lam * mu / (lam + 2 * mu), rel=1e-14)
    # lambda* is what makes the 2D uniaxial-stress modulus equal E
    assert 4 * model.mu * (model.lam + model.mu) / (model.lam + 2 * model.mu) == pytest.approx(50.0)


def test_lam_and_mu_are_taken_as_given():
    data = plane_data()
    data["material"] = {"lam": 121.15, "mu": 80.77}
    _, model = build(data)
    assert (model.lam, model.mu) == (121.15, 80.77)


def test_mode3_keeps_mu_and_its_default():
    scene, model = build(demo_data())
    assert isinstance(model, AntiPlane) and model.mu == scene.material.mu == 1.0
    data = demo_data()
    del data["material"]["mu"]
    _, model = build(data)
    assert model.mu == Material.DEFAULT_MU
    data["material"].update(E=2.6, nu=0.3)
    assert build(data)[1].mu == pytest.approx(1.0)


@pytest.mark.parametrize("moduli, match", [
    ({"E": 50.0, "nu": 0.29, "mu": 19.38}, r"material.mu = 19.38, material.E = 50.0, material.nu = 0.29 "
                                           r"is not allowed: give exactly one pair"),
    ({"E": 50.0}, r"material.E = 50.0 is not allowed: give exactly one pair of elastic moduli, lam and mu"),
    ({"lam": 1.0}, r"material.lam = 1.0 is not allowed"),
    ({"E": 50.0, "nu": 0.5}, r"material.nu = 0.5 is not allowed: Poisson's ratio must be in \(-1, 0.5\)"),
    ({"E": -1.0, "nu": 0.3}, r"material.E = -1.0 .*must be > 0"),
    ({"lam": -20.0, "mu": 15.0}, r"material.lam = -20.0 .*must be > -2 mu/3 = -10"),
    ({"mu": 0.0, "lam": 1.0}, r"material.mu = 0.0 .*must be > 0"),
])
def test_moduli_must_be_one_valid_pair(moduli, match):
    data = plane_data()
    data["material"] = moduli
    bad(data, match)


def test_plane_model_refuses_mu_alone():
    data = plane_data()
    data["material"] = {"mu": 1.0}
    bad(data, r"model.kind = 'plane_strain' needs the elastic moduli lam and mu, or E and nu "
              r"\(given: mu\)")


def test_unknown_kind_suggests_a_plane_model():
    data = plane_data()
    data["model"]["kind"] = "plane_strian"
    bad(data, r"did you mean 'plane_strain'")


@pytest.mark.parametrize("value, match", [
    ("10*t", r"loads\[0\].value = '10\*t' is one expression, but model.kind = 'plane_strain' needs \[ux, uy\]"),
    (["0", "t", "0"], r"loads\[0\].value = \[\"0\", \"t\", \"0\"\] has 3 entries, .* needs 2"),
    (["free", "free"], r"loads\[0\].value = .* every component is free"),
    (["0", "t +"], r"loads\[0\].value\[1\]: cannot parse expression 't \+'"),
    (["0", "fre"], r"loads\[0\].value\[1\]: .*unknown name 'fre'"),
    (["0", 1], None),
])
def test_vector_load_spelling(value, match):
    data = plane_data()
    data["loads"][0]["value"] = value
    if match is None:
        scene, _ = build(data)
        assert scene.loads[0].value[1].value() == 1.0
    else:
        bad(data, match)


def test_mode3_load_must_be_one_expression():
    data = demo_data()
    data["loads"][0]["value"] = ["0", "10*t"]
    bad(data, r"loads\[0\].value = .* is a list, but model.kind = 'mode3' takes one expression")


@pytest.mark.parametrize("kind, force, match", [
    ("plane_strain", "1.0", r"material.body_force = '1.0' is one expression, .* needs \[fx, fy\]"),
    ("plane_strain", ["0", "free"], r"material.body_force = .*none 'free'"),
    ("plane_strain", ["0", "-1", "0"], r"material.body_force = .* has 3 entries"),
    ("mode3", ["0", "-1"], r"material.body_force = .* is a list, but model.kind = 'mode3'"),
])
def test_body_force_shape_follows_the_model(kind, force, match):
    data = plane_data() if kind != "mode3" else demo_data()
    data["material"]["body_force"] = force
    bad(data, match)


def test_vector_scene_round_trips_through_toml(tmp_path):
    data = plane_data()
    data["material"]["body_force"] = ["0", "-9.81"]
    scene, _ = build(data)
    text = to_toml(scene.to_dict())
    assert "lam =" not in text and "mu =" not in text  # moduli not given stay out
    path = tmp_path / "scene.toml"
    path.write_text(text)
    assert load_scene(path) == scene
    assert copy.deepcopy(load_scene(path).to_dict()) == scene.to_dict()


# -- the model on a mesh -----------------------------------------------------------------------
@pytest.fixture(scope="module")
def mesh():
    from ngfrac.scene import Geometry
    return build_mesh(Geometry(width=1.0, height=1.0), 0.25)


def rollers_model():
    data = plane_data()
    data["loads"] = [{"boundary": "left", "value": ["3 + y", "free"]},
                     {"boundary": "bottom", "value": ["free", "4 + x**3"]}]
    return build(data)


def test_dirichlet_per_component(mesh):
    scene, model = rollers_model()
    fes = model.space(mesh, 3, scene.loads)
    x_fixed, y_fixed = (np.count_nonzero(~np.array(c.FreeDofs(), dtype=bool)) for c in fes.components)
    assert x_fixed == y_fixed == 13  # one edge of 4 segments at order 3: 5 vertices + 4*2 edge dofs
    assert np.count_nonzero(~np.array(fes.FreeDofs(), dtype=bool)) == 26


def test_boundary_values_do_not_leak_into_free_components(mesh):
    """At the roller corner (0, 0) ux comes from the left edge and uy from the bottom edge."""
    scene, model = rollers_model()
    fes = model.space(mesh, 3, scene.loads)
    gf = ngs.GridFunction(fes)
    model.set_boundary(gf, model.boundary_values(mesh, scene.loads, ngs.Parameter(0.0)))
    assert np.allclose(gf(mesh(0.0, 0.0)), (3.0, 4.0))
    assert np.allclose(gf(mesh(0.0, 0.5)), (3.5, 0.0))    # uy on the left edge is free: untouched
    assert np.allclose(gf(mesh(0.5, 0.0)), (0.0, 4.125))  # x**3 is exact at order 3


def test_stress_strain_of_a_linear_field(mesh):
    """u = (a x, b y): sigma:e = 2 mu (a^2 + b^2) + lam (a + b)^2, and sigma = 2 mu e + lam tr(e) I."""
    _, model = build(plane_data())
    a, b = 0.3, -0.7
    gf = ngs.GridFunction(ngs.VectorH1(mesh, order=1))
    gf.Set(ngs.CoefficientFunction((a * ngs.x, b * ngs.y)))
    lam, mu = model.lam, model.mu
    assert ngs.Integrate(model.energy_density(gf), mesh) == pytest.approx(
        2 * mu * (a * a + b * b) + lam * (a + b) ** 2, rel=1e-12)
    sigma = np.array(model.stress(gf)(mesh(0.4, 0.6))).reshape(2, 2)
    expected = np.diag([2 * mu * a + lam * (a + b), 2 * mu * b + lam * (a + b)])
    assert np.allclose(sigma, expected, atol=1e-12)


def test_body_force_shape(mesh):
    data = plane_data()
    t = ngs.Parameter(2.0)
    assert build(data)[1].body_force(Scene.from_dict(data).material, t) is None
    data["material"]["body_force"] = ["0", "-t"]
    scene, model = build(data)
    force = model.body_force(scene.material, t)
    assert force.dim == 2 and np.allclose(force(mesh(0.5, 0.5)), (0.0, -2.0))
