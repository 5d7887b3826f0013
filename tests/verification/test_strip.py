"""Mode III strip: the crack starts when the load reaches Griffith's Delta_c (MODEL.md).

A strip 0 < y < H, u = 0 on the bottom and u = Delta on the top, with a long crack along
y = H/2 from the left edge. Far ahead of the tip the strip is uniformly sheared (e = Delta/H),
far behind it is unloaded, so a crack advance da releases G da with G = mu Delta^2/(2H), and
growth starts at Delta_c = sqrt(2 H gamma_eff / mu).

Phase-field corrections, derived here:

- gamma_eff, the cost of a unit of running crack, is that of the surfing test
  (test_surfing.py): the band, gamma (1 + h/(4 eps)) for P2 z with h = eps/10 in the core,
  plus the wake of damage that AT2 (no elastic limit) leaves around the path, about 4.7%:
  gamma_eff = 1.072 gamma.
- The damaged far field: ahead of the tip W = mu (Delta/H)^2 and the uniform z solves
  gamma z/eps = W (1 - z), z* = W/(W + gamma/eps). Irreversibility keeps z* behind the tip,
  so its surface energy is the same on both sides and only the elastic energy
  H/2 (1 - z*)^2 W is released: with x = W eps/gamma, growth starts at
  x/(1 + x)^2 = q = 2 eps gamma_eff/(gamma H), i.e. Delta_c = H sqrt(gamma x/(eps mu)),
  a first-order correction of (1 + 2 eps/H) to Delta_c (8% at eps/H = 0.04).

The load rises slowly (0.3% of Delta_c per step) from 0.85 of the prediction; the measured
onset is the load at which the tip has moved 2 epsilon beyond the initial one. (The tip
starts to creep forward near the sharp-crack value sqrt(2 H gamma/mu), as the process zone of
the initial band forms, and runs away a little above the prediction: 2 epsilon of advance
marks the middle of that range.)

AT1 (``phase_field.model = "AT1"``): the far field stays intact (its strength
W_c = 3 gamma/(8 eps) = 9.4 is far above mu (Delta/H)^2 ~ 2 at eps/H = 0.04), and the band
costs gamma (1 + 3 h/(16 eps)) for P2 z: a z = 1 core one element wide adds
(3/8)(h/eps) gamma, half of it for P2 as for AT2 above (+1.9% at h = eps/10); its halo lies
inside the band (it damages where mu |grad u|^2 = G/(pi r) exceeds W_c, r < 0.85 eps, while
the band is 2 eps wide), so there is no wake term: Delta_c = sqrt(2 H gamma_eff/mu) with
gamma_eff = 1.019 gamma. The paper's scheme advances a tip by a fraction of epsilon per step
(test_surfing.py), so a ramp measures the onset plus the time to grow 2 epsilon; for AT1 that
delay was 10% of Delta_c at 0.3% of load per step. The AT1 test holds the load instead and
brackets the onset: at 0.95 Delta_c the crack stops (no growth in the second half of the
run), at 1.05 Delta_c it keeps growing.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from ngfrac import PhaseFieldStepper, Scene

MU, GAMMA = 1.0, 1.0
HMIN_RATIO = 0.1
"""Element size in the crack core, over epsilon."""


def gamma_eff(eps: float) -> float:
    """Band (P2 z) plus wake, as in test_surfing.py: gamma (1 + h/(4 eps)) + (gamma/eps)
    a^2/(a + 2 eps) with a = G eps/(pi gamma) at G = the band's cost."""
    band = GAMMA * (1 + HMIN_RATIO / 4)
    a = band * eps / (math.pi * GAMMA)
    return band + GAMMA / eps * a * a / (a + 2 * eps)


def strip_scene(eps: float, H: float, length: float, crack: float, d0: float, rate: float,
                n_steps: int, hmin: float, max_vertices: int, model: str = "AT2") -> Scene:
    return Scene.from_dict({
        "name": "strip",
        "model": {"kind": "mode3"},
        "material": {"mu": MU, "gamma": GAMMA},
        "phase_field": {"epsilon": eps, "alpha2": 1e-4, "residual_stiffness": 1e-6, "model": model},
        "geometry": {"width": length, "height": H},
        "cracks": [{"points": [[0.0, H / 2], [crack, H / 2]]}],
        "loads": [{"boundary": "bottom", "value": "0"},
                  {"boundary": "top", "value": f"{d0} + {rate}*t"}],
        "time": {"dt": 1.0 / n_steps, "t_end": 1.0},
        "discretization": {"order": 2},
        "adaptivity": {"enabled": True, "max_vertices": max_vertices, "hmin": hmin,
                       "h_crack": hmin},
        "output": {"vtk_every": 0},
    })


def far_field_onset(eps: float, H: float, gamma_eff: float) -> float:
    """Delta_c with the damaged far field: x/(1+x)^2 = 2 eps gamma_eff/(gamma H)."""
    q = 2 * eps * gamma_eff / (GAMMA * H)
    x = ((1 - 2 * q) - math.sqrt(1 - 4 * q)) / (2 * q)
    return H * math.sqrt(GAMMA * x / (eps * MU))


