"""How to choose ``phase_field.alpha2``: the viscosity of z against the surface term.

The z-step of the scheme is ``alpha2 (z - z_old)/tau = eps div(gamma grad z) - gamma z/eps
+ W (1 - z)``: alpha2/tau adds to the diagonal that gamma/eps sets. While

    alpha2 / tau  <<  gamma / eps        (tau = time.dt, the smallest step; gamma its minimum)

z relaxes to the quasi-static balance within a step and the run does not depend on the load
rate (the paper's rate independence): the relaxation time alpha2 eps / gamma of z is far
below a step. Above it z lags the load, the crack runs late and damage spreads (theory.md,
"Fig. 4": ratio 2 gave the demo's path, ratio 10 a crack that lags the load). The demos keep the
ratio between 0.004 and 0.1; ``demos/sneddon.toml`` raises it to 1e9 on purpose, to freeze z.

alpha2 stays a required key, without a default: it is the model's viscosity (a physical
parameter of the gradient flow, with units of gamma/eps times those of t), and a default
derived from tau would change the model whenever the time step changes. :func:`rate_warnings`
says when a scene's choice is not rate independent.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .sections import Scene

__all__ = ["RATE_LIMIT", "RECOMMENDED_RATIO", "rate_ratio", "rate_warnings", "suggested_alpha2"]

RATE_LIMIT = 1.0
"""alpha2/tau above this many gamma/eps: warned (z lags the load)."""
RECOMMENDED_RATIO = 0.01
"""The ratio :func:`suggested_alpha2` aims at (the demos: 0.004-0.1)."""


def _gamma_min(scene: "Scene") -> float:
    """The smallest toughness on the domain's sample grid (gamma may vary in space)."""
    gamma = scene.material.gamma
    if gamma.is_constant:
        return gamma.value()
    coordinates = scene.geometry.domain().sample_points()
    values = gamma.evaluate_numpy(dict(zip("xyz", coordinates)))
    return float(np.min(np.broadcast_to(values, coordinates[0].shape)))


def rate_ratio(scene: "Scene") -> float:
    """(alpha2 / time.dt) / (min gamma / epsilon): below 1 (better 0.1) the run is rate
    independent."""
    pf = scene.phase_field
    return (pf.alpha2 / scene.time.dt) / (_gamma_min(scene) / pf.epsilon)


def suggested_alpha2(scene: "Scene", ratio: float = RECOMMENDED_RATIO) -> float:
    """The alpha2 that gives ``ratio`` = (alpha2/dt)/(min gamma/eps) for the scene's dt."""
    return ratio * scene.time.dt * _gamma_min(scene) / scene.phase_field.epsilon


def rate_warnings(scene: "Scene") -> list[str]:
    """One line when alpha2/dt is not small against gamma/eps (:data:`RATE_LIMIT`), else []."""
    ratio = rate_ratio(scene)
    if ratio <= RATE_LIMIT:
        return []
    pf = scene.phase_field
    return [f"phase_field.alpha2 = {pf.alpha2:g}: alpha2/dt = {pf.alpha2 / scene.time.dt:.3g} "
            f"is {ratio:.3g} times gamma/epsilon = {_gamma_min(scene) / pf.epsilon:.3g}, so z "
            "lags the load (rate dependent); for a quasi-static crack keep alpha2/dt well below "
            f"gamma/epsilon, e.g. alpha2 = {suggested_alpha2(scene):.2g} (user guide, "
            "'Choosing alpha2')"]
