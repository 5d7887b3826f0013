"""Run a scene into an output folder: the loop behind ``ngfrac run``.

A run folder holds ``scene.toml`` (the resolved scene), ``history.csv``, ``vtk/`` (a ``.pvd``
series), ``results.h5`` (history and field snapshots with their meshes), ``checkpoint.h5``
(written atomically every ``output.checkpoint_every`` steps), ``results.xdmf``,
``crack_path.csv`` (tip track and final ridge of z) and the plots. ``restart=True``
continues a folder from its checkpoint: rows and snapshots written after the checkpoint are
dropped, so the continued history equals an uninterrupted one.
"""
from __future__ import annotations

import logging
import time
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .checkpoint import resume, save_checkpoint
from .crackpath import crack_path_rows, final_ridge
from .fields import snapshot_fields
from .output import (HistoryWriter, OutputError, VTKSeries, atomic_write_text, prepare_output_dir,
                     to_toml)
from .plotting import plot_force_displacement, plot_history, plot_phase_field, read_history
from .results import ResultsWriter
from .scene import Scene
from .stepper import PhaseFieldStepper, StepRecord

log = logging.getLogger(__name__)

CHECKPOINT = "checkpoint.h5"


@dataclass(frozen=True)
class RunSummary:
    """What a finished run wrote and how it ended."""

    out_dir: Path
    last: StepRecord
    n_snapshots: int
    profile: str = ""
    """The per-phase timing table (see :class:`ngfrac.profiling.PhaseTimer`)."""


def write_snapshot(series: VTKSeries, stepper: PhaseFieldStepper) -> None:
    """One VTK snapshot: u, z, gamma and the derived fields of :func:`ngfrac.fields.snapshot_fields`
    (energy density, stress, estimator, element size)."""
    series.write(stepper.mesh, snapshot_fields(stepper), stepper.t)


def write_crack_path(out: Path, stepper: PhaseFieldStepper) -> Path:
    """crack_path.csv: the tip track of history.csv and the final ridge of z (2D with an
    initial crack; :func:`ngfrac.crackpath.crack_path_rows` has the layout)."""
    history = read_history(out / "history.csv")
    ridge = final_ridge(stepper.scene, stepper.mesh, stepper.z)
    header, rows = crack_path_rows(history, ridge, stepper.k, stepper.t)
    path = out / "crack_path.csv"
    with HistoryWriter(path, header) as writer:
        for row in rows:
            writer.write(row)
    return path


def write_plots(out: Path, stepper: PhaseFieldStepper) -> None:
    """history.png, crack.png (z with the tip path) and force_displacement.png (if any)."""
    import numpy as np

    plot_history(out / "history.csv", out / "history.png")
    history = read_history(out / "history.csv")
    tips = np.column_stack([history[c] for c in ("tip_x", "tip_y", "tip_z") if c in history])
    z_vertices = stepper.z_node_values()[: stepper.mesh.nv]
    plot_phase_field(stepper.mesh, z_vertices, out / "crack.png",
                     title=f"{stepper.scene.name}: z at t = {stepper.t:.4g}",
                     path=tips[np.all(np.isfinite(tips), axis=1)])
    plot_force_displacement(history, out / "force_displacement.png")


def _start(scene: Scene, out: Path, overwrite: bool, restart: bool) -> PhaseFieldStepper:
    if restart:
        checkpoint = out / CHECKPOINT
        if not checkpoint.exists():
            raise OutputError(f"no checkpoint in {str(out)!r}; a restart needs {CHECKPOINT} "
                              "(written every output.checkpoint_every steps)")
        return resume(checkpoint, scene)
    prepare_output_dir(out, overwrite)
    atomic_write_text(out / "scene.toml", to_toml(scene.to_dict()))
    return PhaseFieldStepper(scene)


def run_scene(scene: Scene, out_dir: str | Path, overwrite: bool = False,
              on_record: Callable[[StepRecord], None] | None = None,
              plots: bool = True,
              on_step: Callable[[PhaseFieldStepper], None] | None = None,
              restart: bool = False,
              on_start: Callable[[PhaseFieldStepper], None] | None = None) -> RunSummary:
    """Run ``scene`` to its end time, writing history, VTK, results, checkpoints and plots.

    Parameters
    ----------
    scene : Scene
    out_dir : path of the run folder
    overwrite : replace an earlier run in that folder (only the files ngfrac writes)
    on_record : called with every step record (the CLI's progress bar)
    plots : write history.png and crack.png at the end
    on_step : called with the stepper after set-up and after every step (for checks in tests)
    restart : continue the run in ``out_dir`` from its checkpoint
    on_start : called once with the stepper before the first step (e.g. to place a progress bar)
    """
    started = time.perf_counter()
    out = Path(out_dir)
    stepper = _start(scene, out, overwrite, restart)
    stepper.timer.add("set-up (mesh, spaces, z0, u0)", time.perf_counter() - started)
    if on_start is not None:
        on_start(stepper)
    output = scene.output
    subdivision = output.vtk_subdivision if output.vtk_subdivision >= 0 else scene.discretization.order - 1
    series = VTKSeries(out / "vtk", subdivision)
    record = stepper.record()
    if on_step is not None:
        on_step(stepper)
    with ExitStack() as stack:
        history = stack.enter_context(HistoryWriter(out / "history.csv", record.header(),
                                                    resume_after=stepper.k if restart else None))
        results = None
        if output.results:
            results = (ResultsWriter.resume(out / "results.h5", scene, stepper.k) if restart
                       else ResultsWriter(out / "results.h5", scene, overwrite=overwrite))
            stack.callback(results.close)
        if restart:
            series.resume(stepper.t)
        else:
            history.write(record.row())
            if results is not None:
                results.append(record)
            if output.vtk_every:
                write_snapshot(series, stepper)
                if results is not None:
                    results.write_snapshot(stepper)
        timer = stepper.timer
        for record in stepper.run():
            if record.has_diagnostics:
                with timer.phase("output: history"):
                    history.write(record.row())
                    if results is not None:
                        results.append(record)
            if output.vtk_every and stepper.output_due(output.vtk_every) or stepper.finished:
                with timer.phase("output: VTK and snapshots"):
                    write_snapshot(series, stepper)
                    if results is not None:
                        results.write_snapshot(stepper)
            # after the other writes, so a restart's "drop what came after k" stays consistent
            if output.checkpoint_every and record.step % output.checkpoint_every == 0:
                with timer.phase("output: checkpoint"):
                    save_checkpoint(stepper, out / CHECKPOINT)
            if on_record is not None:
                on_record(record)
            if on_step is not None:
                on_step(stepper)
    with stepper.timer.phase("output: crack path"):
        write_crack_path(out, stepper)
    if plots:
        with stepper.timer.phase("output: plots"):
            write_plots(out, stepper)
    log.info("run %s finished at t=%g in %.1f s", scene.name, record.t, record.wall_s)
    wall = time.perf_counter() - started
    return RunSummary(out, record, len(series.entries), stepper.timer.table(total=wall))
