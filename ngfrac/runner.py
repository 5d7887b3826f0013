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

:func:`run_scene` is a loop over ``stepper.run()`` that hands each record to the writers of
:mod:`ngfrac.io.writers` (:func:`~ngfrac.io.writers.default_writers` and any given).
"""
from __future__ import annotations

import contextlib
import json
import logging
import math
import time
import tomllib
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

from .environment import set_threads
from .io.checkpoint import CheckpointError, CheckpointState, load_checkpoint
from .io.output import (Manifest, OutputError, atomic_write_text, read_run_json, run_metadata,
                        to_toml, write_run_json)
from .io.writers import (CHECKPOINT, PLOTS, RunFolder, VTKSnapshots, Writer, Writers,  # noqa: F401
                         default_writers, run_info, write_crack_path, write_plots,
                         write_snapshot)  # PLOTS ... write_snapshot: importable from here, as before
from .parallel.communicator import world
from .solve.communicator import SERIAL, Communicator, ParallelError
from .scene import Scene
from .mesh.resolution import ResolutionWarning, resolution_warnings
from .solve.stepper import PhaseFieldStepper, StepRecord

__all__ = ["RunSummary", "exit_code", "open_run", "record_restart", "run_scene"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RunSummary:
    """What a finished run wrote and how it ended."""

    out_dir: Path
    last: StepRecord
    n_snapshots: int
    profile: str = ""
    """The per-phase timing table (see :class:`ngfrac.solve.profiling.PhaseTimer`)."""


def open_run(scene: Scene, out: Path, overwrite: bool = False,
             restart: bool = False,
             comm: Communicator = SERIAL) -> tuple[PhaseFieldStepper, RunFolder | None]:
    """The stepper and the run folder of a new run (:meth:`RunFolder.create
    <ngfrac.io.writers.RunFolder.create>`) or of a restart from the folder's checkpoint
    (its scene and the restart recorded by :func:`record_restart`).

    The communicator says what each process does: the folder is rank 0's (``comm.on_root``;
    None on the other ranks of an MPI job), the checkpoint is read on rank 0
    (``comm.read_on_root``) and continued by ``comm.resume`` (in an MPI job
    :func:`ngfrac.parallel.checkpoints.resume_distributed` distributes its mesh and scatters
    its fields). Collective in an MPI job.
    """
    checkpoint = _read_checkpoint(out, scene, comm) if restart else None
    return _open(scene, out, overwrite, restart, comm, checkpoint)


def _open(scene: Scene, out: Path, overwrite: bool, restart: bool, comm: Communicator,
          checkpoint: CheckpointState | None) -> tuple[PhaseFieldStepper, RunFolder | None]:
    """:func:`open_run` with a restart's checkpoint read (by :func:`_read_checkpoint`)."""
    if not restart:
        folder = comm.on_root(lambda: RunFolder.create(out, scene, overwrite))
        return PhaseFieldStepper(scene, comm=comm), folder
    stepper = comm.resume(checkpoint, scene)
    return stepper, comm.on_root(lambda: _continued_folder(out, scene, stepper, overwrite))


def _continued_folder(out: Path, scene: Scene, stepper: PhaseFieldStepper,
                      overwrite: bool) -> RunFolder:
    """The folder of a restart: its CAD copy checked, its manifest, the restart recorded."""
    _check_cad_copy(out)
    manifest = Manifest.load(out) or Manifest.adopt(out)
    manifest.save()
    info = record_restart(out, scene, stepper, manifest)
    return RunFolder(out, manifest, info, restart=True, overwrite=overwrite)


def _check_cad_copy(out: Path) -> None:
    """The run folder's copy of the CAD file is the one the run read (run.json's sha256)."""
    from .io.output import file_sha256

    cad = (read_run_json(out) or {}).get("cad_file")
    if not isinstance(cad, dict) or not cad.get("name"):
        return
    copy = out / str(cad["name"])
    if not copy.is_file():
        raise OutputError(f"{str(copy)!r} is missing: the run read its CAD file from there; "
                          f"copy {cad.get('source')!r} back to it")
    if file_sha256(copy) != cad.get("sha256"):
        raise OutputError(f"{str(copy)!r} changed since the run read it (its SHA-256 differs "
                          "from run.json's cad_file); restore it to continue the run")


def _no_checkpoint(out: Path) -> str:
    return (f"no checkpoint in {str(out)!r}; a restart needs {CHECKPOINT} "
            "(written every output.checkpoint_every steps)")


