"""Kinds are registered, not branched on: a test-only geometry kind and a test-only load kind
work through the scene by their registry entry alone, and a scene is interpreted once (one
domain, one elastic model, one crack model for every part of a run)."""
from __future__ import annotations

import pickle

import ngsolve as ngs
import pytest

from ngfrac.geometry.domains import Rectangle
from ngfrac.physics.elastic import traction_of
from ngfrac.physics.loads import LOAD_KINDS, LoadKind
from ngfrac.scene import Scene, SceneError
from ngfrac.scene.build import crack_model_of, elastic_model_of
from ngfrac.scene.geometry_section import GEOMETRY_KINDS, RectangleKind
from ngfrac.testing.scenes import quick_slit


class SquareKind(RectangleKind):
    """A test-only ``geometry.kind = "square"``: a rectangle of side ``width``."""

    name = "square"
    choice = "'square' (a test kind)"
    required_keys = ("width",)

    def validate(self, geometry):
        if geometry.height == geometry.height:  # given (not NaN)
            raise SceneError("geometry.height: a square takes width only")

    def domain(self, geometry):
        return Rectangle(geometry.width, geometry.width, tuple(geometry.origin))


class NormalShear(LoadKind):
    """A test-only ``loads[i].kind = "shear"``: one expression s, the traction s (n_y, -n_x)."""

    name = "shear"
    scalar = True

    def value_problem(self, value):
        return ([str(e) for e in value], "a shear is one expression") if isinstance(value, tuple) else None

    def model_problem(self, model_kind, n_components):
        return None if n_components == 2 else "needs a plane model"

    def traction(self, value, mesh, t):
        n = ngs.specialcf.normal(mesh.dim)
        return value.to_coefficient(t) * ngs.CoefficientFunction((n[1], -n[0]))


def plane_scene(loads, **geometry):
    return Scene.from_dict({
        "model": {"kind": "plane_strain"}, "material": {"lam": 1.0, "mu": 1.0},
        "phase_field": {"epsilon": 0.1, "alpha2": 1.0},
        "geometry": {"width": 1.0, **geometry}, "time": {"dt": 0.1, "t_end": 0.2},
        "loads": [{"boundary": "bottom", "value": ["0", "0"]}, *loads]})


def test_a_registered_geometry_kind_needs_no_other_change(monkeypatch):
    monkeypatch.setitem(GEOMETRY_KINDS, "square", SquareKind())
    scene = plane_scene([], kind="square")
    domain = scene.geometry.domain()
    assert (domain.width, domain.height) == (1.0, 1.0) and scene.geometry.dim == 2
    assert scene.geometry.boundary_names == ("bottom", "right", "top", "left")
    with pytest.raises(SceneError, match="a square takes width only"):
        plane_scene([], kind="square", height=2.0)
    with pytest.raises(SceneError, match=r"choose .*'occ' \(CAD shapes or a file\) or 'square'"):
        plane_scene([], kind="sqare")


def test_a_registered_load_kind_needs_no_other_change(monkeypatch):
    monkeypatch.setitem(LOAD_KINDS, "shear", NormalShear())
    scene = plane_scene([{"boundary": "top", "kind": "shear", "value": "2*t"}], height=1.0)
    load = scene.loads[1]
    assert not load.is_dirichlet and load.free == (True,)
    mesh = ngs.Mesh(scene.geometry.domain().netgen_geometry().GenerateMesh(maxh=0.5))
    t = ngs.Parameter(1.0)
    force = ngs.Integrate(traction_of(load, mesh, t), mesh, definedon=mesh.Boundaries("top"))
    assert force[0] == pytest.approx(2.0) and force[1] == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(SceneError, match=r"loads\[1\]\.value = \['1', '2'\] is not allowed: a shear is"):
        plane_scene([{"boundary": "top", "kind": "shear", "value": ["1", "2"]}], height=1.0)
    with pytest.raises(SceneError, match="choose 'displacement', 'traction', 'pressure', 'shear'"):
        plane_scene([{"boundary": "top", "kind": "sheer", "value": "1"}], height=1.0)


def test_the_scene_is_interpreted_once():
    """One domain, one elastic model and one crack model per scene, whoever asks; copies and
    pickles leave them out and build their own."""
    from ngfrac.mesh.adapter import MeshAdapter
    from ngfrac.solve.stepper import PhaseFieldStepper

    scene = quick_slit("time.t_end=0.0001")
    stepper = PhaseFieldStepper(scene)
    adapter = MeshAdapter(scene)
    assert stepper.domain is scene.geometry.domain() is adapter.domain
    assert stepper.model is elastic_model_of(scene) is scene.elastic_model
    assert stepper.crack_model is crack_model_of(scene) is adapter.crack_model
    copy = pickle.loads(pickle.dumps(scene))
    assert copy.to_dict() == scene.to_dict() and "crack_model" not in copy.__dict__
    assert copy.crack_model is not scene.crack_model
    assert type(copy.crack_model) is type(scene.crack_model)
