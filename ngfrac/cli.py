"""Command line: ``ngfrac run SCENE.toml --out DIR`` and ``ngfrac check SCENE.toml``.

Bad input exits with status 2 and one line on stderr; no traceback.
"""
from __future__ import annotations

import argparse
import logging
import sys

from .output import OutputError
from .scene import SceneError, load_scene
from .stepper import SolverError

EXIT_BAD_INPUT = 2
EXIT_SOLVER = 3


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="ngfrac", description="Phase-field crack propagation "
                                     "on adaptive NGSolve meshes.")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a scene")
    run.add_argument("scene", help="scene file (TOML)")
    run.add_argument("--out", required=True, help="output folder")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene key, e.g. --set time.t_end=0.05 (repeatable)")
    run.add_argument("--overwrite", action="store_true", help="replace an earlier run in --out")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    run.add_argument("--no-plots", action="store_true", help="skip history.png and crack.png")
    run.add_argument("-v", "--verbose", action="store_true", help="log at INFO level")
    check = sub.add_parser("check", help="validate a scene file and exit")
    check.add_argument("scene")
    check.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    return parser


def _fail(message: str, code: int = EXIT_BAD_INPUT) -> int:
    print(f"ngfrac: error: {message}", file=sys.stderr)
    return code


def _run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from .runner import run_scene

    scene = load_scene(args.scene, args.overrides)
    bar = tqdm(total=scene.time.n_steps, unit="step", disable=args.no_progress,
               desc=scene.name, dynamic_ncols=True)
    state = {"tip_x": float("nan")}

    def progress(record) -> None:
        if record.has_diagnostics:
            state["tip_x"] = record.tip_x
        bar.set_postfix(t=f"{record.t:.4g}", nv=record.nv, tip_x=f"{state['tip_x']:.3f}", refresh=False)
        bar.update(1)

    try:
        summary = run_scene(scene, args.out, overwrite=args.overwrite, on_record=progress,
                            plots=not args.no_plots)
    finally:
        bar.close()
    last = summary.last
    print(f"{scene.name}: {last.step} steps to t = {last.t:.4g} in {last.wall_s:.1f} s; "
          f"crack length {last.crack_length:.4f}, tip ({last.tip_x:.3f}, {last.tip_y:.3f}); "
          f"results in {summary.out_dir}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``ngfrac`` command."""
    args = _parser().parse_args(argv)
    logging.basicConfig(level=logging.INFO if getattr(args, "verbose", False) else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    try:
        if args.command == "check":
            scene = load_scene(args.scene, args.overrides)
            print(f"{args.scene}: scene {scene.name!r} is valid ({scene.time.n_steps} steps, "
                  f"model {scene.model.kind})")
            return 0
        return _run(args)
    except (SceneError, OutputError) as err:
        return _fail(str(err))
    except SolverError as err:
        return _fail(str(err), EXIT_SOLVER)
    except KeyboardInterrupt:
        return _fail("interrupted", 130)


if __name__ == "__main__":
    sys.exit(main())
