"""A newcomer's first day (issue 28): what the command line says and what the run folder
shows. One tiny run (SI units, 9 steps of 1e-4) is shared by most checks."""
import csv
import logging
from pathlib import Path

import h5py
import numpy as np
import pytest

from ngfrac import cli
from ngfrac.io.plotting import (force_displacement_curves, force_displacement_figure,
                                history_figure, read_history)
from ngfrac.scene.units import UNIT_SYSTEMS, column_units

pytestmark = pytest.mark.usefixtures("one_thread")

ROOT = Path(__file__).resolve().parents[2]
SLIT = str(ROOT / "demos" / "mode3_slit.toml")
TINY = ["--set", "phase_field.epsilon=0.08", "--set", "geometry.mesh_size=0.04",
        "--set", "adaptivity.enabled=false", "--set", "discretization.order=1",
        "--set", "time.dt=1e-4", "--set", "time.t_end=0.0009", "--set", 'units="SI"',
        "--no-progress"]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """The folder of a finished tiny run and the lines ``ngfrac run`` printed."""
    import contextlib
    import io

    out = tmp_path_factory.mktemp("first_day") / "run"
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        code = cli.main(["run", SLIT, "--out", str(out), *TINY])
    assert code == 0
    return out, stdout.getvalue()


def rows(out):
    with (out / "history.csv").open() as handle:
        return list(csv.DictReader(handle))


def one_error_line(capsys, code, expected_code=2):
    err = capsys.readouterr().err
    assert code == expected_code, err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    return err


# -- item 6: which crack length -----------------------------------------------------------------
def test_summary_shows_the_geometric_length_first(run):
    out, printed = run
    last = rows(out)[-1]
    line = printed.strip().splitlines()[-1]
    geometric = f"crack path length {float(last['path_length']):.4f}"
    functional = f"Gamma-functional crack length {float(last['crack_length']):.4f}"
    assert geometric in line and functional in line, line
    assert line.index(geometric) < line.index(functional)


def test_history_figure_names_the_functional_after_the_geometric_length(run):
    out, _ = run
    figure = history_figure(read_history(out / "history.csv"), "SI")
    crack_axes = figure.axes[1]
    labels = [line.get_label() for line in crack_axes.get_lines()]
    assert labels[0] == "crack path length (geometric)"
    assert labels[1].startswith("Γ-functional crack length"), labels
    assert crack_axes.get_ylabel().endswith("[m]")
    assert figure.axes[0].get_ylabel() == "energy [J/m]"  # 2D: per unit thickness


# -- item 7: force against displacement of the boundaries that move ------------------------------
def test_force_displacement_leaves_out_held_boundaries():
    t = np.linspace(0, 1, 5)
    history = {"t": t, "Fy_bottom": -3 * t, "uy_bottom": 0 * t, "Fy_top": 3 * t, "uy_top": t,
               "Fx_top": 0 * t, "ux_top": 0 * t}
    assert force_displacement_curves(history) == [("uy_top", "Fy_top")]
    held_only = {"t": t, "Fy_bottom": -3 * t, "uy_bottom": 0 * t}  # a traction pulls elsewhere
    assert force_displacement_curves(held_only) == [("t", "Fy_bottom")]
    figure = force_displacement_figure(history, "mm-kN-GPa")
    (axes,) = figure.axes
    assert [line.get_label() for line in axes.get_lines()] == ["Fy_top against uy_top"]
    assert axes.get_ylabel() == "reaction force [kN/mm]"
    assert axes.get_xlabel() == "mean displacement of the boundary [mm]"
    assert force_displacement_figure({"t": t, "Fy_a": 0 * t, "uy_a": t}) is None


# -- item 8: units ------------------------------------------------------------------------------
def test_results_h5_names_the_units(run):
    out, _ = run
    with h5py.File(out / "results.h5") as f:
        assert f.attrs["units"] == "SI"
        columns = [str(c) for c in f["history"].attrs["columns"]]
        units = dict(zip(columns, (str(u) for u in f["history"].attrs["units"])))
        last = f["snapshots"][sorted(f["snapshots"])[-1]]
        assert last["mesh/coordinates"].attrs["units"] == "m"
        assert last["vertex_values/u"].attrs["units"] == "m"
    assert units["E_el"] == "J/m" and units["crack_length"] == "m" and units["wall_s"] == "s"
    assert units["Fz_top"] == "N/m" and units["uz_top"] == "m"  # mode III: per unit thickness
    assert units["t"] == "" and units["nv"] == ""


