"""Time-step control: steps of ``time.dt * 2**level``, halved when z jumps, doubled when calm.

Times are counted in ticks of ``time.dt`` (t = ticks * dt, a product, never a sum). With
``time.adaptive``, a step whose largest nodal change of z exceeds ``dz_target`` is redone
with a step 2**j times smaller (j from how far it is off), and a step whose Newton u-solve
(a split) failed is redone with half the step (:meth:`StepSizeControl.halve`); after a step that changed z by
less than a quarter of the target, the step doubles when the time is a multiple of the
doubled step (so output times stay on the grid).
"""
from __future__ import annotations

import math

from ..scene import TimeSettings


class StepSizeControl:
    """The level of the step size, dt * 2**level, and the rules that change it.

    Parameters
    ----------
    settings : TimeSettings
        The scene's ``[time]`` section.
    """

    def __init__(self, settings: TimeSettings) -> None:
        self.settings = settings
        self.level = settings.max_doublings if settings.adaptive else 0
        """The current step is dt * 2**level."""

    def ticks(self, done: int) -> int:
        """Ticks of the next step after ``done`` ticks (the last step ends at t_end)."""
        return min(2 ** self.level, self.settings.n_ticks - done)

    def rejects(self, dz_max: float) -> bool:
        """Whether a step that changed z by ``dz_max`` must be redone; if so the level is
        lowered by at least one, more when far off."""
        s = self.settings
        if not (s.adaptive and dz_max > s.dz_target and self.level > 0):
            return False
        self.level = max(0, self.level - max(1, math.ceil(math.log2(dz_max / s.dz_target))))
        return True

    def halve(self) -> bool:
        """Lower the level by one for a step to be redone (its Newton u-solve failed); False
        when the step is already dt (level 0, or fixed steps): the run must give up. So a step
        is halved at most ``max_doublings`` times."""
        if self.level == 0:
            return False
        self.level -= 1
        return True

    def accepted(self, done: int, dz_max: float) -> None:
        """After an accepted step ending at ``done`` ticks: double the step when z changed by
        less than dz_target / 4 and ``done`` is a multiple of the doubled step."""
        s = self.settings
        if (s.adaptive and dz_max < s.dz_target / 4 and self.level < s.max_doublings
                and done % 2 ** (self.level + 1) == 0):
            self.level += 1
