"""Run a study's scenes on Dask: a ``LocalCluster`` of one-thread processes, or any scheduler.

Each run is an ordinary run folder ``DIR/runs/<name>/`` written by
:func:`ngfrac.runner.run_scene` inside a Dask worker. Before anything is submitted every folder
is looked at (:func:`run_state`): a finished run (its checkpoint at the end time, of the same
scene) is skipped and its files are left alone; an unfinished one with a checkpoint continues
from it (``restart``); one without a checkpoint starts again. A run that raises is recorded as
failed with its one-line error, a worker that dies takes only its run with it (the scheduler
does not retry it on a local cluster: ``allowed-failures`` 0), and the others go on.
``DIR/study.csv`` is rewritten after every run that ends.

Dask is imported only here, and only when a study runs scenes: ``pip install ngfrac[dask]``.
"""
from __future__ import annotations

import contextlib
import json
import logging
import math
import os
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator

from ..io.output import OutputError, atomic_write_text, run_metadata
from ..scene import Scene
from .plan import PlannedRun, StudyPlan
from .richardson import richardson
from .table import FIXED_COLUMNS, read_table, run_quantities, write_table

__all__ = ["DaskMissing", "StudyResult", "run_state", "run_study", "study_client"]

log = logging.getLogger(__name__)

FINISHED, FAILED, RUNNING, PENDING = "finished", "failed", "running", "pending"
STUDY_FORMAT = "ngfrac-study"
RUNS = "runs"


class DaskMissing(ImportError):
    """``distributed`` is not installed (a study needs ``pip install ngfrac[dask]``)."""


@dataclass
class StudyResult:
    """What :func:`run_study` did: the table's rows, in the plan's order, and the counts."""

    out_dir: Path
    rows: list[dict[str, Any]]
    skipped: list[str] = field(default_factory=list)
    """The runs that were finished before this call (not run, their files not touched)."""
    wall_s: float = 0.0

    @property
    def failed(self) -> list[dict[str, Any]]:
        return [row for row in self.rows if row["status"] != FINISHED]

    def summary(self) -> str:
        """The one-line summary ``ngfrac study`` prints."""
        n = len(self.rows)
        done = n - len(self.failed)
        skipped = f" ({len(self.skipped)} already finished, not run again)" if self.skipped else ""
        failed = (f", {len(self.failed)} failed (first: {self.failed[0]['name']}: "
                  f"{self.failed[0]['error']})" if self.failed else "")
        return (f"study: {n} runs, {done} finished{skipped}{failed} in {self.wall_s:.1f} s; "
                f"table {self.out_dir / 'study.csv'}")


def _one_line(error: BaseException) -> str:
    text = str(error).strip().splitlines()
    return f"{type(error).__name__}: {text[0]}" if text else type(error).__name__


def run_state(folder: Path, scene: Scene) -> str:
    """``"new"``, ``"finished"``, ``"restart"`` (a checkpoint before the end) or ``"stale"``
    (a folder without a usable checkpoint: started again, only ngfrac's files replaced).

    Raises
    ------
    OutputError
        The folder's checkpoint is of another scene (the study's scene changed): it is not
        touched.
    """
    import h5py

    from ..io.hdf5 import scene_hash

    if not folder.exists():
        return "new"
    checkpoint = folder / "checkpoint.h5"
    if not checkpoint.is_file():
        return "stale"
    try:
        with h5py.File(checkpoint, "r") as f:
            ticks, stored = int(f.attrs["ticks"]), str(f.attrs["scene_hash"])
    except (OSError, KeyError, ValueError):
        return "stale"
    if stored != scene_hash(scene):
        raise OutputError(f"{str(folder)!r} holds a run of another scene (its checkpoint's "
                          "scene differs from this study's); move it away or use another --out")
    return "finished" if ticks >= scene.time.n_ticks else "restart"


