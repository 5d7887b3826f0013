"""Richardson extrapolation and Roache's grid convergence index from three refinement levels.

The procedure of Roache (Verification and Validation in Computational Science and
Engineering, 1998) as written out by Celik et al., "Procedure for estimation and reporting of
uncertainty due to discretization in CFD applications", J. Fluids Eng. 130 (2008) 078001, for
a constant refinement ratio ``r``: with ``f1`` the finest, ``f2``, ``f3`` the coarsest value,

    e21 = f2 - f1,  e32 = f3 - f2,  p = ln(e32 / e21) / ln r,
    f_ext = f1 + (f1 - f2) / (r**p - 1),  GCI = Fs |f1 - f2| / (r**p - 1),

with the safety factor ``Fs = 1.25`` of a three-level study. ``p`` is defined only when the
differences have one sign (monotone convergence) and ``|e32| > |e21|`` (they shrink); otherwise
the estimate says why there is none (``status``) instead of giving a number.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

__all__ = ["SAFETY_FACTOR", "Richardson", "richardson"]

SAFETY_FACTOR = 1.25
"""Roache's Fs for a study of three or more levels with an observed order."""

CONVERGED = "converged"
OSCILLATING = "oscillating"
DIVERGING = "diverging"
EXACT = "exact"
TOO_FEW = "too few levels"
NOT_FINITE = "not finite"


@dataclass(frozen=True)
class Richardson:
    """The estimate from the three finest levels of one quantity.

    ``status`` is ``"converged"`` (all numbers set), ``"exact"`` (the two finest values are
    equal: no discretization error to see, ``gci`` 0, no order), ``"oscillating"`` (the differences
    change sign), ``"diverging"`` (they grow under refinement), ``"too few levels"`` or
    ``"not finite"``; the numbers are NaN unless converged or exact.
    """

    status: str
    finest: float
    extrapolated: float = math.nan
    order: float = math.nan
    """The observed order ``p`` (against the mesh size: ``p`` where the error ~ h**p)."""
    gci: float = math.nan
    """The error band of the finest value: ``Fs |f1 - f2| / (r**p - 1)`` (absolute)."""
    asymptotic_ratio: float = math.nan
    """``GCI_32 / (r**p GCI_21)`` from the relative indices: near 1 in the asymptotic range."""

    @property
    def ok(self) -> bool:
        return self.status in (CONVERGED, EXACT)

    @property
    def band(self) -> tuple[float, float]:
        """``(finest - gci, finest + gci)``: where the converged value lies, by the GCI."""
        return (self.finest - self.gci, self.finest + self.gci)

    def describe(self) -> str:
        if self.status == CONVERGED:
            return (f"{self.finest:.6g} +- {self.gci:.3g} (GCI, Fs {SAFETY_FACTOR}); "
                    f"extrapolated {self.extrapolated:.6g}, observed order {self.order:.2f}")
        if self.status == EXACT:
            return f"{self.finest:.6g} (the two finest levels agree exactly)"
        return f"{self.finest:.6g}: no error estimate ({self.status})"


def richardson(values: Sequence[float], ratio: float,
               safety_factor: float = SAFETY_FACTOR) -> Richardson:
    """Richardson's extrapolation of the three finest of ``values`` (coarsest first).

    Parameters
    ----------
    values : the quantity on each level, the coarsest first (at least three)
    ratio : the grid refinement ratio ``h_coarse / h_fine`` between neighbouring levels (> 1)
    safety_factor : Roache's Fs (1.25 for three or more levels)

    Returns
    -------
    Richardson
    """
    if not ratio > 1:
        raise ValueError(f"ratio = {ratio!r}: the refinement ratio must be > 1")
    values = [float(v) for v in values]
    finest = values[-1] if values else math.nan
    if len(values) < 3:
        return Richardson(TOO_FEW, finest)
    f3, f2, f1 = values[-3:]
    if not all(math.isfinite(v) for v in (f1, f2, f3)):
        return Richardson(NOT_FINITE, finest)
    e21, e32 = f2 - f1, f3 - f2
    if e21 == 0:  # no difference left to see on the finest levels (whatever e32 is)
        return Richardson(EXACT, f1, f1, math.nan, 0.0)
    if e32 == 0 or e32 / e21 < 0:
        return Richardson(OSCILLATING, f1)
    quotient = e32 / e21
    if quotient <= 1:
        return Richardson(DIVERGING, f1)
    order = math.log(quotient) / math.log(ratio)
    growth = ratio ** order - 1  # = quotient - 1 for a constant ratio
    extrapolated = f1 + (f1 - f2) / growth
    gci = safety_factor * abs(e21) / growth
    gci_21 = gci / abs(f1) if f1 else math.nan
    gci_32 = safety_factor * abs(e32) / growth / abs(f2) if f2 else math.nan
    asymptotic = gci_32 / (ratio ** order * gci_21) if gci_21 else math.nan
    return Richardson(CONVERGED, f1, extrapolated, order, gci, asymptotic)