def measure_onset(eps: float, H: float = 1.0, max_vertices: int = 4000, n_steps: int = 100):
    """Run the strip under a slowly rising load; return the load at which the tip has moved
    2 epsilon (None if it never does) and the rows (Delta, tip_x, E_surf) up to that step (the
    run stops there: nothing after the onset is measured)."""
    guess = far_field_onset(eps, H, gamma_eff(eps))
    d0, span = 0.85 * guess, 0.30 * guess
    length, crack = 2.5 * H, 1.0 * H
    scene = strip_scene(eps, H, length, crack, d0, span, n_steps, HMIN_RATIO * eps, max_vertices)
    rows, onset = [], None
    for record in PhaseFieldStepper(scene).run():
        delta = d0 + span * record.t
        rows.append((delta, record.tip_x, record.E_surf))
        if record.tip_x - crack > 2 * eps:
            onset = delta
            break
    return onset, np.array(rows)


def check_onset(eps, H=1.0, **kwargs):
    """The onset lies within 5% of the prediction."""
    onset, rows = measure_onset(eps, H, **kwargs)
    predicted = far_field_onset(eps, H, gamma_eff(eps))
    table = "\n".join(f"Delta={d:.4f} tip_x={x:.4f} E_surf={e:.4f}" for d, x, e in rows[::4])
    message = (f"eps/H={eps / H}: onset Delta={onset}, predicted {predicted:.4f} (gamma_eff = "
               f"{gamma_eff(eps):.4f}; without the far-field damage "
               f"{math.sqrt(2 * H * gamma_eff(eps) / MU):.4f})\n{table}")
    assert onset is not None, "the crack never moved 2 epsilon: " + message
    assert abs(onset / predicted - 1) < 0.05, message
    return onset, predicted


def test_strip_onset_coarse():
    """epsilon/H = 0.04 (the far-field correction is 8%); a few tens of seconds."""
    check_onset(0.04)


@pytest.mark.slow
def test_strip_onset_fine():
    """epsilon/H = 0.02 (the far-field correction is 4%)."""
    check_onset(0.02, max_vertices=8000)


AT1_HELD_STEPS = 60


def at1_gamma_eff() -> float:
    """AT1's band for P2 z: gamma (1 + 3 h/(16 eps)) (module docstring); no wake."""
    return GAMMA * (1 + 3 * HMIN_RATIO / 16)


def held_growth(eps: float, delta: float, H: float = 1.0, steps: int = AT1_HELD_STEPS,
                max_vertices: int = 4000) -> tuple[float, float]:
    """Hold Delta on the AT1 strip; return the tip advance and the surface-energy increase
    over the second half of the run."""
    scene = strip_scene(eps, H, 2.5 * H, 1.0 * H, delta, 0.0, steps, HMIN_RATIO * eps,
                        max_vertices, model="AT1")
    rows = [(record.tip_x, record.E_surf) for record in PhaseFieldStepper(scene).run()]
    (tip_half, surf_half), (tip_end, surf_end) = rows[len(rows) // 2], rows[-1]
    return tip_end - tip_half, surf_end - surf_half


@pytest.mark.parametrize("factor, grows", [(0.95, False), (1.05, True)])
def test_at1_strip_onset_bracketed_within_5_percent(factor, grows):
    """AT1, eps/H = 0.04, the load held at 0.95 and 1.05 of Griffith's Delta_c.

    Measured (z_update = "obstacle", the AT1 default): at 0.95 the tip does not move and
    E_surf stays 1.071 (to the printed 1e-3) from step 25 on, +1e-5 over the second half; at
    1.05 the tip advances 0.041 (1 eps) and E_surf grows 0.060 over it (session 8, 80 steps;
    the session that wrote this test noted 0.047 and 0.07). With 60 steps (session 14, 20 %
    less CPU): +4e-5 at 0.95; at 1.05 the tip advances 0.040 and E_surf grows 0.053.
    Thresholds: growth means more than eps/4 of tip advance and more than gamma eps/4 of
    surface energy; arrest means less than a tenth of that. (Before the obstacle solve, the projected z-step did not move the tip even at
    1.13 Delta_c.)
    """
    check_at1_bracket(0.04, factor, grows)


@pytest.mark.slow
@pytest.mark.parametrize("factor, grows", [(0.95, False), (1.05, True)])
def test_at1_strip_onset_bracketed_fine(factor, grows):
    """eps/H = 0.02, cap 8,000, 120 steps. Measured: at 0.95 no tip motion, E_surf 1.062
    (to the printed 1e-3) from step 41 on; at 1.05 the tip advances 0.025 (1.2 eps) and E_surf grows 0.021 in the second
    half."""
    check_at1_bracket(0.02, factor, grows, steps=120, max_vertices=8000)


def check_at1_bracket(eps: float, factor: float, grows: bool, **kwargs) -> None:
    predicted = math.sqrt(2 * 1.0 * at1_gamma_eff() / MU)
    advance, surface = held_growth(eps, factor * predicted, **kwargs)
    message = (f"Delta = {factor} Delta_c = {factor * predicted:.4f}: second-half tip advance "
               f"{advance:.4f}, E_surf increase {surface:.5f} (eps = {eps})")
    if grows:
        assert advance > eps / 4 and surface > GAMMA * eps / 4, message
    else:
        assert advance < eps / 40 and surface < GAMMA * eps / 40, message