def test_unit_systems_are_consistent():
    """E in stress units times a length² is a force; gamma = force/length."""
    for name, system in UNIT_SYSTEMS.items():
        units = column_units(["F_a", "E_el", "crack_volume"], system, 3)
        if system.known:
            assert units == [system.force_unit, system.energy_unit, f"{system.length}³"]
        else:
            assert all(u == "scene units" for u in units)
    assert column_units(["Fx_top"], UNIT_SYSTEMS["scene units"], 2) == [
        "scene units, per unit thickness"]


def test_unknown_unit_system_is_one_line(capsys):
    err = one_error_line(capsys, cli.main(["check", SLIT, "--set", 'units="furlong"']))
    assert "units = 'furlong' is not allowed" in err and "'SI'" in err


# -- item 10: the smaller ones ------------------------------------------------------------------
def test_times_are_written_as_the_scene_meant_them(run):
    out, _ = run
    times = [row["t"] for row in rows(out)]
    assert times[-1] == "0.0009"  # 9 * 1e-4 is 0.0009000000000000001 as a product of floats
    assert all(float(t) == float(f"{k * 1e-4:.15g}") for k, t in enumerate(times))


def test_plot_times_beyond_the_run_are_refused(run, capsys):
    out, _ = run
    err = one_error_line(capsys, cli.main(["plot", str(out), "--times", "0.1"]))
    assert "--times 0.1 is outside the run's snapshots (t = 0 to 0.0009)" in err


def test_check_of_a_folder_says_it_is_a_folder(run, capsys):
    out, _ = run
    err = one_error_line(capsys, cli.main(["check", str(out)]))
    assert "is a folder, not a scene file" in err and f"--restart {out}" in err
    assert "does not exist" not in err


def test_restart_of_a_missing_folder_names_the_folder(tmp_path, capsys):
    err = one_error_line(capsys, cli.main(["run", "--restart", str(tmp_path / "nothere")]))
    assert "no such run folder" in err and "scene.toml" not in err


def test_no_plots_help_names_every_plot():
    parser = cli.build_parser()
    run_parser = parser._subparsers._group_actions[0].choices["run"]
    (action,) = [a for a in run_parser._actions if "--no-plots" in a.option_strings]
    assert "force_displacement.png" in action.help


def test_interrupted_run_says_how_to_continue(run, capsys, monkeypatch):
    import ngfrac.runner

    out, _ = run

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(ngfrac.runner, "run_scene", interrupted)
    err = one_error_line(capsys, cli.main(["run", "--restart", str(out), "--set",
                                           "time.t_end=0.002", "--no-progress"]), 130)
    assert f"ngfrac run --restart {out} continues from step 9 (t = 0.0009)" in err


def test_vtk_series_takes_a_folder_name(tmp_path):
    import ngsolve as ngs

    from ngfrac.io.output import VTKSeries

    series = VTKSeries(str(tmp_path / "vtk"), 1)  # the guide's example passes a str
    mesh = ngs.Mesh(ngs.unit_square.GenerateMesh(maxh=0.5))
    written = series.write(mesh, {"x": ngs.x}, 0.0)
    assert written.exists() and (tmp_path / "vtk" / "fields.pvd").exists()


def test_transfer_warning_says_what_it_measures(caplog):
    import ngsolve as ngs

    from ngfrac.mesh.transfer import locate

    mesh = ngs.Mesh(ngs.unit_square.GenerateMesh(maxh=0.5))
    with caplog.at_level(logging.WARNING):
        locate(mesh, np.array([[0.5, 0.5], [1.01, 0.5]]))
    (message,) = [r.getMessage() for r in caplog.records]
    assert message.startswith("1 of 2 points lie outside the old mesh; they take the value at "
                              "the nearest old vertex (up to ")


# -- item 9: alpha2 ------------------------------------------------------------------------------
def test_check_warns_when_alpha2_makes_the_run_rate_dependent(capsys):
    from ngfrac.scene.rates import rate_ratio, suggested_alpha2
    from ngfrac.testing.scenes import quick_slit

    assert cli.main(["check", SLIT]) == 0
    assert "alpha2" not in capsys.readouterr().err  # the demo: ratio 0.04
    assert cli.main(["check", SLIT, "--set", "phase_field.alpha2=1.0", "--strict"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["ngfrac: warning: phase_field.alpha2 = 1: alpha2/dt = 2e+03 is 40 times "
                   "gamma/epsilon = 50, so z lags the load (rate dependent); for a quasi-static "
                   "crack keep alpha2/dt well below gamma/epsilon, e.g. alpha2 = 0.00025 (user "
                   "guide, 'Choosing alpha2')"]
    scene = quick_slit('material.gamma="1 + 0.5*x"')  # gamma varies: its minimum counts
    assert rate_ratio(scene) == pytest.approx((1e-3 / 5e-4) / (1.0 / 0.04))
    assert suggested_alpha2(scene) == pytest.approx(0.01 * 5e-4 * 1.0 / 0.04)
