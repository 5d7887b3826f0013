"""AT1 (phase_field.model = "AT1"): its optimal profile costs gamma per unit length, and a
homogeneous state stays undamaged below the strength sigma_c = sqrt(3 mu gamma / (8 eps))."""
import math

import pytest

from ngfrac import PhaseFieldStepper, Scene

EPS = 0.05


def scene(model: str, mesh_size: float, crack: bool, top: str, steps: int = 5, order: int = 2) -> Scene:
    return Scene.from_dict({
        "name": "at1", "model": {"kind": "mode3"}, "material": {"mu": 1.0, "gamma": 1.0},
        "phase_field": {"epsilon": EPS, "alpha2": 1e-3, "model": model},
        "geometry": {"width": 1.0, "height": 1.0, "mesh_size": mesh_size},
        "cracks": [{"points": [[0.0, 0.5], [1.0, 0.5]]}] if crack else [],
        "loads": [{"boundary": "bottom", "value": "0"}, {"boundary": "top", "value": top}],
        "time": {"dt": 1.0 / steps, "t_end": 1.0}, "discretization": {"order": order},
        "adaptivity": {"enabled": False}, "output": {"vtk_every": 0}})


@pytest.mark.parametrize("model", ["AT1", "AT2"])
def test_the_optimal_profile_costs_gamma_per_unit_length(model):
    """A crack across the unit square, on a mesh that has it as edges, P2 z at h = eps/5:
    the surface energy is gamma * 1 (measured: 1 - 2e-6 for AT1, 1 + 8e-7 for AT2; the issue
    asks for 1 %)."""
    record = PhaseFieldStepper(scene(model, EPS / 5, crack=True, top="0")).record()
    assert record.E_surf == pytest.approx(1.0, rel=1e-2)
    assert record.crack_length == pytest.approx(1.0, rel=1e-2)


@pytest.mark.parametrize("factor, damaged", [(0.95, False), (1.05, True)])
def test_no_damage_below_the_strength(factor, damaged):
    """Simple shear u = Delta y (exact for P1: u = 0 below, Delta above, free sides), held for
    5 steps: the drive W = mu Delta^2 is uniform, and the z-step's source -3 gamma/(8 eps)
    outweighs it below sigma_c (z stays exactly 0), not above (z grows everywhere)."""
    sigma_c = math.sqrt(3 * 1.0 * 1.0 / (8 * EPS))
    stepper = PhaseFieldStepper(scene("AT1", 0.05, crack=False, top=f"{factor * sigma_c}", order=1))
    for _ in stepper.run():
        pass
    z = stepper.z_node_values()
    if damaged:
        assert z.min() > 0.0
    else:
        assert z.max() == 0.0
