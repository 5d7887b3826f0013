"""Demo: single-edge notched shear (Miehe et al. 2010), force-displacement curve and crack path.

    python demos/sens.py [OUT_DIR] [--set key=value ...]

Writes history.csv (columns Fx_top, ux_top: the shear force on the top edge in kN per mm of
thickness and its displacement in mm), force_displacement.png, path.json, VTK, history.png and
crack.png.

What to expect. The top slides in +x, so the upper face of the notch slides in +x relative to
the lower one: pure mode II with K_II > 0 (LEFM, :func:`ngfrac.post.crackpath.griffith_onset`:
K_I/K_II = 0.000, G = 29.8 u^2, F = 63.3 u), and the maximum hoop stress kinks the crack
downwards by -70.5 degrees, towards the bottom right corner. Griffith puts the start of growth
of the sharp notch at u = 9.5e-3 mm, F = 0.60 kN. Miehe et al. (with their spectral split):
a curved crack down to the bottom right, peak 0.531 kN at u = 9.4e-3 mm (their curve as
digitized in phasefieldx).

The scene's crack model is AT2 driven by the tensile part of Miehe's split in the hybrid
formulation (sens.toml): the u-step stays linear (isotropic degradation), z grows only where
the tensile part drives it, so the crack kinks as LEFM says. The notch is a slit 2 um wide
cut out of the geometry: with a split, a band of z0 is a closed crack in shear and the
specimen barely notices it (benchmarks/scenes/sens_band.toml; docs/validation.md, "SENS and
SENT with Miehe's split", which also has this scene at three mesh levels: within 0.05 %).
Without a split (``--set material.split='"none"' --set material.split_mode='"full"'``,
the paper's model) sigma:e, largest straight ahead of a mode II tip, drives z there and the
notch grows straight ahead as a shear band.

Measured (``NGFRAC_THREADS=1 /usr/bin/time -v python demos/sens.py``: epsilon = 0.015 mm, P2,
adaptive up to 8,000 vertices (7,733 reached), the staggered pass in fixed steps of 1e-5 mm,
1,800 to u = 0.018 mm; 467 s of run, 7:53 wall and 466 s CPU in all, load ~2: another run
beside it): peak 0.5498 kN at u = 9.19e-3 mm, 1.035 of Miehe et al.'s 0.531 kN (0.5458 at
steps of 5e-6: the step's share is below 1 %; docs/validation.md), 9 % below the sharp
notch's Griffith load; the crack leaves the notch at -74.4 degrees (the ridge of z between
epsilon and 6 epsilon; -72.1 from the tip track between 2 and 8 epsilon) and reaches the
bottom edge at the right corner; the force at u = 0.018 mm is 0.8 % of the peak. Until
session 26 the demo ran the paper's single pass with adaptive steps (2e-5..3.2e-4 mm, 435
steps, 225 s): 0.5702 kN at 1.022e-2 mm, 1.074 of theirs, the single pass's lag.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ngfrac import PhaseFieldStepper, RunSummary, load_scene
from ngfrac.post.crackpath import griffith_onset, history_path, measure_kink, tip_and_direction
from ngfrac.io.plotting import read_history

from _common import (command_line, plot_force_displacement, run_keeping_stepper,  # demos/_common.py
                     slit_notch, write_json)

SCENE = Path(__file__).with_suffix(".toml")


def main(out_dir: str | Path = "out/sens", overrides: Sequence[str] = (),
         on_step: Callable[[PhaseFieldStepper], None] | None = None) -> RunSummary:
    scene = load_scene(SCENE, list(overrides))
    crack, box = slit_notch(scene)
    estimate = griffith_onset(scene, "Fx_top", crack=crack, box=box)
    print(f"{scene.name}: LEFM K_I/K_II = {estimate['K_I'] / estimate['K_II']:.3f}, kink "
          f"{estimate['kink_deg']:.1f} deg; the sharp notch starts to grow at u = "
          f"{estimate['t_c']:.3g} mm, F = {estimate['F_c']:.3f} kN")
    summary, stepper = run_keeping_stepper(scene, out_dir, on_step)
    out = Path(out_dir)
    history = read_history(out / "history.csv")
    u, force = history["ux_top"], history["Fx_top"]
    peak = int(np.argmax(force))
    eps = scene.phase_field.epsilon
    material = scene.material
    split = ("no split" if material.split == "none"
             else f"{material.split} split, {material.split_mode}")
    plot_force_displacement(u, force, out / "force_displacement.png",
                            f"{scene.name}: epsilon = {eps:g} mm", ("F_x top", "u_x top"),
                            curve=f"phase field ({split})")
    origin, reference = tip_and_direction(crack)
    try:
        angle, path = measure_kink(stepper, eps, 6 * eps, crack=crack)
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
