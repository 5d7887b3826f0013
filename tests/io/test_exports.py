"""What a run folder exports besides history and VTK: crack_path.csv, the plots of
``ngfrac plot`` (mesh, tip path), and figures drawn without touching matplotlib's state."""
import csv
import subprocess
import sys

import numpy as np
import pytest

from ngfrac.io.plotting import plot_mesh, plot_run, read_history
from ngfrac.runner import run_scene

from ngfrac.testing.scenes import quick_slit


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    run_scene(quick_slit("time.t_end=0.003", "output.vtk_every=2"), out, overwrite=True)
    return out


def test_crack_path_csv_holds_the_tip_track(run_folder):
    history = read_history(run_folder / "history.csv")
    with (run_folder / "crack_path.csv").open(newline="") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == ["kind", "step", "t", "x", "y"]
    tips = [row for row in rows[1:] if row[0] == "tip"]
    has_tip = np.isfinite(history["tip_x"])
    assert len(tips) == int(has_tip.sum()) > 0
    np.testing.assert_array_equal([float(row[3]) for row in tips], history["tip_x"][has_tip])
    np.testing.assert_array_equal([int(row[1]) for row in tips], history["step"][has_tip])
    # 6 steps: the crack has not grown past 2 epsilon, so the final ridge is empty
    assert all(row[0] in ("tip", "ridge") for row in rows[1:])


def test_plot_adds_mesh_and_tip_path(run_folder):
    written = {path.name for path in plot_run(run_folder)}
    assert {"history.png", "mesh.png", "tip_path.png"} <= written
    for name in ("mesh.png", "tip_path.png"):
        assert (run_folder / "plots" / name).stat().st_size > 10_000, name  # not a blank image


def test_mesh_picture_of_a_3d_mesh(tmp_path):
    from netgen.csg import unit_cube
    import ngsolve as ngs

    from ngfrac.io.hdf5 import MeshArrays

    arrays = MeshArrays.of(ngs.Mesh(unit_cube.GenerateMesh(maxh=0.5)))
    png = plot_mesh(arrays.coordinates, arrays.cells, tmp_path / "mesh.png", facets=arrays.facets)
    assert png.stat().st_size > 10_000


def test_plots_leave_matplotlib_alone(run_folder):
    """Importing ngfrac imports no matplotlib; plotting neither imports pyplot nor sets a backend."""
    code = (
        "import sys, ngfrac, ngfrac.io.plotting, ngfrac.runner\n"
        "assert 'matplotlib' not in sys.modules, 'matplotlib imported at import'\n"
        "import matplotlib\n"
        "matplotlib.use('svg')\n"
        f"ngfrac.io.plotting.plot_run({str(run_folder)!r})\n"
        "assert 'matplotlib.pyplot' not in sys.modules, 'pyplot imported'\n"
        "assert matplotlib.get_backend() == 'svg', matplotlib.get_backend()\n")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
