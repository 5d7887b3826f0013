"""What the sub-problems of one run share: the time and 1/dt of the step, threads, the timer."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import ngsolve as ngs

from .communicator import SERIAL

from .profiling import PhaseTimer
from ..fem.threads import ThreadPolicy


@dataclass(frozen=True, eq=False)
class StepContext:
    """The Parameters a step sets and the sub-problems' forms read, and how they run.

    ``time`` is t_k (boundary values, body force), ``inv_dt`` is 1/dt of the step (the
    alpha1 and alpha2 terms); ``threads`` says where NGSolve's threads are used, ``timer``
    collects the time of each phase and ``comm`` is the run's communicator
    (:mod:`ngfrac.parallel`: one process, or an MPI job).
    """

    time: ngs.Parameter = field(default_factory=lambda: ngs.Parameter(0.0))
    inv_dt: ngs.Parameter = field(default_factory=lambda: ngs.Parameter(1.0))
    threads: ThreadPolicy = field(default_factory=ThreadPolicy)
    timer: PhaseTimer = field(default_factory=PhaseTimer)
    comm: Any = SERIAL