def execute_run(folder: str, data: dict[str, Any], scene_name: str,
                threads: int = 1) -> dict[str, Any]:
    """Run one planned scene into ``folder`` (in a Dask worker): ``status``, ``error``,
    ``wall_s``. Every exception becomes a failed status with its one-line error."""
    os.environ["NGFRAC_THREADS"] = str(threads)  # run_scene applies it
    started = time.perf_counter()
    try:
        from ..mesh.resolution import ResolutionWarning
        from ..runner import run_scene

        scene = Scene.from_dict(data, name=scene_name)
        path = Path(folder)
        state = run_state(path, scene)
        if state != "finished":
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ResolutionWarning)  # in run.json
                run_scene(scene, path, overwrite=state == "stale", restart=state == "restart")
    except BaseException as error:  # noqa: BLE001 - a run's failure is a row, not a crash
        if isinstance(error, KeyboardInterrupt):
            raise
        return {"status": FAILED, "error": _one_line(error),
                "wall_s": time.perf_counter() - started}
    return {"status": FINISHED, "error": "", "wall_s": time.perf_counter() - started}


@contextlib.contextmanager
def study_client(workers: int | None = None, scheduler: str | None = None,
                 client: Any = None) -> Iterator[tuple[Any, dict[str, Any]]]:
    """A ``distributed.Client`` and a description of it for study.json.

    ``client`` given: that one (not closed here). ``scheduler`` given: connect to the running
    scheduler at that address. Otherwise a ``LocalCluster`` of ``workers`` processes (default:
    the usable cores) with one thread each, closed at the end.
    """
    try:
        import dask
        import distributed
    except ImportError:
        raise DaskMissing("ngfrac study runs its scenes with Dask, which is not installed: "
                          "pip install 'ngfrac[dask]' (or pip install distributed)") from None
    if client is not None:
        yield client, {"kind": "client", "address": str(getattr(client, "scheduler", ""))}
        return
    if scheduler:
        try:
            connected = distributed.Client(scheduler, timeout=30)
        except (OSError, TimeoutError, ValueError) as err:  # ValueError: a malformed address
            raise OutputError(f"--scheduler {scheduler}: cannot connect ({_one_line(err)}); "
                              "start the scheduler first, or leave out --scheduler for a "
                              "local cluster") from None
        with connected:
            yield connected, {"kind": "scheduler", "address": scheduler}
        return
    n = workers or _usable_cores()
    quiet = logging.getLogger("distributed")
    if quiet.getEffectiveLevel() < logging.WARNING and not log.isEnabledFor(logging.INFO):
        quiet.setLevel(logging.WARNING)  # the scheduler runs here: its start-up lines are noise
    with dask.config.set({"distributed.scheduler.allowed-failures": 0,
                          "distributed.worker.daemon": False}):
        cluster = distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                           # no dashboard; the scheduler's HTTP routes on
                                           # a free port (8787 by default: two studies at
                                           # once would collide)
                                           dashboard_address=":0",
                                           scheduler_kwargs={"dashboard": False},
                                           silence_logs=logging.ERROR,
                                           env={"NGFRAC_THREADS": "1",
                                                "OMP_NUM_THREADS": "1"})
        with cluster, distributed.Client(cluster) as local:
            yield local, {"kind": "LocalCluster", "workers": n, "threads_per_worker": 1}


