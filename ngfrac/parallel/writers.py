"""The writers of an MPI run: which writers each rank has, and results.h5 with crack_path.csv
from the fields gathered to rank 0.

Rank 0 holds the run folder and writes history.csv, scene.toml, run.json, the manifest, the
serial checkpoint, results.h5 and crack_path.csv; every rank writes its part of each VTK
snapshot (NGSolve's ``VTKOutput`` is collective) and takes part in the gathers of the
checkpoints and results. :func:`rank_writers` is :meth:`MPICommunicator.run_writers
<ngfrac.parallel.MPICommunicator.run_writers>`; the serial run's writers are
:func:`ngfrac.io.writers.default_writers`.
"""
from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

from ..io.writers import (Checkpoints, HistoryCSV, ResultsH5, RunFolder, VTKSnapshots, Writer,
                          snapshot_due, write_crack_path)
from ..scene import Scene

if TYPE_CHECKING:
    from ..solve.communicator import Communicator
    from ..solve.stepper import PhaseFieldStepper, StepRecord

__all__ = ["GatheredResults", "rank_writers"]

log = logging.getLogger(__name__)


def rank_writers(folder: RunFolder | None, out: Path, scene: Scene, extra: Sequence[Writer],
                 restart: bool, comm: "Communicator") -> list[Writer]:
    """The writers of this rank of an MPI run.

    Rank 0: :class:`~ngfrac.io.writers.HistoryCSV`, :class:`~ngfrac.io.writers.VTKSnapshots`,
    :class:`~ngfrac.io.writers.Checkpoints`, :class:`GatheredResults` and ``extra``; the
    other ranks (``folder`` None): the VTK series (a part per rank, listed by rank 0), the
    checkpoints and :class:`GatheredResults` (they take part in the gathers). No plots and no
    opening.csv (docs/parallel.md, "Not yet"). Collective (rank 0 makes ``vtk/`` first).
    """
    if not comm.is_root:
        vtk = VTKSnapshots(RunFolder(out, None, restart=restart), scene)  # type: ignore[arg-type]
        comm.barrier()  # rank 0 has made vtk/
        return [vtk, Checkpoints(None, scene), GatheredResults(None, scene, restart)]
    log.info("under MPI ngfrac writes no plots and no opening.csv (docs/parallel.md)")
    vtk = VTKSnapshots(folder, scene)
    comm.barrier()
    return [HistoryCSV(folder), vtk, Checkpoints(folder, scene),
            GatheredResults(folder, scene, restart), *extra]


class GatheredResults(Writer):
    """``results.h5`` (and ``results.xdmf``) and ``crack_path.csv`` of an MPI run, on every
    rank: at each snapshot (:func:`~ngfrac.io.writers.snapshot_due`) and at the end u and z
    are gathered to rank 0's serial mesh (``stepper.comm.gather_view``:
    :func:`ngfrac.parallel.checkpoints.gather_view`), where the serial writers
    (:class:`~ngfrac.io.writers.ResultsH5`, :func:`~ngfrac.io.writers.write_crack_path`)
    write them; ``folder`` is None on the other ranks. After
    :class:`~ngfrac.io.writers.HistoryCSV` (the crack path reads history.csv)."""

    def __init__(self, folder: RunFolder | None, scene: Scene, restart: bool = False) -> None:
        self.folder = folder
        self.scene = scene
        self.restart = restart
        self.results = ResultsH5.for_folder(folder, scene) if folder is not None else None

    def _view(self, stepper: "PhaseFieldStepper") -> Any:
        with stepper.timer.phase("output: VTK and snapshots"):
            return stepper.comm.gather_view(stepper)

    def start(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        snapshot = self.scene.output.results and self.scene.output.vtk_every
        view = self._view(stepper) if snapshot and not self.restart else None
        if self.results is not None:
            self.results.start(view if view is not None else _Counters(stepper), record)

    def record(self, stepper: "PhaseFieldStepper", record: "StepRecord") -> None:
        if not self.scene.output.results:
            return
        view = self._view(stepper) if snapshot_due(stepper) else None
        writer = self.results.writer if self.results is not None else None
        if writer is None:
            return
        if record.has_diagnostics:
            writer.append(record)
        if view is not None:
            writer.write_snapshot(view)

    def finish(self, stepper: "PhaseFieldStepper") -> None:
        view = self._view(stepper)
        if self.results is not None:
            self.results.close()
        if self.folder is not None:
            with (stepper.timer.phase("output: crack path"),
                  self.folder.manifest.writing("crack_path.csv")):
                write_crack_path(self.folder.path, view)

    def close(self) -> None:
        if self.results is not None:
            self.results.close()


class _Counters:
    """The step and time of a stepper (what :class:`~ngfrac.io.writers.ResultsH5` reads at a
    restart)."""

    def __init__(self, stepper: "PhaseFieldStepper") -> None:
        self.k, self.t = stepper.k, stepper.t
