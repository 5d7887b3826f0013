"""Marking strategies: error indicators in, boolean flags out (pure numpy)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["limit_marks", "mark_coarsening", "mark_doerfler", "mark_maximum"]


def _indicators(eta: ArrayLike) -> np.ndarray:
    values = np.asarray(eta, dtype=float)
    if values.ndim != 1:
        raise ValueError(f"eta must be a 1-D array of element indicators, got shape {values.shape}")
    if values.size == 0:
        raise ValueError("eta is empty: there are no elements to mark")
    if not np.all(np.isfinite(values)) or np.any(values < 0):
        raise ValueError("eta must contain finite, nonnegative values")
    return values


def _check_theta(theta: float, name: str = "theta") -> float:
    if not (0.0 < theta <= 1.0):
        raise ValueError(f"{name} must lie in (0, 1], got {theta!r}")
    return float(theta)


def mark_doerfler(eta: ArrayLike, theta: float) -> np.ndarray:
    """Doerfler (bulk) marking.

    Marks a set ``M`` of minimal cardinality with
    ``sum_{T in M} eta_T^2 >= theta * sum_T eta_T^2``, taking the largest
    indicators first.

    Parameters
    ----------
    eta : array_like
        Nonnegative indicators, one per element.
    theta : float
        Bulk fraction in ``(0, 1]``.

    Returns
    -------
    numpy.ndarray
        Boolean flags, shape of ``eta``.
    """
    values = _indicators(eta)
    theta = _check_theta(theta)
    squares = values**2
    order = np.argsort(-squares, kind="stable")
    cumulative = np.cumsum(squares[order])
    total = cumulative[-1]
    marked = np.zeros(values.size, dtype=bool)
    if total == 0.0:
        return marked
    # First position where the running sum reaches the bulk; ties broken by index.
    count = int(np.searchsorted(cumulative, theta * total)) + 1
    marked[order[: min(count, values.size)]] = True
    return marked


def mark_maximum(eta: ArrayLike, theta: float) -> np.ndarray:
    """Maximum strategy: mark ``T`` with ``eta_T >= theta * max eta``.

    Parameters
    ----------
    eta : array_like
        Nonnegative indicators, one per element.
    theta : float
        Fraction of the maximum in ``(0, 1]``.

    Returns
    -------
    numpy.ndarray
        Boolean flags (none if all indicators are zero).
    """
    values = _indicators(eta)
    theta = _check_theta(theta)
    largest = values.max()
    if largest == 0.0:
        return np.zeros(values.size, dtype=bool)
    return values >= theta * largest


def mark_coarsening(eta: ArrayLike, fraction: float) -> np.ndarray:
    """Flag elements for coarsening: ``eta_T^2 < fraction * mean(eta^2)``.

    Parameters
    ----------
    eta : array_like
        Nonnegative indicators, one per element.
    fraction : float
        Fraction of the mean squared indicator in ``(0, 1]``.

    Returns
    -------
    numpy.ndarray
        Boolean flags.
    """
    values = _indicators(eta)
    fraction = _check_theta(fraction, "fraction")
    squares = values**2
    return squares < fraction * squares.mean()


def limit_marks(eta: ArrayLike, marked: ArrayLike, max_count: int) -> np.ndarray:
    """Keep at most ``max_count`` marked elements, those with largest ``eta``.

    Parameters
    ----------
    eta : array_like
        Nonnegative indicators, one per element.
    marked : array_like of bool
        Flags, same shape as ``eta``.
    max_count : int
        Largest number of flags to keep (``>= 0``).

    Returns
    -------
    numpy.ndarray
        New boolean flags, a subset of ``marked``.
    """
    values = _indicators(eta)
    flags = np.asarray(marked)
    if flags.shape != values.shape or flags.dtype != bool:
        raise ValueError(
            f"marked must be a boolean array of shape {values.shape}, "
            f"got dtype {flags.dtype} and shape {flags.shape}"
        )
    if int(max_count) != max_count or max_count < 0:
        raise ValueError(f"max_count must be a nonnegative integer, got {max_count!r}")
    result = flags.copy()
    candidates = np.flatnonzero(flags)
    if candidates.size <= max_count:
        return result
    ranked = candidates[np.argsort(-values[candidates], kind="stable")]
    result[ranked[int(max_count):]] = False
    return result
