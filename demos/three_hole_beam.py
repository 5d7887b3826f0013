"""Demo: the asymmetric notched beam with three holes (Bittencourt et al. 1996, Ambati et al.
2015); the crack runs from the notch into a hole.

    python demos/three_hole_beam.py [OUT_DIR] [--set key=value ...]

`three_hole_beam.toml` is a CAD domain (``geometry.kind = "occ"``: the beam, three holes cut
out and three small pads, the pads' faces named by bounding boxes) with the notch as an
initial crack, in mm and kN. The top pad at x = 10 is pushed down by t mm between supports at
x = 1 and 19; the notch at x = 4 is off the middle, so the crack grows in mixed mode, curves
towards the load, and the holes at x = 6 draw it in. Bittencourt's experiment and Ambati et
al.'s phase field for this layout: into the middle hole (6, 4.75). The crack model is AT2
with Miehe's split in the hybrid formulation (Ambati et al.'s), uniform toughness, only the
pads damage-free; the crack reaches the lower hole (docs/validation.md).

Which hole (:func:`hole_reached`): the first hole whose edge a crack tip of the history comes
within 2 epsilon of (the band's half width: the crack set {z >= 1/2} then touches the hole);
if none yet, the hole nearest the ray from the notch tip through the last tip (the one it
heads for). Writes history.csv
(Fy_load, uy_load: the top pad's force in kN per mm of thickness and its displacement in mm,
both negative), force_displacement.png, path.json (the tip track, the hole reached), VTK,
history.png and crack.png, and prints the hole and the peak force.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ngfrac import PhaseFieldStepper, RunSummary

from _common import command_line, run_specimen, write_json

SCENE = Path(__file__).with_suffix(".toml")
NOTCH_TIP = np.array([4.0, 1.0])
"""The notch's tip (mm)."""
HOLES = {"lower": np.array([6.0, 2.75]), "middle": np.array([6.0, 4.75]),
         "upper": np.array([6.0, 6.75])}
"""The holes' centres (mm)."""
RADIUS = 0.25
"""The holes' radius (mm)."""
PUBLISHED = "middle"
"""The hole Bittencourt et al.'s crack and Ambati et al.'s phase field run into."""


def tip_track(history: dict) -> np.ndarray:
    """The crack tips of the history that have left the notch tip, (n, 2), in order."""
    tips = np.column_stack([history["tip_x"], history["tip_y"]])
    tips = tips[np.isfinite(tips).all(axis=1)]
    return tips[np.linalg.norm(tips - NOTCH_TIP, axis=1) > 1e-9]


def heading(history: dict) -> str:
    """The hole the crack heads for: the one whose centre is nearest the ray from the notch
    tip through the last tip ("" without growth)."""
    tips = tip_track(history)
    if not len(tips):
        return ""
    direction = (tips[-1] - NOTCH_TIP) / np.linalg.norm(tips[-1] - NOTCH_TIP)

    def off_ray(centre: np.ndarray) -> float:
        along = max(float((centre - NOTCH_TIP) @ direction), 0.0)
        return float(np.linalg.norm(centre - NOTCH_TIP - along * direction))

    return min(HOLES, key=lambda name: off_ray(HOLES[name]))


def hole_reached(history: dict, epsilon: float) -> tuple[str, bool]:
    """The hole the crack reached (True) or heads for (False, :func:`heading`): the first
    hole whose edge a tip comes within 2 epsilon of ("" without growth)."""
    for tip in tip_track(history):
        for name, centre in HOLES.items():
            if np.linalg.norm(tip - centre) < RADIUS + 2 * epsilon:
                return name, True
    return heading(history), False


def main(out_dir: str | Path = "out/three_hole_beam", overrides: Sequence[str] = (),
         on_step: Callable[[PhaseFieldStepper], None] | None = None) -> RunSummary:
    run = run_specimen(SCENE, out_dir, overrides, on_step, ("uy_load", "Fy_load"), sign=-1.0)
    run.plot(("-F_y load", "deflection"))
    scene, summary, history, out = run.scene, run.summary, run.history, run.out
    u, force, peak = run.u, run.force, run.peak
    eps = scene.phase_field.epsilon
    hole, reached = hole_reached(history, eps)
    tips = tip_track(history)
    write_json(out / "path.json", {"hole": hole, "reached": reached, "published": PUBLISHED,
                                   "tips": tips, "peak_force_kN": float(force[peak]),
                                   "deflection_at_peak_mm": float(u[peak]),
                                   "final_force_kN": float(force[-1]), "epsilon": eps})
    where = "did not grow from the notch" if not hole else (f"reached the {hole} hole" if reached
                                          else f"heads for the {hole} hole")
    print(f"{scene.name}: the crack {where} (published: the {PUBLISHED} hole); peak force "
          f"{force[peak]:.4g} kN/mm at a deflection of {u[peak]:.4g} mm, {force[-1]:.4g} at the "
          f"end; wall time {summary.last.wall_s:.1f} s; results in {out_dir}")
    return summary


if __name__ == "__main__":
    command_line(main, "out/three_hole_beam")
