"""Run a scene into an output folder: the loop behind ``ngfrac run``.

A run folder holds ``scene.toml`` (the resolved scene), ``run.json`` (versions, git commit,
threads, command line, start time and the restarts), ``manifest.json`` (every file ngfrac
wrote there), ``history.csv``, ``vtk/`` (a ``.pvd`` series), ``results.h5`` (history and field
snapshots with their meshes), ``checkpoint.h5`` (written atomically every
``output.checkpoint_every`` steps), ``results.xdmf``, ``crack_path.csv`` (tip track and final
ridge of z) and the plots. ``restart=True`` continues a folder from its
checkpoint: rows and snapshots written after the checkpoint are dropped, so the continued
history equals an uninterrupted one; a changed scene (``time.t_end``, ``[output]``) replaces
``scene.toml`` and the restart is appended to ``run.json``.
"""
from __future__ import annotations

import contextlib
import json
import logging
import math
import time
import tomllib
import warnings
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from .io.checkpoint import resume, save_checkpoint
from .scene.checks import ResolutionWarning, resolution_warnings
from .post.crackpath import crack_path_rows, final_ridge
from .post.fields import snapshot_fields
from .io.output import (HistoryWriter, Manifest, OutputError, VTKSeries, atomic_write_text,
                     prepare_output_dir, read_run_json, run_metadata, to_toml, write_run_json)
from .io.plotting import plot_force_displacement, plot_history, plot_phase_field, read_history
from .io.results import ResultsWriter
from .scene import Scene
from .solve.stepper import PhaseFieldStepper, StepRecord

log = logging.getLogger(__name__)

CHECKPOINT = "checkpoint.h5"
PLOTS = ("history.png", "crack.png", "force_displacement.png")
"""The files :func:`write_plots` may write (listed in the manifest while it runs)."""


@dataclass(frozen=True)
class RunSummary:
    """What a finished run wrote and how it ended."""

    out_dir: Path
    last: StepRecord
    n_snapshots: int
    profile: str = ""
    """The per-phase timing table (see :class:`ngfrac.solve.profiling.PhaseTimer`)."""


def write_snapshot(series: VTKSeries, stepper: PhaseFieldStepper) -> None:
    """One VTK snapshot: u, z, gamma and the derived fields of :func:`ngfrac.post.fields.snapshot_fields`
    (energy density, stress, estimator, element size)."""
    series.write(stepper.mesh, snapshot_fields(stepper), stepper.t)


def write_crack_path(out: Path, stepper: PhaseFieldStepper) -> Path:
    """crack_path.csv: the tip track of history.csv and the final ridge of z (2D with an
    initial crack; :func:`ngfrac.post.crackpath.crack_path_rows` has the layout)."""
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


def _start(scene: Scene, out: Path, overwrite: bool,
           restart: bool) -> tuple[PhaseFieldStepper, Manifest, dict[str, Any]]:
    """The stepper, the folder's manifest and its run.json data (written here)."""
    if restart:
        checkpoint = out / CHECKPOINT
        if not checkpoint.exists():
            raise OutputError(f"no checkpoint in {str(out)!r}; a restart needs {CHECKPOINT} "
                              "(written every output.checkpoint_every steps)")
        stepper = resume(checkpoint, scene)
        manifest = Manifest.load(out) or Manifest.adopt(out)
        manifest.save()
        return stepper, manifest, record_restart(out, scene, stepper, manifest)
    manifest = prepare_output_dir(out, overwrite)
    with manifest.writing("scene.toml"):
        atomic_write_text(out / "scene.toml", to_toml(scene.to_dict()))
    info = run_info(scene)
    write_run_json(out, info, manifest)
    return PhaseFieldStepper(scene), manifest, info


def run_info(scene: Scene) -> dict[str, Any]:
    """The ``run.json`` data of a new run of ``scene`` (also results.h5's root attributes).

    :func:`~ngfrac.io.output.run_metadata` (versions, git commit, threads, command line, start
    time), the scene's name, its resolution warnings (``resolution_warnings``, a list of
    lines, empty when the scene resolves its crack) and an empty ``restarts`` list.
    """
    return {"scene": scene.name, **run_metadata(),
            "resolution_warnings": resolution_warnings(scene), "restarts": []}


