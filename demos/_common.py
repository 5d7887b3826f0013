"""What the mode III demo scripts share: run a scene through the API and say what the crack did."""
from __future__ import annotations

import sys
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ngfrac import PhaseFieldStepper, RunSummary, load_scene, run_scene
from ngfrac.plotting import read_history


def run_and_report(scene_file: Path, out_dir: str | Path, overrides: Sequence[str] = (),
                   on_step: Callable[[PhaseFieldStepper], None] | None = None) -> RunSummary:
    """Run ``scene_file`` into ``out_dir`` and print how far the crack ran and how straight."""
    scene = load_scene(scene_file, list(overrides))
    summary = run_scene(scene, out_dir, overwrite=True, on_step=on_step)
    history = read_history(Path(out_dir) / "history.csv")
    deviation = np.nanmax(np.abs(history["tip_y"] - scene.cracks[0].points[-1][1]))
    print(f"{scene.name}: tip reached x = {np.nanmax(history['tip_x']):.3f} "
          f"(right edge at {scene.geometry.origin[0] + scene.geometry.width}); "
          f"largest tip deviation from the slit's line {deviation:.3f}; "
          f"wall time {summary.last.wall_s:.1f} s; results in {out_dir}")
    return summary


def command_line(main: Callable[..., RunSummary], default_out: str) -> None:
    """``python demos/NAME.py [OUT_DIR] [--set key=value ...]``."""
    args = sys.argv[1:]
    out = args.pop(0) if args and not args[0].startswith("--") else default_out
    main(out, [value for flag, value in zip(args[::2], args[1::2]) if flag == "--set"])
