"""What the demo scripts share: run a scene through the API, keep its stepper, measure the
crack path, plot a force-displacement curve, write JSON results, and say what the crack did."""
from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ngfrac import PhaseFieldStepper, RunSummary, Scene, load_scene, run_scene
from ngfrac.post.crackpath import CrackPath, history_path, kink_angle, measure_kink, tip_and_direction
from ngfrac.io.plotting import new_figure, read_history


def json_safe(value: Any) -> Any:
    """``value`` with numpy scalars and arrays as Python numbers and lists, and NaN or
    infinity as None (JSON has no NaN: ``json.dumps`` would write a bare ``NaN``)."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [json_safe(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    return value


def write_json(path: Path, data: Any) -> Path:
    """Write ``data`` as strict JSON (NaN and infinity as null, see :func:`json_safe`)."""
    path.write_text(json.dumps(json_safe(data), indent=1, allow_nan=False) + "\n")
    return path


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


def run_keeping_stepper(scene: Scene, out_dir: str | Path,
                        on_step: Callable[[PhaseFieldStepper], None] | None = None,
                        ) -> tuple[RunSummary, PhaseFieldStepper]:
    """Run ``scene`` into ``out_dir`` and return the summary and the stepper of the last step
    (whose mesh and z the path measurements read)."""
    last: list[PhaseFieldStepper] = []

    def keep(stepper: PhaseFieldStepper) -> None:
        last[:] = [stepper]
        if on_step is not None:
            on_step(stepper)

    summary = run_scene(scene, out_dir, overwrite=True, on_step=keep)
    return summary, last[0]


@dataclass
class SpecimenRun:
    """A specimen demo's run: its scene, summary, last stepper and history, and the load curve
    (displacement ``u`` and ``force`` of the loaded boundary, as the demo orients them)."""

    scene: Scene
    summary: RunSummary
    stepper: PhaseFieldStepper
    history: dict
    out: Path
    u: np.ndarray
    force: np.ndarray

    @property
    def peak(self) -> int:
        """The row of the largest force."""
        return int(np.argmax(self.force))

    def plot(self, label: tuple[str, str], estimate: tuple[float, float] | None = None,
             unit: str = " mm") -> Path:
        """``force_displacement.png`` in the run's folder (:func:`plot_force_displacement`)."""
        return plot_force_displacement(
            self.u, self.force, self.out / "force_displacement.png",
            f"{self.scene.name}: epsilon = {self.scene.phase_field.epsilon:g}{unit}", label,
            estimate=estimate)


def run_specimen(scene_file: Path, out_dir: str | Path, overrides: Sequence[str],
                 on_step: Callable[[PhaseFieldStepper], None] | None,
                 columns: tuple[str, str], sign: float = 1.0) -> SpecimenRun:
    """Run ``scene_file`` into ``out_dir`` keeping the last stepper, and read its load curve:
    the history ``columns`` (displacement, force) times ``sign`` (-1 for a downward load)."""
    scene = load_scene(scene_file, list(overrides))
    summary, stepper = run_keeping_stepper(scene, out_dir, on_step)
    out = Path(out_dir)
    history = read_history(out / "history.csv")
    return SpecimenRun(scene, summary, stepper, history, out, sign * history[columns[0]],
                       sign * history[columns[1]])


def measure_kink_both_ways(stepper: PhaseFieldStepper, scene: Scene, history: dict,
                           rmin: float, rmax: float) -> tuple[float, CrackPath, float]:
    """The kink angle from the ridge of z between ``rmin`` and ``rmax`` from the initial tip,
    that ridge as a path, and the angle from the tip history (nan if too short)."""
    measured, path = measure_kink(stepper, rmin, rmax)
    origin, reference = tip_and_direction(scene.cracks[0].points)
    track = history_path(history, origin, reference, max_jump=0.1)
    try:
        from_history = kink_angle(track, rmin, rmax)
    except ValueError:
        from_history = math.nan
    return measured, path, from_history


def slit_notch(scene: Scene) -> tuple[list[list[float]], list[list[float]]]:
    """The notch of a specimen cut out of an ``occ`` rectangle as a thin slit (SENT, SENS):
    ``(crack, box)``, the slit's centre line from the left edge ``[[x, y], [x, y]]`` and the
    outer rectangle ``[[x0, y0], [x1, y1]]`` (the first shape and the first cut rectangle)."""
    shapes = scene.geometry.shapes
    cuts = [s for s in shapes if s.op == "cut" and s.type == "rectangle"]
    if not shapes or shapes[0].type != "rectangle" or not cuts:
        raise ValueError(f"{scene.name}: the notch is not a cut rectangle in a rectangle")
    (x0, y0), (w, h) = shapes[0].corner, shapes[0].size
    (cx, cy), (cw, ch) = cuts[0].corner, cuts[0].size
    return [[cx, cy + ch / 2], [cx + cw, cy + ch / 2]], [[x0, y0], [x0 + w, y0 + h]]


def plot_force_displacement(u: np.ndarray, force: np.ndarray, png: Path, title: str,
                            label: tuple[str, str], estimate: tuple[float, float] | None = None,
                            curve: str = "phase field") -> Path:
    """The force-displacement curve with its peak marked (and an LEFM estimate, when given)."""
    peak = int(np.argmax(force))
    fig = new_figure(figsize=(6, 4.2), constrained_layout=True)
    ax = fig.subplots()
    ax.plot(u, force, "-", lw=1.5, label=curve)
    ax.plot(u[peak], force[peak], "o", color="C3",
            label=f"peak {force[peak]:.3f} kN at {u[peak]:.3g} mm")
    if estimate is not None:
        ax.plot(*estimate, "x", color="k", ms=9, label="LEFM (sharp crack) start of growth")
    ax.set(xlabel=f"{label[1]} (mm)", ylabel=f"{label[0]} (kN per mm thickness)", title=title)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.savefig(png, dpi=120)
    return png
