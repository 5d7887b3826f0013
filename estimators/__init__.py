"""A-posteriori error estimators and marking strategies for NGSolve.

An estimator maps a GridFunction (and coefficients) to one nonnegative value
per volume element; a marking strategy maps those values to boolean flags.
Nothing here refines a mesh.
"""

from estimators.marking import limit_marks, mark_coarsening, mark_doerfler, mark_maximum
from estimators.residual import residual_estimator
from estimators.zz import recover_gradient, zz_estimator

__all__ = [
    "limit_marks",
    "mark_coarsening",
    "mark_doerfler",
    "mark_maximum",
    "recover_gradient",
    "residual_estimator",
    "zz_estimator",
]
