"""Surfing: a K-field whose tip moves at speed v is imposed on the whole boundary (MODEL.md).

Once the crack follows the moving tip steadily, every unit of crack advance costs the same
energy, so d(E_surf)/dt = gamma_eff v; below the critical K the crack stays put.

gamma_eff of this discrete AT2 model, derived here:

- The band: its two exponential tails cost gamma; a core (z = 1) one element of size h wide
  adds gamma h/(2 epsilon). The adaptive mesh makes h = epsilon/10 there: +5% for P1 z; a P2
  z has a narrower core (its tails are nearly exact), between +0 and +5%: +2.5% is used.
- The wake: AT2 has no elastic limit, so the singular field damages a halo around the tip,
  z = W eps/(gamma + W eps) where z varies slowly (the z-equation without its gradient term).
  In mode III W = mu |grad u|^2 = G/(pi r); a point at height y sees at most G/(pi |y|) as the
  tip passes, and irreversibility keeps z_w = a/(a + |y|), a = G eps/(pi gamma), behind it.
  Beyond |y| = 2 epsilon, where the band's exp(-|y|/eps) falls below z_w, that costs
  (gamma/eps) a^2/(a + 2 eps) per unit length (both sides, gradient term included to leading
  order): 4.7% of gamma for G = 1.025 gamma. The mode I halo is of the same size (the same
  1/r energy density, a different angular factor); the same estimate is used.

So gamma_eff = 1.072 gamma for P2 z (mode III here) and 1.098 gamma for P1 z (mode I here).
The same gamma_eff predicts the strip's onset (test_strip.py).

The scheme: z is driven by the displacement of the previous step, so the tip can only follow
if it moves much less than epsilon per step; at v dt = epsilon/4 it falls behind even at
1.3 K_c, at v dt = epsilon/20 it keeps up. K is set 15% above sqrt(2 mu gamma_eff) (mode I:
sqrt(E gamma_eff/(1 - nu^2))) so that the crack, which starts from rest, catches up with the
imposed tip after the start-up; in steady state the dissipation per unit advance does not
depend on K (measured: the same 1.16 at 1.0 and 1.15 K_c in mode III).

The atan2 branch cut lies along the crack behind the tip: theta = atan2(y - y0, x - x0 - v t)
is +-pi on the crack faces y = y0, x < x0 + v t.

Mode III: u = (K/mu) sqrt(2 r/pi) sin(theta/2), G = K^2/(2 mu).
Mode I, plane strain: u_x = K/(2 mu) sqrt(r/(2 pi)) (kappa - cos theta) cos(theta/2), u_y the
same with sin(theta/2), kappa = 3 - 4 nu, G = K^2 (1 - nu^2)/E.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from ngfrac import PhaseFieldStepper, Scene

MU, NU, GAMMA = 1.0, 0.3, 1.0
LAM = 2 * MU * NU / (1 - 2 * NU)
E = 2 * MU * (1 + NU)
X0, V = 0.25, 1.0
HMIN_RATIO = 0.1
BOUNDARIES = ("bottom", "right", "top", "left")
SUPERCRITICAL = 1.15
STEPS_PER_EPSILON = 20


def wake(G: float, eps: float) -> float:
    """The AT2 wake's energy per unit length beyond 2 epsilon: (gamma/eps) a^2/(a + 2 eps)."""
    a = G * eps / (math.pi * GAMMA)
    return GAMMA / eps * a * a / (a + 2 * eps)


def gamma_eff(eps: float, order: int) -> float:
    """The band's cost (P1 z: gamma (1 + h/(2 eps)); P2 z: gamma (1 + h/(4 eps))) plus the
    wake at G = that value; h = HMIN_RATIO eps in the core."""
    band = GAMMA * (1 + HMIN_RATIO / (2 if order == 1 else 4))
    return band + wake(band, eps)


def k_field(model: str, K: float) -> list:
    """The boundary values (expressions in x, y, t) of the moving K-field."""
    dx = f"(x - {X0} - {V}*t)"
    r = f"sqrt({dx}*{dx} + y*y)"  # not **: NGSolve's vectorized pow is NaN for a negative base
    theta = f"atan2(y, {dx})"
    if model == "mode3":
        return [f"{K / MU}*sqrt(2*{r}/pi)*sin({theta}/2)"]
    kappa = 3 - 4 * NU
    amplitude = f"{K / (2 * MU)}*sqrt({r}/(2*pi))*({kappa} - cos({theta}))"
    return [f"{amplitude}*cos({theta}/2)", f"{amplitude}*sin({theta}/2)"]


def critical_k(model: str, toughness: float) -> float:
    """K with G = toughness: mode III G = K^2/(2 mu), mode I G = K^2 (1 - nu^2)/E."""
    if model == "mode3":
        return math.sqrt(2 * MU * toughness)
    return math.sqrt(E * toughness / (1 - NU ** 2))


