"""Settings of the session that ngfrac changes only when asked: NGSolve's thread count.

Importing ngfrac changes nothing. :func:`ngfrac.run_scene` and ``ngfrac run`` call
:func:`set_threads` when a run starts; a script that drives a
:class:`~ngfrac.solve.stepper.PhaseFieldStepper` itself calls it once (NGSolve's own
``SetNumThreads`` works before the first stepper; after it ngfrac keeps the count it read,
:func:`ngfrac.fem.threads.configured_threads`).
"""
from __future__ import annotations

import logging
import os

import ngsolve as ngs

from .fem.threads import note_threads

__all__ = ["THREADS_VARIABLE", "set_threads"]

log = logging.getLogger(__name__)

THREADS_VARIABLE = "NGFRAC_THREADS"
"""The environment variable that caps NGSolve's threads (a positive integer)."""


def set_threads(n: int | None = None) -> int | None:
    """Set the number of threads of NGSolve's ``TaskManager``.

    NGSolve uses all cores by default and its idle threads spin, so two runs side by side slow
    each other down badly; ``NGFRAC_THREADS=1`` before starting several runs caps each.

    Parameters
    ----------
    n : int, optional
        The thread count. None: the value of ``NGFRAC_THREADS``; unset or empty leaves
        NGSolve's count as it is, and a value that is not a positive integer is logged as a
        warning and ignored.

    Returns
    -------
    int or None
        The thread count set, or None when nothing was changed.

    Raises
    ------
    ValueError
        ``n`` given and not a positive integer.
    """
    if n is None:
        value = os.environ.get(THREADS_VARIABLE, "").strip()
        if not value:
            return None
        if not value.isdigit() or int(value) < 1:
            log.warning("%s = %r ignored: expected a positive integer, e.g. %s=1",
                        THREADS_VARIABLE, value, THREADS_VARIABLE)
            return None
        n = int(value)
    elif isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"set_threads: n = {n!r} is not a positive integer (e.g. n=1)")
    ngs.SetNumThreads(n)
    note_threads(n)
    return n
