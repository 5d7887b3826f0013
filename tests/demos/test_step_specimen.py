"""The 3D specimen from a STEP file (demos/notched_cylinder.py): the test writes the part with
netgen.occ, the scene reads it as geometry.file, and a quick run checks the elastic
stiffness of the notched bar and that the crack nucleates at the notch root."""
import math

import numpy as np
import pytest

from ngfrac.io.plotting import read_history

from .loading import DEMOS, load_demo

# P2 on the first adaptive mesh (hmax = 0.25, ~330 vertices), fixed steps of 0.1: the crack
# nucleates at t = 1.5. adaptivity.every = 1000: the adapter makes the first mesh under the
# cap and no later one, and no VTK (in 3D each remesh and each P2 snapshot cost seconds).
QUICK = ["time.dt=0.1", "time.t_end=1.7", "time.adaptive=false", "adaptivity.every=1000",
         "adaptivity.max_vertices=1000", "output.vtk_every=0"]

K_REFERENCE = 0.1768
"""The quarter bar's elastic stiffness F/u: P3 on a uniform curved mesh of h = 0.1 (181k dofs;
h = 0.4 P2: 0.1806, h = 0.2 P2: 0.1789, h = 0.2 P3: 0.1775, h = 0.1 P3: 0.17678)."""




@pytest.fixture(scope="module")
def demo():
    return load_demo("notched_cylinder")


class Bounds:
    """0 <= z <= 1 at the Lagrange nodes after every step; keeps the last stepper."""

    def __call__(self, stepper):
        self.stepper = stepper
        values = stepper.z_node_values()
        assert values.min() >= 0.0 and values.max() <= 1.0, (values.min(), values.max())


def test_the_step_file_is_the_part(demo, tmp_path):
    """The STEP file the script writes, read back, is the quarter bar with its notch."""
    from ngfrac.scene import Geometry

    path = demo.write_step_file(tmp_path / "part.step")
    domain = Geometry(kind="occ", file=str(path)).domain()
    r, length, a, w = demo.RADIUS, demo.LENGTH, demo.DEPTH, demo.OPENING
    # the notch removes a revolved triangle of area a w / 2 whose centroid lies at R - a/3
    notch = 2 * math.pi * (r - a / 3) * (a * w / 2) / 4
    assert domain.dim == 3 and domain.curved
    assert domain.measure == pytest.approx(math.pi * r ** 2 * length / 4 - notch, rel=1e-9)


def test_notched_cylinder_quick(demo, tmp_path, one_thread):
    checker = Bounds()
    out = tmp_path / "notched_cylinder"
    demo.main(out, QUICK, on_step=checker)
    history = read_history(out / "history.csv")
    stepper = checker.stepper
    scene = stepper.scene
    assert np.all(history["nv"] <= 1000)
    # Elastic stiffness at the first step (z has not moved yet). Exact bounds on the FE value:
    # above E pi (R - a)^2 / (4 L) (complementary energy of the core alone carrying the load;
    # a conforming FE solution is stiffer than the exact one) and below E |part| / L^2 (the
    # uniaxial field u = (-nu x, -nu y, z) e, in every FE space, restricted to the part).
    k = demo.initial_stiffness(history)
    bounds = demo.stiffness(scene.material.E)
    upper = scene.material.E * scene.geometry.domain().measure / demo.LENGTH ** 2
    assert bounds["lower"] < k < upper, (k, bounds, upper)
    # Against the converged value: the quick mesh is 1.4 % stiffer (measured 0.1792); 3 % is
    # twice that. The 1D closed form 1/K = int dz/(E A(z)) (0.1916) misses the notch's stress
    # concentration: the converged value is 7.7 % below it, so it is no sharper test.
    assert k == pytest.approx(K_REFERENCE, rel=0.03), k
    assert 0.88 < k / bounds["estimate"] < 0.96, k / bounds["estimate"]
    # The crack nucleates where the stress concentrates: at the notch root r = R - a, z = L/2
    # (measured: a node on the root circle, r = 0.750, z = 2.000 at t = 1.5). One epsilon.
    nucleus = stepper.nucleus
    assert nucleus is not None, "no crack nucleated"
    eps = scene.phase_field.epsilon
    radius = math.hypot(nucleus[0], nucleus[1])
    assert abs(radius - (demo.RADIUS - demo.DEPTH)) < eps and abs(nucleus[2] - demo.LENGTH / 2) < eps, \
        f"nucleus {nucleus} (r = {radius:.3f}) is not at the notch root"