def surfing_scene(model: str, K: float, eps: float, t_end: float, dt: float,
                  max_vertices: int, order: int = 2) -> Scene:
    values = k_field(model, K)
    value = values[0] if model == "mode3" else values
    material = {"mu": MU, "gamma": GAMMA}
    if model != "mode3":
        material["lam"] = LAM
    hmin = HMIN_RATIO * eps
    return Scene.from_dict({
        "name": f"surfing_{model}",
        "model": {"kind": model},
        "material": material,
        "phase_field": {"epsilon": eps, "alpha2": 1e-4, "residual_stiffness": 1e-6},
        "geometry": {"width": 1.0, "height": 0.6, "origin": [0.0, -0.3]},
        "cracks": [{"points": [[0.0, 0.0], [X0, 0.0]]}],
        "loads": [{"boundary": b, "value": value} for b in BOUNDARIES],
        "time": {"dt": dt, "t_end": t_end},
        "discretization": {"order": order},
        "adaptivity": {"enabled": True, "max_vertices": max_vertices, "hmin": hmin,
                       "h_crack": hmin},
        "output": {"vtk_every": 0},
    })


def run_surfing(model: str, factor: float, eps: float, t_end: float,
                max_vertices: int = 4000, order: int = 2) -> np.ndarray:
    """Rows (t, tip_x, E_surf) of a surfing run with K = factor * K_c(gamma_eff)."""
    scene = surfing_scene(model, factor * critical_k(model, gamma_eff(eps, order)), eps, t_end,
                          eps / (STEPS_PER_EPSILON * V), max_vertices, order)
    return np.array([(r.t, r.tip_x, r.E_surf) for r in PhaseFieldStepper(scene).run()])


def check_steady(model: str, eps: float, order: int = 2, **kwargs) -> float:
    """Steady running (tip speed within 10% of v, lag below 3 epsilon) and
    d(E_surf)/dt / v within 5% of gamma_eff; returns the measured rate."""
    rows = run_surfing(model, SUPERCRITICAL, eps, t_end=0.5, order=order, **kwargs)
    window = (rows[:, 1] >= X0 + 0.2) & (rows[:, 1] <= X0 + 0.45)
    table = "\n".join(f"t={t:.3f} tip_x={x:.4f} imposed={X0 + V * t:.4f} E_surf={e:.4f}"
                      for t, x, e in rows[::10])
    assert window.sum() >= 10, f"{model}: the crack did not reach the window\n{table}"
    t, tip, surf = rows[window].T
    speed = np.polyfit(t, tip, 1)[0]
    rate = np.polyfit(t, surf, 1)[0] / V
    lag = X0 + V * t[-1] - tip[-1]
    predicted = gamma_eff(eps, order)
    message = (f"{model}, eps={eps}: d(E_surf)/dt/v = {rate:.4f} against gamma_eff = "
               f"{predicted:.4f} ({rate / predicted - 1:+.1%}); dE_surf/dx_tip = "
               f"{rate * V / speed:.4f}; tip speed {speed:.3f} (v = {V}); lag {lag:.4f}\n{table}")
    assert abs(speed / V - 1) < 0.1 and abs(lag) < 3 * eps, message
    assert abs(rate / predicted - 1) < 0.05, message
    return rate


def check_subcritical(model: str, eps: float, order: int = 2, **kwargs) -> None:
    """At 0.7 K_c the tip does not move 2 epsilon while the imposed tip moves 0.15."""
    rows = run_surfing(model, 0.7, eps, t_end=0.15, order=order, **kwargs)
    moved = np.nanmax(rows[:, 1]) - X0
    assert moved < 2 * eps, f"{model}: at 0.7 K_c the tip moved by {moved:.4f}\n{rows[::10]}"


# The steady checks take 2-4 minutes each (250 steps). A shorter run is not steady yet: with
# t_end = 0.38 and the window 0.12..0.33 beyond X0 (mode III, P1) the tip runs at 0.84 v and
# the rate is 6.5% below gamma_eff. So they are slow studies; the sub-critical ones stay.
@pytest.mark.slow
def test_mode3_surfing_steady():
    check_steady("mode3", 0.04)  # P2


def test_mode3_surfing_subcritical():
    check_subcritical("mode3", 0.04)


@pytest.mark.slow
def test_mode1_surfing_steady():
    check_steady("plane_strain", 0.04, order=1)


def test_mode1_surfing_subcritical():
    check_subcritical("plane_strain", 0.04, order=1)


@pytest.mark.slow
@pytest.mark.parametrize("model", ["mode3", "plane_strain"])
def test_surfing_steady_fine(model):
    check_steady(model, 0.02, max_vertices=8000, order=2)
