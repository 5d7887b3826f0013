"""Every demo runs in a quick mode and shows one physical fact; z keeps its bounds."""
import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from ngfrac.plotting import read_history

ROOT = Path(__file__).resolve().parents[2]
DEMOS = ROOT / "demos"
QUICK = ["phase_field.epsilon=0.04", "geometry.mesh_size=0.02", "output.vtk_every=50",
         "time.dt=1e-3", "adaptivity.max_vertices=2000"]


def load_demo(name):
    if str(DEMOS) not in sys.path:
        sys.path.insert(0, str(DEMOS))  # the scripts import their shared _common.py
    spec = importlib.util.spec_from_file_location(f"demo_{name}", DEMOS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class BoundsChecker:
    """Checks 0 <= z <= 1 and, on an unchanged mesh, z^k >= z^{k-1} at every Lagrange node."""

    def __init__(self):
        self.previous = None
        self.mesh = None
        self.steps = 0

    def __call__(self, stepper):
        values = stepper.z_node_values()
        assert values.min() >= 0.0 and values.max() <= 1.0, (values.min(), values.max())
        if stepper.mesh is not self.mesh:  # a new mesh: transfers are checked in test_adaptive_run
            self.previous, self.mesh = None, stepper.mesh
        if self.previous is not None:
            decrease = np.max(self.previous - values)
            assert decrease <= 0.0, f"z decreased by {decrease} at step {stepper.k}"
            self.steps += 1
        self.previous = values


def run_quick(name, tmp_path):
    checker = BoundsChecker()
    load_demo(name).main(tmp_path / name, QUICK, on_step=checker)
    assert checker.steps > 50
    out = tmp_path / name
    for produced in ("history.csv", "history.png", "crack.png", "scene.toml", "vtk/fields.pvd"):
        assert (out / produced).exists(), produced
    read_back_independently(out)
    return read_history(out / "history.csv")


def read_back_independently(out):
    """Every VTK file of the .pvd series opens in meshio; results.h5 opens in plain h5py."""
    import xml.etree.ElementTree as ET

    import h5py
    import meshio

    files = [d.get("file") for d in ET.parse(out / "vtk" / "fields.pvd").getroot().iter("DataSet")]
    assert files
    for name in files:
        mesh = meshio.read(out / "vtk" / name)
        assert "z" in mesh.point_data and np.all(np.isfinite(mesh.point_data["z"]))
    with h5py.File(out / "results.h5", "r") as f:
        assert f["history"].shape[0] > 0 and len(f["snapshots"]) >= 1


def check_slit(history):
    # Fig. 2: the crack runs straight across to the right edge.
    assert np.nanmax(history["tip_x"]) > 0.97, np.nanmax(history["tip_x"])
    assert np.nanmax(np.abs(history["tip_y"] - 0.5)) < 0.1


def check_stripes(history):
    # Fig. 4: the weak stripes draw the crack off the slit's straight line.
    assert np.nanmax(history["tip_x"]) > 0.5
    deviation = np.nanmax(np.abs(history["tip_y"] - 0.5))
    assert deviation > 0.05, f"tip stayed within {deviation:.3f} of the slit's line"


CHECKS = {"mode3_slit": check_slit, "mode3_stripes": check_stripes}


def test_every_demo_has_a_test():
    scenes = {path.stem for path in DEMOS.glob("*.toml")}
    scripts = {path.stem for path in DEMOS.glob("*.py") if not path.stem.startswith("_")}
    assert scenes == set(CHECKS), f"demos without a physics check: {scenes - set(CHECKS)}"
    assert scripts == scenes, f"scenes and scripts differ: {scenes ^ scripts}"


@pytest.mark.parametrize("name", sorted(CHECKS))
def test_demo_quick(name, tmp_path):
    CHECKS[name](run_quick(name, tmp_path))
