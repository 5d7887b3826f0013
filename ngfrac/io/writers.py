"""Writers of a run folder: observers that receive the stepper's records.

A writer has four methods, called in this order by :func:`ngfrac.runner.run_scene` (or by a
script's own loop over ``stepper.run()``):

- ``start(stepper, record)`` once, before the first step: opens its files; ``record`` is
  ``stepper.record()`` of the state the run starts from, which a new run writes and a restart
  (whose files already hold it) does not;
- ``record(stepper, record)`` after every step, with the step's
  :class:`~ngfrac.solve.stepper.StepRecord`;
- ``finish(stepper)`` once, after the last step: closes its files, writes what needs the
  whole run (the crack path, the plots);
- ``close()`` always, also after an error: releases what is still open (safe to call twice).

:func:`default_writers` gives the writers of ``ngfrac run`` in the order they write (the
checkpoint after the other writes of a step, so a restart that drops what came after its
step leaves consistent files). :class:`Writers` calls a list of writers as one.

Every file is listed in the folder's manifest (:class:`~ngfrac.io.output.Manifest`) before it
is written; :class:`RunFolder` holds the manifest and what the writers share.
"""
from __future__ import annotations

import contextlib
import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterable, Iterator

import numpy as np

from .checkpoint import save_state
from .output import (HistoryWriter, Manifest, VTKSeries, atomic_write_text, prepare_output_dir,
                     run_metadata, to_toml, write_run_json)
from .plotting import plot_force_displacement, plot_history, plot_phase_field, read_history
from .results import ResultsWriter
from ..post.crackpath import crack_path_rows, final_ridge
from ..post.fields import snapshot_fields
from ..post.pressurized import opening_profile
from ..scene import Scene
from ..mesh.resolution import resolution_warnings

if TYPE_CHECKING:
    from ..solve.stepper import PhaseFieldStepper, StepRecord

__all__ = ["CHECKPOINT", "PLOTS", "Checkpoints", "CrackPathCSV", "HistoryCSV", "OpeningCSV",
           "Plots", "Progress", "ResultsH5", "RunFolder", "VTKSnapshots", "Writer", "Writers",
           "default_writers", "run_info", "snapshot_due", "write_crack_path", "write_opening",
           "write_plots", "write_snapshot"]

log = logging.getLogger(__name__)

CHECKPOINT = "checkpoint.h5"
PLOTS = ("history.png", "crack.png", "force_displacement.png")
"""The files :func:`write_plots` may write (listed in the manifest while it runs)."""


# -- the folder -------------------------------------------------------------------------------
def run_info(scene: Scene) -> dict[str, Any]:
    """The ``run.json`` data of a new run of ``scene`` (also results.h5's root attributes).

    :func:`~ngfrac.io.output.run_metadata` (versions, git commit, threads, command line, start
    time), the scene's name, its resolution warnings (``resolution_warnings``, a list of
    lines, empty when the scene resolves its crack) and an empty ``restarts`` list.
    """
    return {"scene": scene.name, **run_metadata(),
            "resolution_warnings": resolution_warnings(scene), "restarts": []}


@dataclass
class RunFolder:
    """A run folder as the writers see it.

    Attributes
    ----------
    path : Path
        The folder.
    manifest : Manifest
        The files ngfrac wrote there.
    info : dict
        The ``run.json`` data (also results.h5's root attributes).
    restart : bool
        The run continues the folder's earlier run from its checkpoint.
    overwrite : bool
        The folder's earlier run was replaced.
    """

    path: Path
    manifest: Manifest
    info: dict[str, Any] = field(default_factory=dict)
    restart: bool = False
    overwrite: bool = False

    @classmethod
    def create(cls, path: str | Path, scene: Scene, overwrite: bool = False) -> "RunFolder":
        """Prepare ``path`` for a new run of ``scene``: the manifest, ``scene.toml`` and
        ``run.json`` (:func:`~ngfrac.io.output.prepare_output_dir` says what ``overwrite``
        replaces), and a copy of the scene's CAD file (``geometry.file``), which the stored
        scene names (:func:`~ngfrac.io.output.copy_cad_file`; its SHA-256 in run.json's
        ``cad_file``)."""
        from .output import copy_cad_file, portable_scene_dict

        path = Path(path)
        manifest = prepare_output_dir(path, overwrite)
        cad = copy_cad_file(scene.to_dict(), path, manifest)  # the folder is self-contained
        with manifest.writing("scene.toml"):
            atomic_write_text(path / "scene.toml",
                              to_toml(portable_scene_dict(scene.to_dict(), path)))
        info = run_info(scene)
        if cad is not None:
            info["cad_file"] = cad
        write_run_json(path, info, manifest)
        return cls(path, manifest, info, restart=False, overwrite=overwrite)


