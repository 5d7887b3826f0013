"""Demo: a plate with a circular hole pulled apart; the crack nucleates at the hole.

    python demos/plate_hole.py [OUT_DIR] [--set key=value ...]

`plate_hole.toml` is a CAD domain (``geometry.kind = "occ"``: a square minus a circle, its
edges named by selectors) with no initial crack. The hoop stress of an infinite plate with a
hole under uniaxial tension (Kirsch) is three times the far-field stress where the hole meets
the line through its centre normal to the load: (0.4, 0.5) and (0.6, 0.5). The crack set first
appears there (``stepper.nucleus``) and runs sideways to the edges while the force on the top
falls. Writes history.csv (Fy_top, uy_top in kN and mm), force_displacement.png, nucleus.json,
VTK, history.png and crack.png, and prints the nucleation point and the peak force.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ngfrac import PhaseFieldStepper, RunSummary

from _common import command_line, run_specimen, write_json

SCENE = Path(__file__).with_suffix(".toml")
KIRSCH_POINTS = np.array([[0.4, 0.5], [0.6, 0.5]])
"""Where the hoop stress at the hole peaks (centre (0.5, 0.5), radius 0.1, load along y)."""


def main(out_dir: str | Path = "out/plate_hole", overrides: Sequence[str] = (),
         on_step: Callable[[PhaseFieldStepper], None] | None = None) -> RunSummary:
    run = run_specimen(SCENE, out_dir, overrides, on_step, ("uy_top", "Fy_top"))
    run.plot(("F_y top", "u_y top"))
    scene, summary, stepper, history, out = (run.scene, run.summary, run.stepper, run.history,
                                             run.out)
    u, force, peak = run.u, run.force, run.peak
    nucleus = stepper.nucleus
    distance = (float(np.min(np.linalg.norm(KIRSCH_POINTS - nucleus[:2], axis=1)))
                if nucleus is not None else float("nan"))
    write_json(out / "nucleus.json", {"nucleus": nucleus, "distance_to_kirsch_point": distance,
                                      "peak_force_kN": float(force[peak]),
                                      "u_at_peak_mm": float(u[peak]),
                                      "final_force_kN": float(force[-1])})
    where = "none" if nucleus is None else f"({nucleus[0]:.3f}, {nucleus[1]:.3f})"
    print(f"{scene.name}: the crack nucleated at {where}, {distance:.3f} mm from the nearest "
          f"Kirsch point; peak force {force[peak]:.4f} kN at u = {u[peak]:.4g} mm, "
          f"{force[-1]:.4f} kN at the end; wall time {summary.last.wall_s:.1f} s; "
          f"results in {out_dir}")
    return summary


if __name__ == "__main__":
    command_line(main, "out/plate_hole")
