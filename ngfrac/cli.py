"""Command line: ``ngfrac run SCENE.toml --out DIR``, ``ngfrac run --restart DIR``,
``ngfrac plot DIR``, ``ngfrac check SCENE.toml`` and ``ngfrac study SCENE.toml --vary KEY=V1,V2
--out DIR`` (:mod:`ngfrac.studies`; exit 1 when a run of the study failed).

Bad input exits with status 2 and one line on stderr; no traceback. Resolution warnings
(:func:`ngfrac.mesh.resolution.resolution_warnings`) are one line each on stderr; ``--strict`` makes
them exit 2 before anything is written. A meshing or solver failure during the run exits 3.
Under ``mpirun -np N`` (N >= 3) the run is distributed (:mod:`ngfrac.parallel`); rank 0 prints.
``NGFRAC_THREADS`` caps the threads of a run (applied by :func:`ngfrac.runner.run_scene`).
"""
from __future__ import annotations

import argparse
import logging
import sys
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

from .io.checkpoint import CheckpointError
from .mesh.resolution import ResolutionWarning, resolution_warnings
from .geometry.domains import MeshingError
from .io.output import OutputError
from .io.hdf5 import ResultsError
from .parallel.communicator import launched_rank
from .solve.communicator import ParallelError
from .scene import Scene, SceneError, load_scene
from .solve.stepper import SolverError
from .studies.engine import DaskMissing

if TYPE_CHECKING:
    from .solve.records import StepRecord

EXIT_BAD_INPUT = 2
EXIT_SOLVER = 3
STRICT_HELP = "treat resolution warnings as errors (exit 2)"


class _Strict(Exception):
    """--strict and the scene has resolution warnings (already printed)."""


class _Interrupted(Exception):
    """Ctrl-C during a run: the message says how to continue it."""


def _check_scene_path(path: str) -> None:
    """A scene argument that is a folder: say what to give instead (one line)."""
    if Path(path).is_dir():
        hint = (f"; to continue the run in it: ngfrac run --restart {path}"
                if (Path(path) / "scene.toml").is_file() else "")
        raise SceneError(f"{path!r} is a folder, not a scene file; give a scene file (TOML)"
                         f"{hint}")


def _check_run_folder(folder: Path, option: str) -> None:
    """The folder of ``--restart`` exists and holds a run (its scene.toml)."""
    if not folder.is_dir():
        raise OutputError(f"{option} {str(folder)!r}: no such run folder; give the --out "
                          "folder of an earlier ngfrac run")
    if not (folder / "scene.toml").is_file():
        raise OutputError(f"{option} {str(folder)!r} is not a run folder (no scene.toml); give "
                          "the --out folder of an earlier ngfrac run")


def _interrupted(out: Path) -> str:
    """The line for a run stopped by Ctrl-C: from which step ``--restart`` continues it."""
    import h5py

    path = out / "checkpoint.h5"
    try:
        with h5py.File(path, "r") as f:
            step, t = int(f.attrs["k"]), float(f.attrs["t"])
    except (OSError, KeyError, ValueError):
        return (f"interrupted; no checkpoint in {str(out)!r} to continue from (they are "
                "written every output.checkpoint_every steps): run it again with --overwrite")
    return (f"interrupted; ngfrac run --restart {out} continues from step {step} "
            f"(t = {t:.6g}), its last checkpoint")


def summary_line(scene: Scene, last: "StepRecord", out: Path) -> str:
    """The line ``ngfrac run`` prints at the end: steps, time, the crack's geometric length
    (2D: ``path_length``) before the Gamma-functional ``crack_length``, the tip, the folder."""
    tip = ", ".join(f"{v:.3f}" for v in (last.tip_x, last.tip_y, last.tip_z) if v == v)
    dim = scene.geometry.dim
    measured = "area" if dim == 3 else "length"
    geometric = (f"crack path length {last.path_length:.4f}, " if dim == 2 else "")
    return (f"{scene.name}: {last.step} steps to t = {last.t:.4g} in {last.wall_s:.1f} s; "
            f"{geometric}Gamma-functional crack {measured} {last.crack_length:.4f}, "
            f"tip ({tip}); results in {out}")