def _usable_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def run_study(plan: StudyPlan, out_dir: str | Path, *, workers: int | None = None,
              scheduler: str | None = None, client: Any = None,
              command: list[str] | None = None,
              on_row: Callable[[dict[str, Any]], None] | None = None,
              plots: bool = True) -> StudyResult:
    """Run every scene of ``plan`` into ``out_dir/runs/<name>`` and write the study's table.

    Parameters
    ----------
    plan : from :func:`ngfrac.studies.plan.plan_study`
    out_dir : the study folder (``study.csv``, ``study.json``, ``runs/``, ``plots/``)
    workers : processes of the local cluster (default: the usable cores)
    scheduler : the address of a running Dask scheduler (``tcp://host:8786``) instead
    client : a ``distributed.Client`` to use instead (not closed)
    command : the command line for study.json (default ``sys.argv``)
    on_row : called with each row as its run ends (the command's progress lines)
    plots : write ``plots/<key>.png`` at the end

    Returns
    -------
    StudyResult
        Failed runs are rows with ``status`` "failed" and their ``error``; nothing raises for
        them.

    Raises
    ------
    OutputError
        ``out_dir`` holds a study of another scene or other keys, or a run folder of another
        scene; nothing is written then.
    DaskMissing
        Runs are due and ``distributed`` is not installed.
    """
    started = time.perf_counter()
    out = Path(out_dir)
    _check_study_folder(out, plan)
    runs_dir = out / RUNS
    previous = _previous_rows(out)
    states = {run.name: run_state(runs_dir / run.name, run.scene()) for run in plan.runs}
    rows = {run.name: _row(plan, run, PENDING) for run in plan.runs}
    skipped = [name for name, state in states.items() if state == "finished"]
    for name in skipped:
        rows[name].update(status=FINISHED, wall_s=_float(previous.get(name, {}).get("wall_s")))
        rows[name].update(run_quantities(runs_dir / name))
    due = [run for run in plan.runs if states[run.name] != "finished"]
    info = {"format": STUDY_FORMAT, "format_version": 1, **run_metadata(command),
            "scene_file": str(plan.scene_path.resolve()), "keys": plan.keys,
            "overrides": list(plan.base_overrides),
            "refine": {"keys": list(plan.refine_keys), "ratio": plan.ratio,
                       "levels": plan.levels} if plan.refine_keys else None,
            "runs": [run.name for run in plan.runs], "scheduler": None,
            "threads": 1}  # NGSolve threads of each run (execute_run), not of this process
    if due:
        with study_client(workers, scheduler, client) as (dask_client, described):
            runs_dir.mkdir(parents=True, exist_ok=True)  # Dask there and reached: now write
            info["scheduler"] = described
            _write_json(out, info)
            for run in due:
                rows[run.name]["status"] = RUNNING
            _write(out, plan, rows)
            for name, outcome in _submit(dask_client, due, runs_dir):
                rows[name].update(outcome)
                rows[name].update(run_quantities(runs_dir / name))
                _write(out, plan, rows)
                if on_row is not None:
                    on_row(rows[name])
    table = _write(out, plan, rows)  # unchanged content: not rewritten
    if due or read_json(out) is None:  # nothing ran: study.json and the plots stay
        info["wall_s"] = time.perf_counter() - started
        _write_json(out, info)
        if plots:
            from .plots import plot_study

            plot_study(out, plan, table)
    return StudyResult(out, table, skipped, time.perf_counter() - started)


def _submit(client: Any, due: list[PlannedRun], runs_dir: Path,
            task: Callable[..., dict[str, Any]] = execute_run) -> Iterator[tuple[str, dict]]:
    """Submit ``task(folder, data, scene_name)`` of each due run (:func:`execute_run`); yield
    (name, outcome) as each ends (a dead worker or a lost connection: failed)."""
    from distributed import as_completed

    futures = {}
    for run in due:
        future = client.submit(task, str(runs_dir / run.name), run.data, run.scene_name,
                               key=f"ngfrac-run-{run.name}-{time.time_ns()}", pure=False)
        futures[future] = run.name
    for future in as_completed(futures):
        name = futures[future]
        try:
            yield name, future.result()
        except Exception as error:  # noqa: BLE001 - a killed worker, a lost connection
            yield name, {"status": FAILED, "error": _one_line(error), "wall_s": math.nan}


def _row(plan: StudyPlan, run: PlannedRun, status: str) -> dict[str, Any]:
    row: dict[str, Any] = dict(run.values)
    row.update(name=run.name, status=status, error="", wall_s=math.nan)
    if plan.refine_keys:
        row["level"] = run.level
    return row