def _flat_keys(data: Any, prefix: str = "") -> dict[str, Any]:
    """``{"time.t_end": 0.1, "loads.0.value": "10*t", ...}`` with strict JSON values (a
    non-finite number as its text, "nan", so that it compares equal to itself)."""
    if isinstance(data, dict):
        items = data.items()
    elif isinstance(data, (list, tuple)) and any(isinstance(v, dict) for v in data):
        items = ((str(i), v) for i, v in enumerate(data))
    elif isinstance(data, (list, tuple)):
        return {prefix: [_flat_keys(v)[""] for v in data]}
    else:
        finite = not isinstance(data, float) or math.isfinite(data)
        return {prefix: json.loads(json.dumps(data)) if finite else repr(data)}
    out: dict[str, Any] = {}
    for key, value in items:
        out.update(_flat_keys(value, f"{prefix}.{key}" if prefix else str(key)))
    return out


def record_restart(out: Path, scene: Scene, stepper: PhaseFieldStepper,
                   manifest: Manifest | None = None) -> dict[str, Any]:
    """Store the continued scene in ``scene.toml`` and append the restart to ``run.json``.

    The restart entry holds :func:`~ngfrac.io.output.run_metadata` of this session, the step and
    time it continues from and the changed keys (``{"time.t_end": [old, new]}``).
    Returns the updated run.json data.
    """
    stored = out / "scene.toml"
    try:
        old = _flat_keys(tomllib.loads(stored.read_text())) if stored.exists() else None
    except (OSError, tomllib.TOMLDecodeError):
        old = None
    new = _flat_keys(scene.to_dict())
    changed = {} if old is None else {key: [old.get(key), new.get(key)]
                                      for key in sorted(set(old) | set(new))
                                      if old.get(key) != new.get(key)}
    if changed or old is None:
        with manifest.writing("scene.toml") if manifest else contextlib.nullcontext():
            atomic_write_text(stored, to_toml(scene.to_dict()))
    info = read_run_json(out) or {"scene": scene.name}
    info.setdefault("restarts", []).append(
        {**run_metadata(), "from_step": int(stepper.k), "from_t": float(stepper.t),
         "changed": changed})
    write_run_json(out, info, manifest)
    return info


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

    Warns
    -----
    ResolutionWarning
        One per line of :func:`ngfrac.scene.checks.resolution_warnings` (the mesh or epsilon
        cannot resolve the crack), before anything is written.
    """
    for message in resolution_warnings(scene):
        warnings.warn(message, ResolutionWarning, stacklevel=2)
    started = time.perf_counter()
    out = Path(out_dir)
    stepper, manifest, info = _start(scene, out, overwrite, restart)
    stepper.timer.add("set-up (mesh, spaces, z0, u0)", time.perf_counter() - started)
    if on_start is not None:
        on_start(stepper)
    output = scene.output
    subdivision = output.vtk_subdivision if output.vtk_subdivision >= 0 else scene.discretization.order - 1
    series = VTKSeries(out / "vtk", subdivision, manifest=manifest)
    record = stepper.record()
    if on_step is not None:
        on_step(stepper)
    with ExitStack() as stack:
        with manifest.writing("history.csv"):
            history = stack.enter_context(HistoryWriter(
                out / "history.csv", record.header(), resume_after=stepper.k if restart else None))
        results = None
        if output.results:
            with manifest.writing("results.h5", "results.xdmf"):
                results = (ResultsWriter.resume(out / "results.h5", scene, stepper.k) if restart
                           else ResultsWriter(out / "results.h5", scene, overwrite=overwrite))
            stack.callback(results.close)
            results.set_attributes(info)
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
                with (timer.phase("output: checkpoint"),
                      manifest.writing(CHECKPOINT, "checkpoint.tmp")):
                    save_checkpoint(stepper, out / CHECKPOINT)
            if on_record is not None:
                on_record(record)
            if on_step is not None:
                on_step(stepper)
    with stepper.timer.phase("output: crack path"), manifest.writing("crack_path.csv"):
        write_crack_path(out, stepper)
    if plots:
        with stepper.timer.phase("output: plots"), manifest.writing(*PLOTS):
            write_plots(out, stepper)
    log.info("run %s finished at t=%g in %.1f s", scene.name, record.t, record.wall_s)
    wall = time.perf_counter() - started
    return RunSummary(out, record, len(series.entries), stepper.timer.table(total=wall))