def build_parser() -> argparse.ArgumentParser:
    """The ``ngfrac`` argument parser: the subcommands and flags of the user guide's CLI table."""
    parser = argparse.ArgumentParser(prog="ngfrac", description="Phase-field crack propagation "
                                     "on adaptive NGSolve meshes.")
    parser.add_argument("--version", action="version", version=_version_line(),
                        help="print the versions of ngfrac, NGSolve and Python and exit")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a scene, or continue one with --restart")
    run.add_argument("scene", nargs="?", help="scene file (TOML)")
    run.add_argument("--out", help="output folder (required unless --restart)")
    run.add_argument("--restart", metavar="DIR", help="continue the run in DIR (or DIR/checkpoint.h5) "
                     "from its last checkpoint (one is written at the end of every run); --set "
                     "may extend time.t_end")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene key, e.g. --set time.t_end=0.05 (repeatable)")
    run.add_argument("--overwrite", action="store_true", help="replace an earlier run in --out")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    run.add_argument("--no-plots", action="store_true",
                     help="skip history.png, crack.png and force_displacement.png")
    run.add_argument("--profile", action="store_true", help="print the wall time of each phase at the end")
    run.add_argument("--strict", action="store_true", help=STRICT_HELP)
    run.add_argument("-v", "--verbose", action="store_true", help="log at INFO level")
    plot = sub.add_parser("plot", help="write the figures of a run folder into DIR/plots")
    plot.add_argument("folder", help="a run folder written by ngfrac run")
    plot.add_argument("--times", type=float, nargs="*", default=None,
                      help="times of the phase-field pictures (default: first, middle, last snapshot)")
    study = sub.add_parser("study", help="run a scene over several values of its keys (Dask), "
                           "with a table of headline numbers and error bars")
    study.add_argument("scene", help="scene file (TOML)")
    study.add_argument("--out", required=True, help="study folder: runs/, study.csv, study.json, plots/")
    study.add_argument("--vary", action="append", default=[], metavar="KEY=V1,V2,...",
                       help="run every value of KEY (repeatable: the product of the lists)")
    study.add_argument("--zip", dest="zipped", action="append", default=[], metavar="KEY=V1,V2,...",
                       help="lists of one length, paired value by value (repeatable)")
    study.add_argument("--refine", action="append", default=[], metavar="KEY",
                       help="a discretization key refined over --levels levels by --ratio "
                       "(repeatable: refined together); adds Richardson estimates and GCIs")
    study.add_argument("--ratio", type=float, default=2.0,
                       help="refinement ratio of --refine (default 2: sizes halve per level)")
    study.add_argument("--levels", type=int, default=3, help="refinement levels (default 3)")
    study.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                       help="override a scene key in every run (repeatable)")
    study.add_argument("--workers", type=int, default=None,
                       help="processes of the local Dask cluster (default: the cores)")
    study.add_argument("--scheduler", metavar="ADDRESS",
                       help="a running Dask scheduler (tcp://host:8786) instead of a local cluster")
    study.add_argument("--no-plots", action="store_true", help="skip plots/<key>.png")
    study.add_argument("-v", "--verbose", action="store_true", help="log at INFO level")
    check = sub.add_parser("check", help="validate a scene file and exit")
    check.add_argument("scene")
    check.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    check.add_argument("--strict", action="store_true", help=STRICT_HELP)
    return parser


def _version_line() -> str:
    import platform

    import ngsolve

    from . import __version__

    return f"ngfrac {__version__} (NGSolve {ngsolve.__version__}, Python {platform.python_version()})"


def _plot(args: argparse.Namespace) -> int:
    """``ngfrac plot DIR``: the figures into DIR/plots, each listed in DIR's manifest."""
    from .io.output import Manifest
    from .io.plotting import plot_run

    folder = Path(args.folder)
    if not folder.is_dir():
        raise OutputError(f"run folder {str(folder)!r} does not exist; give the --out folder "
                          "of an ngfrac run")
    if not (folder / "history.csv").is_file():
        raise OutputError(f"{str(folder)!r} is not a run folder (no history.csv); give the "
                          "--out folder of an ngfrac run")
    if args.times:
        _check_plot_times(folder, args.times)
    manifest = Manifest.load(folder) or Manifest.adopt(folder)
    foreign = manifest.foreign("plots/")
    if foreign:
        raise OutputError(f"{str(folder / foreign[0])!r} was not written by ngfrac; move it "
                          "before ngfrac plot replaces it")
    try:
        with manifest.writing("plots/"):
            written = plot_run(folder, args.times)
            manifest.add(*(path.relative_to(folder).as_posix() for path in written))
    except OSError as err:
        raise OutputError(f"cannot write the plots into {str(folder / 'plots')!r} "
                          f"({err.strerror or err}); make the run folder writable") from None
    for path in written:
        print(path)
    return 0


def _check_plot_times(folder: Path, times: list[float]) -> None:
    """``--times`` within the run's snapshots (a time between two takes the nearest)."""
    from .io.results import open_results

    if not (folder / "results.h5").is_file():
        raise OutputError(f"--times: {str(folder)!r} has no results.h5 (output.results = "
                          "false), so no phase-field pictures; leave out --times")
    available = open_results(folder / "results.h5").snapshot_times()
    if not len(available):
        raise OutputError(f"--times: {str(folder / 'results.h5')!r} holds no snapshot")
    first, last = float(available.min()), float(available.max())
    slack = 1e-9 * max(abs(first), abs(last), 1.0)
    outside = [t for t in times if not first - slack <= t <= last + slack]
    if outside:
        raise OutputError(f"--times {outside[0]:g} is outside the run's snapshots "
                          f"(t = {first:g} to {last:g}); give times in that range")


