"""Run a scene into an output folder: the loop behind ``ngfrac run``."""
from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .output import HistoryWriter, VTKSeries, atomic_write_text, prepare_output_dir, to_toml
from .plotting import plot_history, plot_phase_field
from .scene import Scene
from .stepper import PhaseFieldStepper, StepRecord

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RunSummary:
    """What a finished run wrote and how it ended."""

    out_dir: Path
    last: StepRecord
    n_snapshots: int


def write_snapshot(series: VTKSeries, stepper: PhaseFieldStepper) -> None:
    """One VTK snapshot of u, z and gamma."""
    import ngsolve as ngs

    gamma = stepper.gamma if not isinstance(stepper.gamma, float) else ngs.CoefficientFunction(stepper.gamma)
    series.write(stepper.mesh, {"u": stepper.u, "z": stepper.z, "gamma": gamma}, stepper.t)


def run_scene(scene: Scene, out_dir: str | Path, overwrite: bool = False,
              on_record: Callable[[StepRecord], None] | None = None,
              plots: bool = True,
              on_step: Callable[[PhaseFieldStepper], None] | None = None) -> RunSummary:
    """Run ``scene`` to its end time, writing history, VTK, the scene copy and plots.

    Parameters
    ----------
    scene : Scene
    out_dir : path of the run folder
    overwrite : replace an earlier run in that folder
    on_record : called with every step record (the CLI's progress bar)
    plots : write history.png and crack.png at the end
    on_step : called with the stepper after set-up and after every step (for checks in tests)
    """
    out = prepare_output_dir(out_dir, overwrite)
    atomic_write_text(out / "scene.toml", to_toml(scene.to_dict()))
    stepper = PhaseFieldStepper(scene)
    subdivision = scene.output.vtk_subdivision
    if subdivision < 0:
        subdivision = scene.discretization.order - 1
    series = VTKSeries(out / "vtk", subdivision)
    vtk_every = scene.output.vtk_every
    record = stepper.record()
    if on_step is not None:
        on_step(stepper)
    with HistoryWriter(out / "history.csv", record.header()) as history:
        history.write(record.row())
        if vtk_every:
            write_snapshot(series, stepper)
        for record in stepper.run():
            if record.has_diagnostics:
                history.write(record.row())
            last = record.step == stepper.n_steps
            if (vtk_every and record.step % vtk_every == 0) or last:
                write_snapshot(series, stepper)
            if on_record is not None:
                on_record(record)
            if on_step is not None:
                on_step(stepper)
    if plots:
        plot_history(out / "history.csv", out / "history.png")
        z_vertices = stepper.z_node_values()[: stepper.mesh.nv]
        plot_phase_field(stepper.mesh, z_vertices, out / "crack.png",
                         title=f"{scene.name}: z at t = {stepper.t:.4g}")
    log.info("run %s finished at t=%g in %.1f s", scene.name, record.t, record.wall_s)
    return RunSummary(out, record, len(series.entries))
