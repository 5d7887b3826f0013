"""Demo: three-point bending of a notched beam (Miehe et al. 2010) and its force-deflection
curve.

    python demos/three_point_bending.py [OUT_DIR] [--set key=value ...]

`three_point_bending.toml` is a CAD domain (``geometry.kind = "occ"``: the beam and three
small pads, the pads' faces named by bounding boxes) with the notch as an initial crack, in
mm and kN. The top pad is pushed down by t mm between two supports. The crack grows from the
notch tip (4, 0.4) straight up the symmetry line x = 4 while the force on the top pad falls.
The crack model is AT2 with Miehe's split in the hybrid formulation; only the pads are
damage-free.

What to expect. LEFM for this specimen (span S = 8, height W = 2, a/W = 0.2; Srawley's
formula for S/W = 4, accurate to 0.5 %) gives K_I = 3.323 P, so a sharp crack starts to grow
at P_c = 0.0322 kN per mm of thickness (:func:`lefm_onset`). The phase field's peak force is
near it (AT2 damages the ligament before the peak; the band's toughness is
gamma (1 + h/(2 epsilon))). Writes history.csv (Fy_load, uy_load: the top pad's force in kN
per mm of thickness and its displacement in mm; the force pushes down, so both are negative),
force_displacement.png, peak.json, VTK, history.png and crack.png, and prints the peak force.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ngfrac import PhaseFieldStepper, RunSummary, Scene

from _common import command_line, run_specimen, write_json

SCENE = Path(__file__).with_suffix(".toml")
SPAN, HEIGHT, NOTCH = 8.0, 2.0, 0.4
"""The beam's span between the supports, its height and the notch depth (mm)."""


def srawley_f(ratio: float) -> float:
    """Srawley's (1976) geometry factor of the three-point bend specimen with S/W = 4:
    K_I = P S / (B W^1.5) f(a/W), within 0.5 % for 0 <= a/W <= 1."""
    r = ratio
    return (3 * math.sqrt(r) * (1.99 - r * (1 - r) * (2.15 - 3.93 * r + 2.7 * r * r))
            / (2 * (1 + 2 * r) * (1 - r) ** 1.5))


def lefm_onset(scene: Scene) -> float:
    """The force (per unit thickness) at which the sharp notch starts to grow by Griffith:
    G = K_I^2 (1 - nu^2)/E = G_c (plane strain), K_I from :func:`srawley_f`."""
    lam, mu = scene.material.lam, scene.material.mu
    young = mu * (3 * lam + 2 * mu) / (lam + mu)
    nu = lam / (2 * (lam + mu))
    k_per_force = SPAN / HEIGHT ** 1.5 * srawley_f(NOTCH / HEIGHT)
    gamma = 5e-4  # the beam's G_c (only the pads are tougher, see the scene file)
    return math.sqrt(gamma * young / (1 - nu ** 2)) / k_per_force


def main(out_dir: str | Path = "out/three_point_bending", overrides: Sequence[str] = (),
         on_step: Callable[[PhaseFieldStepper], None] | None = None) -> RunSummary:
    run = run_specimen(SCENE, out_dir, overrides, on_step, ("uy_load", "Fy_load"), sign=-1.0)
    run.plot(("-F_y load", "deflection"))
    scene, summary, history, out = run.scene, run.summary, run.history, run.out
    u, force, peak = run.u, run.force, run.peak
    p_c = lefm_onset(scene)
    write_json(out / "peak.json", {"peak_force_kN": float(force[peak]),
                                   "deflection_at_peak_mm": float(u[peak]),
                                   "final_force_kN": float(force[-1]),
                                   "lefm_onset_kN": p_c,
                                   "epsilon": scene.phase_field.epsilon})
    print(f"{scene.name}: peak force {force[peak]:.4g} kN/mm at a deflection of "
          f"{u[peak]:.4g} mm (LEFM start of growth {p_c:.4g} kN/mm); "
          f"{force[-1]:.4g} kN/mm at the end; the tip reached y = "
          f"{np.nanmax(history['tip_y']):.3f} at x = "
          f"{history['tip_x'][np.nanargmax(history['tip_y'])]:.3f}; "
          f"wall time {summary.last.wall_s:.1f} s; results in {out_dir}")
    return summary


if __name__ == "__main__":
    command_line(main, "out/three_point_bending")
