"""The initial phase field exp(-d/epsilon) has surface energy gamma per unit crack length."""
import math

import pytest

from ngfrac.solve.stepper import PhaseFieldStepper

from ngfrac.testing.scenes import demo_data, scene_from

EPS = 0.04


def initial_record(points, gamma, order_z=2, h=EPS / 2):
    scene = scene_from(demo_data(), f"phase_field.epsilon={EPS}", f"geometry.mesh_size={h}",
                       f"material.gamma={gamma}", f"discretization.order_z={order_z}",
                       "adaptivity.enabled=false")
    scene = scene.__class__(**{**scene.__dict__, "cracks": (scene.cracks[0].__class__(points=points),)})
    return PhaseFieldStepper(scene).record()


@pytest.mark.parametrize("gamma", [1.0, 2.5])
def test_crack_across_the_plate_costs_gamma_per_length(gamma):
    # The crack meets both edges: no tips, the band is cut only at distance 0.5 >> epsilon.
    record = initial_record(((0.0, 0.5), (1.0, 0.5)), gamma)
    assert record.E_surf == pytest.approx(gamma * 1.0, rel=0.01)
    assert record.crack_length == pytest.approx(1.0, rel=0.01)


def test_interior_crack_adds_the_tip_caps():
    # Each tip adds a half disc: pi/2 * int r exp(-2r/eps)/eps dr = pi*eps/4.
    record = initial_record(((0.3, 0.5), (0.7, 0.5)), 1.0)
    assert record.crack_length == pytest.approx(0.4 + math.pi * EPS / 2, rel=0.01)


def test_oblique_polyline_crack():
    points = ((0.0, 0.2), (0.4, 0.5), (0.8, 0.5))
    record = initial_record(points, 1.0)
    length = 0.5 + 0.4
    # the kink adds a wedge of the exterior angle; bound it instead of deriving it
    assert length + math.pi * EPS / 4 <= record.crack_length * 1.01
    assert record.crack_length <= (length + math.pi * EPS / 4) * 1.05


def test_alignment_matters():
    """The kink of exp(-d/eps) on the crack is resolved only by a crack-aligned mesh."""
    from ngfrac.geometry.domains import build_mesh

    scene = scene_from(demo_data(), f"phase_field.epsilon={EPS}", f"geometry.mesh_size={EPS / 2}")
    exact = 0.3 + math.pi * EPS / 4
    errors = {}
    for aligned in (True, False):
        cracks = [c.points for c in scene.cracks] if aligned else []
        stepper = PhaseFieldStepper(scene, mesh=build_mesh(scene.geometry, EPS / 2, cracks))
        errors[aligned] = stepper.record().crack_length / exact - 1
    print(f"relative crack-length error at h = eps/2: aligned {errors[True]:+.4f}, "
          f"not aligned {errors[False]:+.4f}")
    assert abs(errors[True]) < 0.005
    assert errors[False] < -0.02
