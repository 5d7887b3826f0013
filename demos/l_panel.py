"""Demo: the L-shaped panel (Winkler's concrete test) with PF-CZM (Wu 2017, Cornelissen
softening, Rankine drive); the crack nucleates at the re-entrant corner and curves.

    python demos/l_panel.py [OUT_DIR] [--set key=value ...]

`l_panel.toml` is a CAD domain (``geometry.kind = "occ"``: an L-shaped polygon and a small
loading pad, its edges named by bounding boxes) with no initial crack, in mm and kN, plane
stress, PF-CZM with a strength f_t (so the peak does not depend on epsilon; the scene's
comment gives each parameter's source and docs/validation.md the measured peak). The
bottom of the vertical leg is clamped and the pad under the horizontal arm, 30 mm from its
end, is pulled up by t mm. The elastic stresses are singular at the re-entrant corner
(250, 250) (stress ~ r^-0.456 at a 270 degree corner), so the crack set first appears there
(``stepper.nucleus``) and then runs into the vertical leg, curving upward, while the force on
the pad falls. Writes history.csv (Fy_load, uy_load: the pad's force in kN per mm of
thickness and its displacement in mm), force_displacement.png, nucleus.json, VTK,
history.png and crack.png, and prints the nucleation point and the peak force.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ngfrac import PhaseFieldStepper, RunSummary

from _common import command_line, run_specimen, write_json

SCENE = Path(__file__).with_suffix(".toml")
CORNER = np.array([250.0, 250.0])
"""The re-entrant corner (mm)."""


def main(out_dir: str | Path = "out/l_panel", overrides: Sequence[str] = (),
         on_step: Callable[[PhaseFieldStepper], None] | None = None) -> RunSummary:
    run = run_specimen(SCENE, out_dir, overrides, on_step, ("uy_load", "Fy_load"))
    run.plot(("F_y load", "u_y load"))
    scene, summary, stepper, history, out = (run.scene, run.summary, run.stepper, run.history,
                                             run.out)
    u, force, peak = run.u, run.force, run.peak
    nucleus = stepper.nucleus
    distance = (float(np.linalg.norm(nucleus[:2] - CORNER)) if nucleus is not None
                else float("nan"))
    write_json(out / "nucleus.json", {"nucleus": nucleus, "distance_to_corner_mm": distance,
                                      "peak_force_kN": float(force[peak]),
                                      "u_at_peak_mm": float(u[peak]),
                                      "final_force_kN": float(force[-1])})
    where = "none" if nucleus is None else f"({nucleus[0]:.1f}, {nucleus[1]:.1f})"
    print(f"{scene.name}: the crack nucleated at {where} mm, {distance:.1f} mm from the "
          f"re-entrant corner; peak force {force[peak]:.4g} kN/mm at u = {u[peak]:.4g} mm, "
          f"{force[-1]:.4g} kN/mm at the end; wall time {summary.last.wall_s:.1f} s; "
          f"results in {out_dir}")
    return summary


if __name__ == "__main__":
    command_line(main, "out/l_panel")
