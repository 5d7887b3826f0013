"""The state of a run between two steps: everything a stepper needs to continue it exactly."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import ngsolve as ngs


@dataclass(frozen=True, eq=False)
class StepperState:
    """A stepper's state after step ``k`` (:meth:`PhaseFieldStepper.state`).

    ``fields`` holds copies of u, u_prev and z on ``mesh`` (z is also the non-repair bound
    of the next step); factorizations are not part of it (they are rebuilt).
    """

    k: int
    ticks: int
    """Time as a count of time.dt (t = ticks * dt)."""
    level: int
    """The adaptive step level (step = dt * 2**level)."""
    mesh: ngs.Mesh
    fields: dict[str, ngs.GridFunction]
    nucleus: np.ndarray | None = None
    """With no initial crack: where z first reached 1/2."""
    previous_tip: np.ndarray | None = None
    """The last tip found (a tip never moves back along the crack)."""
    adapter: dict[str, Any] | None = None
    """:meth:`ngfrac.mesh.adapter.MeshAdapter.state`, with the mesh changes so far under
    ``"adaptations"``; None when the scene does not adapt."""



def copy_of(gf: ngs.GridFunction) -> ngs.GridFunction:
    """A GridFunction on the same space with a copy of the values."""
    copy = ngs.GridFunction(gf.space, gf.name)
    copy.vec.data = gf.vec
    return copy


STATE_FIELDS = ("u", "u_prev", "z")
"""The names in :attr:`StepperState.fields`."""
