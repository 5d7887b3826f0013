"""Wall time per phase of a run: what ``ngfrac run --profile`` prints."""
from __future__ import annotations

import time
from contextlib import contextmanager
from typing import Iterator


class PhaseTimer:
    """Accumulates wall time and call counts per named phase.

    Examples
    --------
    >>> timer = PhaseTimer()
    >>> with timer.phase("u: solve"):
    ...     pass
    >>> timer.calls["u: solve"]
    1
    """

    def __init__(self) -> None:
        self.started = time.perf_counter()
        """When the timer was made (``perf_counter``)."""
        self.seconds: dict[str, float] = {}
        self.calls: dict[str, int] = {}

    @contextmanager
    def phase(self, name: str) -> Iterator[None]:
        started = time.perf_counter()
        try:
            yield
        finally:
            self.add(name, time.perf_counter() - started)

    def add(self, name: str, seconds: float) -> None:
        self.seconds[name] = self.seconds.get(name, 0.0) + seconds
        self.calls[name] = self.calls.get(name, 0) + 1

    def table(self, total: float | None = None) -> str:
        """A text table, phases in the order first seen, with shares of ``total``."""
        total = total if total is not None else sum(self.seconds.values())
        lines = [f"{'phase':<30}{'calls':>8}{'total s':>10}{'per call ms':>13}{'share':>8}"]
        for name, seconds in self.seconds.items():
            calls = self.calls[name]
            share = seconds / total if total > 0 else 0.0
            lines.append(f"{name:<30}{calls:>8}{seconds:>10.2f}{1000 * seconds / calls:>13.2f}{share:>8.1%}")
        lines.append(f"{'measured phases':<30}{'':>8}{sum(self.seconds.values()):>10.2f}")
        lines.append(f"{'wall time of the run':<30}{'':>8}{total:>10.2f}")
        return "\n".join(lines)
