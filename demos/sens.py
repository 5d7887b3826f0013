"""Demo: single-edge notched shear (Miehe et al. 2010), force-displacement curve and crack path.

    python demos/sens.py [OUT_DIR] [--set key=value ...]

Writes history.csv (columns Fx_top, ux_top: the shear force on the top edge in kN per mm of
thickness and its displacement in mm), force_displacement.png, path.json, VTK, history.png and
crack.png.

What to expect. The top slides in +x, so the upper face of the notch slides in +x relative to
the lower one: pure mode II with K_II > 0 (LEFM, :func:`ngfrac.post.crackpath.griffith_onset`:
K_I/K_II = 0.000, G = 29.8 u^2, F = 63.3 u), and the maximum hoop stress would kink the crack
downwards by -70.5 degrees, towards the bottom right corner; that is what models with a
tension/compression split show (Miehe et al.: a curved crack down to the bottom right, peak
about 0.5-0.55 kN near u = 0.01 mm). Griffith puts the start of growth of the sharp notch at
u = 9.5e-3 mm, F = 0.60 kN.

This demo's model, AT2 without a split (the paper's; sens.toml), lets sigma:e drive z
whatever the sign of the stresses, and ahead of a mode II tip sigma:e is largest straight
ahead (the shear strain), not along the hoop-stress direction. So the notch grows straight
ahead as a shear band along y = 0.5 to the right edge, and the force peaks and then drops
to nearly zero. Measured (``python demos/sens.py``,
epsilon = 0.015 mm, P2, adaptive up to 8,000 vertices, adaptive steps of 2e-5..3.2e-4 mm,
261 steps to u = 0.018 mm; 4.8 min with ``NGFRAC_THREADS=1`` while the test suite ran on the
other core): peak 0.509 kN at u = 0.0101 mm (16% below the sharp notch's Griffith load
0.603 kN at 0.0095 mm), the crack straight (+0.8 degrees) to the right edge, below 0.005 kN
from u = 0.0118 mm on. With fixed steps of 2e-5 mm (``--set time.adaptive=false --set time.t_end=1.3e-2``, 650 steps,
27 min on the machine shared at a load of about 8, before relax_core): peak 0.512 kN at
u = 0.0102 mm.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ngfrac import PhaseFieldStepper, RunSummary, load_scene
from ngfrac.post.crackpath import griffith_onset, history_path, measure_kink, tip_and_direction
from ngfrac.io.plotting import read_history

from _common import (command_line, plot_force_displacement, run_keeping_stepper,  # demos/_common.py
                     write_json)

SCENE = Path(__file__).with_suffix(".toml")


def main(out_dir: str | Path = "out/sens", overrides: Sequence[str] = (),
         on_step: Callable[[PhaseFieldStepper], None] | None = None) -> RunSummary:
    scene = load_scene(SCENE, list(overrides))
    estimate = griffith_onset(scene, "Fx_top")
    print(f"{scene.name}: LEFM K_I/K_II = {estimate['K_I'] / estimate['K_II']:.3f}, kink "
          f"{estimate['kink_deg']:.1f} deg; the sharp notch starts to grow at u = "
          f"{estimate['t_c']:.3g} mm, F = {estimate['F_c']:.3f} kN")
    summary, stepper = run_keeping_stepper(scene, out_dir, on_step)
    out = Path(out_dir)
    history = read_history(out / "history.csv")
    u, force = history["ux_top"], history["Fx_top"]
    peak = int(np.argmax(force))
    eps = scene.phase_field.epsilon
    plot_force_displacement(u, force, out / "force_displacement.png",
                            f"{scene.name}: epsilon = {eps:g} mm", ("F_x top", "u_x top"),
                            curve="phase field (no split)")
    origin, reference = tip_and_direction(scene.cracks[0].points)
    try:
        angle, path = measure_kink(stepper, eps, 6 * eps)
    except ValueError:  # the crack has not grown 6 epsilon
        angle, path = float("nan"), None
    track = history_path(history, origin, reference, max_jump=0.1)
    result = {"peak_force_kN": float(force[peak]), "u_at_peak_mm": float(u[peak]),
              "final_force_kN": float(force[-1]), "epsilon": eps, "kink_deg": angle,
              "lefm": {k: float(v) for k, v in estimate.items()},
              "path": [] if path is None else path.points.tolist(),
              "tip_track": track.points.tolist()}
    write_json(out / "path.json", result)
    lowest = track.points[:, 1].min() if len(track.points) else origin[1]
    print(f"{scene.name}: peak force {force[peak]:.4f} kN at u = {u[peak]:.4g} mm; force at the "
          f"end {force[-1]:.4f} kN; crack direction {angle:.1f} deg over {eps:g}..{6 * eps:g} mm "
          f"from the notch tip, tip track down to y = {lowest:.3f}; wall time "
          f"{summary.last.wall_s:.1f} s; results in {out_dir}")
    if path is not None:
        print(path.text(every=3))
    return summary


if __name__ == "__main__":
    command_line(main, "out/sens")