def snapshot_due(stepper: "PhaseFieldStepper") -> bool:
    """Whether the step just taken writes a snapshot: every ``output.vtk_every`` output times
    and at the end (``vtk_every = 0``: only at the end)."""
    every = stepper.scene.output.vtk_every
    return bool(every and stepper.output_due(every) or stepper.finished)


# -- the writers ------------------------------------------------------------------------------
class Writer:
    """A writer that writes nothing: the protocol, and a base whose methods may be left out."""

    def start(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        """Before the first step; ``record`` is the state the run starts from."""

    def record(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        """After every step."""

    def finish(self, stepper: "PhaseFieldStepper") -> None:
        """After the last step."""

    def close(self) -> None:
        """Release open files (after :meth:`finish`, or after an error)."""


class Writers(Writer):
    """Several writers called as one, in the given order; a context manager that closes them.

    Examples
    --------
    >>> with Writers(default_writers(folder, scene)) as writers:   # doctest: +SKIP
    ...     writers.start(stepper, stepper.record())
    ...     for record in stepper.run():
    ...         writers.record(stepper, record)
    ...     writers.finish(stepper)
    """

    def __init__(self, writers: Iterable[Writer]) -> None:
        self.writers = list(writers)

    def __iter__(self) -> Iterator[Writer]:
        return iter(self.writers)

    def start(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        for writer in self.writers:
            writer.start(stepper, record)

    def record(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        for writer in self.writers:
            writer.record(stepper, record)

    def finish(self, stepper: "PhaseFieldStepper") -> None:
        for writer in self.writers:
            writer.finish(stepper)

    def close(self) -> None:
        with contextlib.ExitStack() as stack:  # every writer is closed, even if one fails
            for writer in self.writers:
                stack.callback(writer.close)

    def __enter__(self) -> "Writers":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _times_as_written(record: "StepRecord") -> list[Any]:
    """The record's row with t and dt to 15 significant digits: t = k tau is a product of
    floats (0.0009000000000000001 for 9 steps of 1e-4); the nearest 15-digit number is the
    time the scene meant."""
    row = list(record.row())
    for i, name in enumerate(record.header()):
        if name in ("t", "dt") and isinstance(row[i], float):
            row[i] = float(f"{row[i]:.15g}")
    return row


class HistoryCSV(Writer):
    """``history.csv``: one row per diagnosed step (a restart keeps the rows up to its step)."""

    def __init__(self, folder: RunFolder) -> None:
        self.folder = folder
        self.path = folder.path / "history.csv"
        self.writer: HistoryWriter | None = None

    def start(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        with self.folder.manifest.writing("history.csv"):
            self.writer = HistoryWriter(self.path, record.header(),
                                        resume_after=stepper.k if self.folder.restart else None)
        if not self.folder.restart:
            self.writer.write(_times_as_written(record))

    def record(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        if record.has_diagnostics and self.writer is not None:
            with stepper.timer.phase("output: history"):
                self.writer.write(_times_as_written(record))

    def finish(self, stepper: "PhaseFieldStepper") -> None:
        self.close()

    def close(self) -> None:
        if self.writer is not None:
            self.writer.close()


class ResultsH5(Writer):
    """``results.h5`` (and ``results.xdmf``): the history rows and, with the VTK snapshots,
    u and z on their meshes (:class:`~ngfrac.io.results.ResultsWriter`)."""

    def __init__(self, folder: RunFolder, scene: Scene) -> None:
        self.folder = folder
        self.scene = scene
        self.path = folder.path / "results.h5"
        self.writer: ResultsWriter | None = None

    @classmethod
    def for_folder(cls, folder: RunFolder, scene: Scene) -> "ResultsH5 | None":
        """The results.h5 writer when ``output.results`` (none for a restart of a folder
        without results.h5, e.g. of a distributed run before ngfrac wrote one there: a
        warning)."""
        if not scene.output.results:
            return None
        if folder.restart and not (folder.path / "results.h5").exists():
            log.warning("no results.h5 in %s to continue; the restart writes none", folder.path)
            return None
        return cls(folder, scene)

    def start(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        folder = self.folder
        with folder.manifest.writing("results.h5", "results.xdmf"):
            self.writer = (ResultsWriter.resume(self.path, self.scene, stepper.k) if folder.restart
                           else ResultsWriter(self.path, self.scene, overwrite=folder.overwrite))
        self.writer.manifest = folder.manifest  # lists the per-mesh results_mesh_NNN.xdmf
        self.writer.write_xdmf()
        self.writer.set_attributes(folder.info)
        if not folder.restart:
            self.writer.append(record)
            if self.scene.output.vtk_every:
                self.writer.write_snapshot(stepper)

    def record(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        if self.writer is None:
            return
        if record.has_diagnostics:
            with stepper.timer.phase("output: history"):
                self.writer.append(record)
        if snapshot_due(stepper):
            with stepper.timer.phase("output: VTK and snapshots"):
                self.writer.write_snapshot(stepper)

    def finish(self, stepper: "PhaseFieldStepper") -> None:
        self.close()

    def close(self) -> None:
        if self.writer is not None:
            self.writer.close()


def write_snapshot(series: VTKSeries, stepper: "PhaseFieldStepper") -> None:
    """One VTK snapshot: u, z, gamma and the derived fields of
    :func:`ngfrac.post.fields.snapshot_fields` (energy density, stress, estimator, element
    size)."""
    series.write(stepper.mesh, snapshot_fields(stepper), stepper.t)


class VTKSnapshots(Writer):
    """``vtk/``: a ``.vtu`` per snapshot and the ``fields.pvd`` series (:func:`snapshot_due`).

    The folder ``vtk/`` is made (and listed in the manifest) when the writer is made, before
    the files of the other writers.
    """

    def __init__(self, folder: RunFolder, scene: Scene) -> None:
        output = scene.output
        subdivision = (output.vtk_subdivision if output.vtk_subdivision >= 0
                       else scene.discretization.order - 1)
        self.restart = folder.restart
        self.every = output.vtk_every
        layout = output.vtk_format
        if layout == "auto":
            layout = "vertices" if scene.geometry.dim == 3 else "subdivided"
        self.series = VTKSeries(folder.path / "vtk", subdivision, manifest=folder.manifest,
                                layout=layout)

    def start(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        if self.restart:
            self._resume(stepper)
        elif self.every:
            write_snapshot(self.series, stepper)

    def _resume(self, stepper: "PhaseFieldStepper") -> None:
        """The kept snapshots: rank 0 rewrites the series (``stepper.comm.on_root``), then
        every rank reads it, so each rank of an MPI job names its part of the next snapshot
        by the count (on rank 0 the reading finds what it wrote)."""
        comm = stepper.comm
        comm.on_root(lambda: self.series.resume(stepper.t))
        comm.barrier()
        self.series.resume(stepper.t, write=False)

    def record(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        if snapshot_due(stepper):
            with stepper.timer.phase("output: VTK and snapshots"):
                write_snapshot(self.series, stepper)

    @property
    def n_snapshots(self) -> int:
        """The snapshots in the series (a restart's kept ones included)."""
        return self.series.n_snapshots


class Checkpoints(Writer):
    """``checkpoint.h5`` every ``output.checkpoint_every`` steps and at the end
    (:func:`~ngfrac.io.checkpoint.save_checkpoint`, written atomically).

    In an MPI job every rank has one (``stepper.comm.gather_state`` gathers the fields to rank
    0, which writes the serial checkpoint); ``folder`` is None on the ranks other than 0.
    """

    def __init__(self, folder: RunFolder | None, scene: Scene) -> None:
        self.folder = folder
        self.every = scene.output.checkpoint_every

    def record(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        if self.every and record.step % self.every == 0:
            self._save(stepper)

    def finish(self, stepper: "PhaseFieldStepper") -> None:
        """One more at the end (unless the last step wrote one), so that a finished run can
        be extended: ``ngfrac run --restart DIR --set time.t_end=T``."""
        if self.every and stepper.k % self.every != 0:
            self._save(stepper)

    def _save(self, stepper: "PhaseFieldStepper") -> None:
        with stepper.timer.phase("output: checkpoint"):
            state = stepper.comm.gather_state(stepper)  # stepper.state(); under MPI collective, on rank 0
            if self.folder is not None:
                with self.folder.manifest.writing(CHECKPOINT, "checkpoint.tmp"):
                    save_state(state, stepper.scene, self.folder.path / CHECKPOINT)


def write_crack_path(out: Path, stepper: "PhaseFieldStepper") -> Path:
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


class CrackPathCSV(Writer):
    """``crack_path.csv`` at the end, from ``history.csv`` (so after :class:`HistoryCSV`)."""

    def __init__(self, folder: RunFolder) -> None:
        self.folder = folder

    def finish(self, stepper: "PhaseFieldStepper") -> None:
        with stepper.timer.phase("output: crack path"), self.folder.manifest.writing("crack_path.csv"):
            write_crack_path(self.folder.path, stepper)


OPENING_HALF_WIDTH = 10.0
"""Half length of the lines across the crack of opening.csv, in epsilon (z = exp(-10))."""


def write_opening(out: Path, stepper: "PhaseFieldStepper") -> Path:
    """opening.csv: ``w(s) = -int u.grad z dn`` on lines across the first initial crack (2D,
    straight between its first and last point; :func:`ngfrac.post.pressurized.opening_profile`)."""
    scene = stepper.scene
    profile = opening_profile(stepper.u, stepper.z, scene.cracks[0].points,
                              OPENING_HALF_WIDTH * scene.phase_field.epsilon,
                              stepper.domain.contains)
    path = out / "opening.csv"
    with HistoryWriter(path, ["step", "t", "s", "x", "y", "w"]) as writer:
        for row in zip(profile.s, profile.x, profile.y, profile.w):
            writer.write([stepper.k, stepper.t, *(float(v) for v in row)])
    return path


class OpeningCSV(Writer):
    """``opening.csv`` at the end of a run with ``phase_field.crack_pressure`` and a 2D
    initial crack (:func:`default_writers` adds it then)."""

    def __init__(self, folder: RunFolder) -> None:
        self.folder = folder

    def finish(self, stepper: "PhaseFieldStepper") -> None:
        with stepper.timer.phase("output: opening"), self.folder.manifest.writing("opening.csv"):
            write_opening(self.folder.path, stepper)


def write_plots(out: Path, stepper: "PhaseFieldStepper") -> None:
    """history.png, crack.png (z with the tip path) and force_displacement.png (if any)."""
    units = stepper.scene.units
    plot_history(out / "history.csv", out / "history.png", units)
    history = read_history(out / "history.csv")
    tips = np.column_stack([history[c] for c in ("tip_x", "tip_y", "tip_z") if c in history])
    z_vertices = stepper.z_node_values()[: stepper.mesh.nv]
    plot_phase_field(stepper.mesh, z_vertices, out / "crack.png",
                     title=f"{stepper.scene.name}: z at t = {stepper.t:.4g}",
                     path=tips[np.all(np.isfinite(tips), axis=1)])
    plot_force_displacement(history, out / "force_displacement.png", units)


class Plots(Writer):
    """The figures of :data:`PLOTS` at the end (:func:`write_plots`)."""

    def __init__(self, folder: RunFolder) -> None:
        self.folder = folder

    def finish(self, stepper: "PhaseFieldStepper") -> None:
        with stepper.timer.phase("output: plots"), self.folder.manifest.writing(*PLOTS):
            write_plots(self.folder.path, stepper)


class Progress(Writer):
    """A tqdm progress bar over the run's time (``ngfrac run``'s bar), with t, the vertex
    count and the last tip x as its postfix. ``disable=True`` shows nothing."""

    def __init__(self, scene: Scene, disable: bool = False) -> None:
        self.scene = scene
        self.disable = disable
        self.bar: Any = None
        self.tip_x = float("nan")

    def start(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        from tqdm import tqdm

        self.bar = tqdm(total=self.scene.time.n_ticks, unit="dt", disable=self.disable,
                        desc=self.scene.name, dynamic_ncols=True)
        self.bar.update(stepper.ticks)

    def record(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        if record.has_diagnostics:
            self.tip_x = record.tip_x
        self.bar.set_postfix(t=f"{record.t:.4g}", nv=record.nv, tip_x=f"{self.tip_x:.3f}",
                             refresh=False)
        self.bar.update(round(record.t / self.scene.time.dt) - self.bar.n)

    def finish(self, stepper: "PhaseFieldStepper") -> None:
        self.close()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def default_writers(folder: RunFolder, scene: Scene, plots: bool = True) -> list[Writer]:
    """The writers of ``ngfrac run``, in the order they are called.

    :class:`HistoryCSV`, :class:`ResultsH5` (when ``output.results``), :class:`VTKSnapshots`,
    :class:`Checkpoints` (after the other writes of a step), :class:`CrackPathCSV` (after
    history.csv is closed), :class:`OpeningCSV` (with a crack pressure) and, with ``plots``,
    :class:`Plots`. ``vtk/`` is made here, so the
    manifest lists it before the other files.
    """
    vtk = VTKSnapshots(folder, scene)
    writers: list[Writer] = [HistoryCSV(folder)]
    results = ResultsH5.for_folder(folder, scene)
    if results is not None:
        writers.append(results)
    writers += [vtk, Checkpoints(folder, scene), CrackPathCSV(folder)]
    if scene.phase_field.pressurized and scene.cracks and scene.geometry.dim == 2:
        writers.append(OpeningCSV(folder))
    if plots:
        writers.append(Plots(folder))
    return writers