def _fail(message: str, code: int = EXIT_BAD_INPUT) -> int:
    if launched_rank() == 0:  # under mpirun every rank fails alike: one line
        print(f"ngfrac: error: {message}", file=sys.stderr)
    return code


def _warn_resolution(scene: Scene, strict: bool) -> None:
    """Print the scene's resolution warnings, one line each; with --strict, stop (exit 2).
    Also the rate warning of alpha2 (:func:`ngfrac.scene.rates.rate_warnings`), which
    --strict leaves a warning (a large alpha2 may be meant: demos/sneddon.toml)."""
    from .scene.rates import rate_warnings

    for message in rate_warnings(scene) if launched_rank() == 0 else ():
        print(f"ngfrac: warning: {message}", file=sys.stderr)
    found = resolution_warnings(scene)
    for message in found if launched_rank() == 0 else ():
        print(f"ngfrac: warning: {message}", file=sys.stderr)
    if strict and found:
        raise _Strict(f"--strict: {len(found)} resolution warning(s) above; fix the scene or "
                      "drop --strict")


def _run(args: argparse.Namespace) -> int:
    if bool(args.scene) == bool(args.restart):
        raise SceneError("give a scene file to run, or --restart DIR to continue a run (not both)")
    if args.restart:
        folder = Path(args.restart)
        folder = folder.parent if folder.suffix == ".h5" else folder
        _check_run_folder(folder, "--restart")
        scene = load_scene(folder / "scene.toml", args.overrides)
        out = folder
    else:
        if not args.out:
            raise SceneError("--out DIR is required: the folder the run writes into")
        _check_scene_path(args.scene)
        scene = load_scene(args.scene, args.overrides)
        out = Path(args.out)
    _warn_resolution(scene, args.strict)
    try:
        return _run_scene(args, scene, out)
    except KeyboardInterrupt:
        raise _Interrupted(_interrupted(out)) from None


def _run_scene(args: argparse.Namespace, scene: Scene, out: Path) -> int:
    """The run of ``ngfrac run`` once its scene is read and checked; prints the summary."""
    from .io.writers import Progress
    from .runner import run_scene

    with warnings.catch_warnings():  # printed above, once
        warnings.simplefilter("ignore", ResolutionWarning)
        summary = run_scene(scene, out, overwrite=args.overwrite, plots=not args.no_plots,
                            restart=bool(args.restart),
                            writers=[Progress(scene, disable=args.no_progress)])
    last = summary.last
    if launched_rank() != 0:
        return 0
    print(summary_line(scene, last, summary.out_dir))
    if args.profile:
        print(summary.profile)
    return 0


def _study(args: argparse.Namespace) -> int:
    """``ngfrac study``: every combination validated first (exit 2), then the runs; exit 1 if
    any run failed."""
    from .studies import plan_study, run_study

    if args.workers is not None and args.workers < 1:
        raise SceneError(f"--workers {args.workers}: give a positive number of processes")
    if args.workers is not None and args.scheduler:
        raise SceneError("--workers sizes a local cluster; leave it out with --scheduler")
    _check_scene_path(args.scene)
    plan = plan_study(args.scene, args.vary, args.zipped, args.overrides, args.refine,
                      args.ratio, args.levels)
    print(f"study of {args.scene}: {len(plan.runs)} runs into {args.out}", flush=True)

    def progress(row: dict) -> None:
        error = f": {row['error']}" if row.get("error") else ""
        print(f"  {row['name']}: {row['status']} ({row['wall_s']:.1f} s){error}", flush=True)

    result = run_study(plan, args.out, workers=args.workers, scheduler=args.scheduler,
                       command=sys.argv, on_row=progress, plots=not args.no_plots)
    print(result.summary())
    return 1 if result.failed else 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``ngfrac`` command."""
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=logging.INFO if getattr(args, "verbose", False) else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    try:
        if args.command == "plot":
            return _plot(args)
        if args.command == "study":
            return _study(args)
        if args.command == "check":
            _check_scene_path(args.scene)
            scene = load_scene(args.scene, args.overrides)
            _warn_resolution(scene, args.strict)
            print(f"{args.scene}: scene {scene.name!r} is valid ({scene.time.n_steps} steps, "
                  f"model {scene.model.kind})")
            return 0
        return _run(args)
    except (SceneError, OutputError, CheckpointError, ResultsError, ParallelError, _Strict,
            DaskMissing) as err:
        return _fail(str(err))
    except (SolverError, MeshingError) as err:
        return _fail(str(err), EXIT_SOLVER)
    except _Interrupted as err:
        return _fail(str(err), 130)
    except KeyboardInterrupt:
        return _fail("interrupted", 130)


if __name__ == "__main__":
    sys.exit(main())