def _float(text: Any) -> float:
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def _write(out: Path, plan: StudyPlan, rows: dict[str, dict[str, Any]]) -> list[dict[str, Any]]:
    """study.csv from the rows (and the Richardson columns of a refinement study)."""
    table = [dict(rows[run.name]) for run in plan.runs]
    if plan.refine_keys:
        add_richardson(plan, table)
    first = plan.keys + (["level"] if plan.refine_keys else []) + list(FIXED_COLUMNS)
    write_table(out / "study.csv", table, first)
    return table


def quantity_names(table: list[dict[str, Any]]) -> list[str]:
    """The headline quantities present in the rows (crack_length, ..., peak_F...)."""
    from .table import QUANTITIES

    names = list(QUANTITIES)
    for row in table:
        names += [key for key in row if key.startswith("peak_") and key not in names
                  and not key.endswith(RICHARDSON_COLUMNS)]
    return names


RICHARDSON_COLUMNS = ("_extrapolated", "_order", "_gci", "_estimate", "_spread")
"""The suffixes of the columns :func:`add_richardson` adds to a quantity's name."""


def add_richardson(plan: StudyPlan, table: list[dict[str, Any]]) -> None:
    """Add ``<q>_extrapolated``, ``<q>_order``, ``<q>_gci``, ``<q>_estimate`` and
    ``<q>_spread`` (the range of the three finest levels: a measured fact, not an error
    estimate) to the row of the finest level of each group (the runs that differ only in the
    refinement level), for every quantity ``q``
    (:func:`ngfrac.studies.richardson.richardson`)."""
    groups: dict[tuple, list[dict[str, Any]]] = {}
    for row in table:
        key = tuple(json.dumps(row.get(k), sort_keys=True) for k in plan.grouping_keys)
        groups.setdefault(key, []).append(row)
    for members in groups.values():
        members.sort(key=lambda row: row["level"])
        finest = members[-1]
        if any(row["status"] != FINISHED for row in members):
            for name in quantity_names(table):
                finest[f"{name}_estimate"] = "runs unfinished"
            continue
        for name in quantity_names(table):
            values = [_float(row.get(name)) for row in members]
            estimate = richardson(values, plan.ratio or 2.0)
            finest[f"{name}_extrapolated"] = estimate.extrapolated
            finest[f"{name}_order"] = estimate.order
            finest[f"{name}_gci"] = estimate.gci
            finest[f"{name}_estimate"] = estimate.status
            finest[f"{name}_spread"] = max(values[-3:]) - min(values[-3:])


def _check_study_folder(out: Path, plan: StudyPlan) -> None:
    if out.exists() and not out.is_dir():
        raise OutputError(f"--out {str(out)!r} is a file; give a folder for the study")
    info = read_json(out)
    if info is None:
        if out.is_dir() and (out / "study.csv").exists():
            raise OutputError(f"{str(out / 'study.csv')!r} exists but {str(out)!r} has no "
                              "study.json; move it away or use another --out")
        return
    same = (info.get("scene_file") == str(plan.scene_path.resolve())
            and list(info.get("keys", [])) == plan.keys)
    if not same:
        raise OutputError(f"{str(out)!r} holds a study of {info.get('scene_file')!r} over "
                          f"{info.get('keys')}; use another --out for this one")


def read_json(out: Path) -> dict[str, Any] | None:
    """``out/study.json``, or None without one."""
    path = out / "study.json"
    if not path.is_file():
        return None
    try:
        data = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        raise OutputError(f"{str(path)!r} is not readable JSON; move it away or use another "
                          "--out") from None
    if not isinstance(data, dict) or data.get("format") != STUDY_FORMAT:
        raise OutputError(f"{str(path)!r} was not written by ngfrac study; use another --out")
    return data


def _write_json(out: Path, info: dict[str, Any]) -> None:
    atomic_write_text(out / "study.json", json.dumps(info, indent=1, default=str) + "\n")


def _previous_rows(out: Path) -> dict[str, dict[str, str]]:
    path = out / "study.csv"
    if not path.is_file():
        return {}
    return {row.get("name", ""): row for row in read_table(path)}
