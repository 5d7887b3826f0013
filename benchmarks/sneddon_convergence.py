"""Sneddon's pressurized crack: V and w(0) against the closed forms over epsilon and h_crack.

    python benchmarks/sneddon_convergence.py [--set key=value ...]

Builds demos/sneddon.toml for each eps/l0 in 0.2, 0.1, 0.05 and core size h_crack = eps/4,
eps/10, eps/20 (h_band = eps/4), takes one step (z frozen, so V is that of an elastic solve at
p(dt)) and prints V/V_Sneddon and w(0)/w_Sneddon(0). The table is in docs/theory.md,
"Pressurized cracks". One thread; about 4 minutes in all (the finest case ~33,000 vertices).
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

import ngfrac
from ngfrac import PhaseFieldStepper, load_scene
from ngfrac.post.pressurized import crack_volume, opening_profile

ROOT = Path(__file__).resolve().parents[1]
EPSILONS = (0.2, 0.1, 0.05)
CORE = (4, 10, 20)


def measure(overrides: list[str]) -> tuple[float, float, int]:
    """(V/V_S, w(0)/w_S(0), vertices) of the Sneddon scene after one step."""
    scene = load_scene(ROOT / "demos" / "sneddon.toml", overrides)
    stepper = PhaseFieldStepper(scene)
    stepper.step(diagnose=False)
    lam, mu = scene.material.lame
    E, nu = mu * (3 * lam + 2 * mu) / (lam + mu), lam / (2 * (lam + mu))
    p = float(scene.phase_field.crack_pressure.evaluate_numpy({"t": stepper.t}))
    exact_v, exact_w = 2 * math.pi * p * (1 - nu ** 2) / E, 4 * p * (1 - nu ** 2) / E  # l0 = 1
    volume = crack_volume(stepper.u, stepper.z, stepper.fields.integration_order)
    profile = opening_profile(stepper.u, stepper.z, scene.cracks[0].points,
                              10 * scene.phase_field.epsilon, stepper.domain.contains)
    centre = int(np.argmin(np.abs(profile.s)))
    return volume / exact_v, profile.w[centre] / exact_w, stepper.mesh.nv


def main(extra: list[str]) -> None:
    ngfrac.set_threads(1)
    print("eps/l0  h_crack  V/V_S  w(0)/w_S  vertices")
    for eps in EPSILONS:
        for k in CORE:
            ratio_v, ratio_w, nv = measure([f"phase_field.epsilon={eps}",
                                            f"adaptivity.h_crack={eps / k}",
                                            f"adaptivity.h_band={eps / 4}", *extra])
            print(f"{eps:6.3g}  eps/{k:<4d} {ratio_v:6.3f}  {ratio_w:8.3f}  {nv:8d}", flush=True)


if __name__ == "__main__":
    args = sys.argv[1:]
    main([value for flag, value in zip(args[::2], args[1::2]) if flag == "--set"])
