"""Measurements of a pressurized crack: its volume and its opening (Bourdin, Chukwudozie and
Yoshioka 2012).

Across a crack band z peaks on the crack and u jumps by the opening w, so u . grad z
integrates to -w along a line across it (z rises towards the crack from both sides, and u
points away from it on each side)::

    w(s) = -int u . grad z dn      (a line through the crack point s, along its normal n)
    V    = -int_Omega u . grad z dx = int w ds

docs/theory.md, "Pressurized cracks", has the derivation and Sneddon's closed forms.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import ngsolve as ngs

from ..fem.threads import integrate


def crack_volume(u: ngs.GridFunction, z: ngs.GridFunction, order: int = 5) -> float:
    """``V = -int u . grad z dx`` (2D: an area per unit thickness)."""
    return -float(integrate(ngs.InnerProduct(u, ngs.grad(z)), u.space.mesh, order=order))


@dataclass(frozen=True)
class OpeningProfile:
    """The opening along a straight crack: stations ``s`` (distance from the crack's centre
    along it), their points ``x``, ``y`` and the opening ``w`` measured there."""

    s: np.ndarray
    x: np.ndarray
    y: np.ndarray
    w: np.ndarray

    @property
    def volume(self) -> float:
        """int w ds over the stations (trapezoid rule)."""
        return float(np.trapezoid(self.w, self.s))


def opening_profile(u: ngs.GridFunction, z: ngs.GridFunction, crack: Sequence[Sequence[float]],
                    half_width: float, contains: Any, n_stations: int = 81,
                    n_across: int = 801, extend: float = 1.25) -> OpeningProfile:
    """``w(s) = -int u . grad z dn`` on lines normal to a straight 2D crack.

    Parameters
    ----------
    u, z : ngsolve.GridFunction
        Displacement (a 2D vector) and phase field.
    crack : sequence of points
        The crack's first and last point give its line (the initial crack of a scene).
    half_width : float
        Each line runs from -half_width to +half_width across the crack (about 10 epsilon:
        z = exp(-10) there).
    contains : callable
        ``contains(points) -> bools`` of the domain (:meth:`ngfrac.geometry.domains.Domain.contains`);
        the part of a line outside it is left out.
    n_stations, n_across : int
        Lines, and sample points on each line (trapezoid rule).
    extend : float
        The stations cover ``extend`` times the crack's half length on both sides of its
        centre, so the profile shows where the opening closes.
    """
    a, b = (np.asarray(p, dtype=float)[:2] for p in (crack[0], crack[-1]))
    centre, half = (a + b) / 2, np.linalg.norm(b - a) / 2
    tangent = (b - a) / (2 * half)
    normal = np.array([-tangent[1], tangent[0]])
    s = np.linspace(-extend * half, extend * half, n_stations)
    across = np.linspace(-half_width, half_width, n_across)
    mesh = u.space.mesh
    integrand = ngs.InnerProduct(u, ngs.grad(z))
    w = np.zeros_like(s)
    for k, station in enumerate(s):
        points = centre + station * tangent + across[:, None] * normal
        inside = np.asarray(contains(points), dtype=bool)
        values = np.zeros(len(across))
        if inside.any():
            mips = mesh(points[inside, 0], points[inside, 1])
            values[inside] = np.asarray(integrand(mips)).ravel()
        w[k] = -np.trapezoid(values, across)
    x, y = (centre[:, None] + np.outer(tangent, s))
    return OpeningProfile(s, x, y, w)