def _read_checkpoint(out: Path, scene: Scene, comm: Communicator) -> CheckpointState | None:
    """The folder's checkpoint, read on rank 0 (None on the other ranks of an MPI job); a
    missing or unusable one raises the same error on every rank (one line from rank 0, no
    Abort)."""
    def read() -> CheckpointState:
        path = out / CHECKPOINT
        if not path.exists():
            raise OutputError(_no_checkpoint(out))
        return load_checkpoint(path, scene)

    return comm.read_on_root(read)


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
    from .io.output import portable_scene_dict

    stored_dict = portable_scene_dict(scene.to_dict(), out)  # the CAD copy by its name
    new = _flat_keys(stored_dict)
    changed = {} if old is None else {key: [old.get(key), new.get(key)]
                                      for key in sorted(set(old) | set(new))
                                      if old.get(key) != new.get(key)}
    if changed or old is None:
        with manifest.writing("scene.toml") if manifest else contextlib.nullcontext():
            atomic_write_text(stored, to_toml(stored_dict))
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
              on_start: Callable[[PhaseFieldStepper], None] | None = None,
              writers: Sequence[Writer] = (),
              comm: Communicator | None = None) -> RunSummary:
    """Run ``scene`` to its end time, writing history, VTK, results, checkpoints and plots.

    The files are written by :func:`~ngfrac.io.writers.default_writers`; ``NGFRAC_THREADS``,
    when set, caps NGSolve's threads first (:func:`ngfrac.environment.set_threads`).

    Parameters
    ----------
    scene : Scene
    out_dir : str or Path
        The run folder.
    overwrite : replace an earlier run in that folder (only the files ngfrac writes)
    on_record : called with every step record
    plots : write history.png and crack.png at the end
    on_step : called with the stepper after set-up and after every step (for checks in tests)
    restart : continue the run in ``out_dir`` from its checkpoint
    on_start : called once with the stepper before the first step
    writers : more writers (:class:`~ngfrac.io.writers.Writer`), called after the default ones,
        e.g. :class:`~ngfrac.io.writers.Progress` (in an MPI job on rank 0 only)
    comm : the processes of the run (:mod:`ngfrac.parallel`); by default
        :func:`ngfrac.parallel.world`: an MPI job when launched by ``mpirun -np N`` (N >= 3;
        rank 0 writes ``history.csv``, docs/parallel.md says what else), else one process.
        In an MPI job an error on any rank ends the job (one line on stderr, ``Abort``).

    Warns
    -----
    ResolutionWarning
        One per line of :func:`ngfrac.mesh.resolution.resolution_warnings` (the mesh or epsilon
        cannot resolve the crack), before anything is written.
    """
    for message in resolution_warnings(scene):
        warnings.warn(message, ResolutionWarning, stacklevel=2)
    set_threads()
    comm = world() if comm is None else comm
    comm.check(scene)  # the same on every rank: refused before anything is written
    started = time.perf_counter()
    # before the guard: a missing or foreign checkpoint is an error alike on every rank
    checkpoint = _read_checkpoint(Path(out_dir), scene, comm) if restart else None
    with comm.guard(exit_code):
        return _run(scene, Path(out_dir), overwrite, on_record, plots, on_step, restart,
                    on_start, writers, comm, checkpoint, started)


def exit_code(error: BaseException) -> int:
    """The exit status of ``ngfrac run`` for an error (an MPI job ends with it): those of
    :func:`ngfrac.cli.main` for one process, 2 for bad input (a scene, an output folder, a
    checkpoint or results file, an MPI launch), 3 for a meshing or solver failure, 130 for an
    interrupt; 1 for any other error."""
    from .geometry.domains import MeshingError
    from .io.hdf5 import ResultsError
    from .solve.u_problem import SolverError

    if isinstance(error, (SolverError, MeshingError)):
        return 3
    if isinstance(error, KeyboardInterrupt):
        return 130
    bad_input = (ValueError, OutputError, CheckpointError, ResultsError, ParallelError)
    return 2 if isinstance(error, bad_input) else 1


def _run(scene: Scene, out_dir: Path, overwrite: bool,
         on_record: Callable[[StepRecord], None] | None, plots: bool,
         on_step: Callable[[PhaseFieldStepper], None] | None, restart: bool,
         on_start: Callable[[PhaseFieldStepper], None] | None, writers: Sequence[Writer],
         comm: Communicator, checkpoint: CheckpointState | None,
         started: float) -> RunSummary:
    """:func:`run_scene` after its checks (``started``: its clock, before the checkpoint was
    read)."""
    stepper, folder = _open(scene, out_dir, overwrite, restart, comm, checkpoint)
    stepper.timer.add("set-up (mesh, spaces, z0, u0)", time.perf_counter() - started)
    if on_start is not None:
        on_start(stepper)
    # this rank's writers: default_writers on one process (then the given ones); in an MPI
    # job those of ngfrac.parallel.writers.rank_writers (the given ones on rank 0)
    writers = comm.run_writers(lambda: default_writers(folder, scene, plots), folder, out_dir,
                               scene, writers, restart)
    record = stepper.record()
    if on_step is not None:
        on_step(stepper)
    with Writers(writers) as all_writers:
        all_writers.start(stepper, record)
        for record in stepper.run():
            all_writers.record(stepper, record)
            if on_record is not None:
                on_record(record)
            if on_step is not None:
                on_step(stepper)
        all_writers.finish(stepper)
    log.info("run %s finished at t=%g in %.1f s", scene.name, record.t, record.wall_s)
    wall = time.perf_counter() - started
    snapshots = next((w.n_snapshots for w in writers if isinstance(w, VTKSnapshots)), 0)
    return RunSummary(out_dir if folder is None else folder.path, record, snapshots,
                      stepper.timer.table(total=wall))
