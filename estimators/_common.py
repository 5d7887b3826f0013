"""Small helpers shared by the estimators (private)."""

from __future__ import annotations

import numpy as np
import ngsolve
from ngsolve import CoefficientFunction


def as_coefficient(value: CoefficientFunction | float) -> CoefficientFunction:
    """Return ``value`` as a CoefficientFunction (floats are wrapped)."""
    if isinstance(value, CoefficientFunction):
        return value
    return CoefficientFunction(float(value))


def space_order(gf: ngsolve.GridFunction) -> int:
    """Polynomial order of the space of ``gf``."""
    return int(gf.space.globalorder)


def element_values(integrated: object) -> np.ndarray:
    """Copy the result of ``Integrate(..., element_wise=True)`` to numpy."""
    return np.array(integrated.NumPy(), dtype=float, copy=True)
