"""Demo: a compact tension (CT) specimen loaded through its pin holes, its peak pin force
against the Griffith load of the sharp crack (ASTM E399).

    python demos/compact_tension.py [OUT_DIR] [--set key=value ...]

`compact_tension.toml` is a CAD domain (``geometry.kind = "occ"``: the ASTM E399 proportions
with W = 40 mm, two pin holes and a machined notch cut out) with a pre-crack to a/W = 0.5 as
an initial crack, in mm and kN. Each hole's circle is split into two arcs
(``geometry.split_points``); the pins push on the arcs facing away from the crack plane: the
upper hole's upper half moves up by t mm, the lower hole's lower half down. The crack grows
from the pre-crack's tip (20, 0) along the symmetry line y = 0 while the pin force falls.
The crack model is AT2 with Miehe's split in the hybrid formulation; G_c is uniform (no
toughened zone).

What to expect. ASTM E399: K_I = P/(B sqrt W) f(a/W) (:func:`astm_f`; f(0.5) = 9.659, within
0.5 % of the f that ASTM E647's compliance fit gives through G = P^2/(2B) dC/da,
:func:`compliance_f`). With G = K_I^2 (1 - nu^2)/E = G_c (plane strain) a sharp crack starts to
grow at P_c = 2.694 kN per mm of thickness (:func:`lefm_onset`); the phase field's peak is
near it (the band's toughness is gamma (1 + h/(2 epsilon))). Writes history.csv (Fy_pin_top,
uy_pin_top: the upper pin's force in kN per mm of thickness and its displacement in mm),
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
WIDTH, CRACK_TIP = 40.0, 20.0
"""W (mm, from the load line x = 0 to the back face) and the initial crack length a (mm)."""
GAMMA = 0.073
"""The specimen's G_c (kN/mm), uniform (the scene file)."""


def astm_f(ratio: float) -> float:
    """ASTM E399's geometry factor of the CT specimen: K_I = P/(B sqrt W) f(a/W), for
    0.2 <= a/W <= 1 (the standard quotes 0.5 % accuracy)."""
    r = ratio
    return (2 + r) / (1 - r) ** 1.5 * (0.886 + 4.64 * r - 13.32 * r ** 2 + 14.72 * r ** 3
                                        - 5.6 * r ** 4)


def compliance(ratio: float) -> float:
    """ASTM E647's load-line compliance fit of the CT specimen (Saxena and Hudak 1978):
    E' B v/P, v the opening of the load line, 0.2 <= a/W <= 0.975."""
    r = ratio
    return ((1 + r) / (1 - r)) ** 2 * (2.1630 + 12.219 * r - 20.065 * r ** 2 - 0.9925 * r ** 3
                                       + 20.609 * r ** 4 - 9.9314 * r ** 5)


def compliance_f(ratio: float, step: float = 1e-5) -> float:
    """The geometry factor that :func:`compliance` implies: G = P^2/(2B) dC/da = K^2/E' gives
    f^2 = (1/2) d(E' B v/P)/d(a/W) (a central difference)."""
    slope = (compliance(ratio + step) - compliance(ratio - step)) / (2 * step)
    return math.sqrt(slope / 2)


def plane_strain_modulus(scene: Scene) -> float:
    """E' = E/(1 - nu^2) of the scene's Lame constants."""
    lam, mu = scene.material.lam, scene.material.mu
    young = mu * (3 * lam + 2 * mu) / (lam + mu)
    nu = lam / (2 * (lam + mu))
    return young / (1 - nu ** 2)


def lefm_onset(scene: Scene) -> float:
    """The pin force (per unit thickness) at which the sharp crack starts to grow by
    Griffith: K_I^2/E' = G_c with K_I from :func:`astm_f`."""
    return math.sqrt(GAMMA * plane_strain_modulus(scene) * WIDTH) / astm_f(CRACK_TIP / WIDTH)


def lefm_stiffness(scene: Scene) -> float:
    """Pin force per pin displacement t of the sharp crack by :func:`compliance` (the
    opening is 2 t); the pins here load half arcs, not the load line's points."""
    return 2 * plane_strain_modulus(scene) / compliance(CRACK_TIP / WIDTH)


def main(out_dir: str | Path = "out/compact_tension", overrides: Sequence[str] = (),
         on_step: Callable[[PhaseFieldStepper], None] | None = None) -> RunSummary:
    run = run_specimen(SCENE, out_dir, overrides, on_step, ("uy_pin_top", "Fy_pin_top"))
    scene, summary, history, out = run.scene, run.summary, run.history, run.out
    u, force, peak = run.u, run.force, run.peak
    p_c = lefm_onset(scene)
    run.plot(("F_y pin", "u_y pin"), estimate=(p_c / lefm_stiffness(scene), p_c))
    tip_x, tip_y = history["tip_x"], history["tip_y"]
    write_json(out / "peak.json", {"peak_force_kN": float(force[peak]),
                                   "u_at_peak_mm": float(u[peak]),
                                   "final_force_kN": float(force[-1]),
                                   "lefm_onset_kN": p_c,
                                   "peak_over_lefm": float(force[peak] / p_c),
                                   "initial_stiffness": float(force[1] / u[1]),
                                   "lefm_stiffness": lefm_stiffness(scene),
                                   "tip_x_max_mm": float(np.nanmax(tip_x)),
                                   "tip_abs_y_max_mm": float(np.nanmax(np.abs(tip_y))),
                                   "epsilon": scene.phase_field.epsilon})
    print(f"{scene.name}: peak pin force {force[peak]:.4g} kN/mm at u = {u[peak]:.4g} mm "
          f"(LEFM start of growth {p_c:.4g} kN/mm, ratio {force[peak] / p_c:.3f}); "
          f"{force[-1]:.4g} kN/mm at the end; the tip reached x = {np.nanmax(tip_x):.2f}, "
          f"|y| <= {np.nanmax(np.abs(tip_y)):.3f}; wall time {summary.last.wall_s:.1f} s; "
          f"results in {out_dir}")
    return summary


if __name__ == "__main__":
    command_line(main, "out/compact_tension")
