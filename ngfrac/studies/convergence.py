"""Convergence studies: one scene run over the values of one setting, errors, fitted rates.

Call :func:`convergence_study` from your own pytest files::

    from ngfrac.studies import convergence_study

    table = convergence_study(scene, "geometry.mesh_size", [0.2, 0.1, 0.05],
                              {"L2": l2_error}, run=solve_once)
    table.assert_rate("L2", 3.0, tol=0.2)      # fails with the printed table

Each value ``v`` gives the scene ``Scene.from_dict(apply_overrides(scene.to_dict(), [f"{key}={v}"]))``
(the same path as ``ngfrac run --set key=v``), which is run and measured. Rates are the slope
of ``numpy.polyfit(log(abscissa), log(error), 1)``: ``error ~ C abscissa**rate``. Against the
mesh size a rate is positive (``p + 1`` for the L2 error of elements of order ``p``); against
the number of degrees of freedom it is negative (``-(p + 1)/2`` in 2D).
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from ..scene import Scene, SceneError, apply_overrides

ErrorFunction = Callable[[Any, Any], float]
"""``f(result, reference) -> float``: one error of one run."""

LAST = "last"
"""``reference=LAST``: the run of the last value is the reference (and gets no row)."""


@dataclass(frozen=True)
class StudyRun:
    """What the default run returns: the stepper after its last step and every record.

    ``records[0]`` is the initial state (step 0), then one record per step.
    """

    scene: Scene
    stepper: Any
    records: list

    @property
    def ndof(self) -> int:
        """Degrees of freedom of u plus those of z at the end of the run."""
        return int(self.records[-1].ndof)


def run_all_steps(scene: Scene) -> StudyRun:
    """The default ``run=``: a :class:`~ngfrac.solve.stepper.PhaseFieldStepper` to the end time."""
    from ..solve.stepper import PhaseFieldStepper

    stepper = PhaseFieldStepper(scene)
    records = [stepper.record()]
    records.extend(stepper.run())
    return StudyRun(scene, stepper, records)


@dataclass(frozen=True)
class StudyRow:
    """One run of a study: the setting's value, the abscissa of the fit and the errors."""

    value: Any
    abscissa: float
    errors: dict[str, float]
    wall_s: float
    ndof: int | None = None


@dataclass(frozen=True)
class StudyTable:
    """The measured errors of a study and the rates fitted to them.

    ``rows`` are in the order of the values; ``rates[name]`` is the least-squares slope of
    log(error) over log(abscissa) (NaN when fewer than two rows have a positive, finite error).
    """

    key: str
    abscissa: str
    rows: tuple[StudyRow, ...]
    rates: dict[str, float] = field(default_factory=dict)

    @property
    def names(self) -> list[str]:
        """The error names, in the order given to the study."""
        return list(self.rows[0].errors) if self.rows else []

    def errors(self, name: str) -> np.ndarray:
        """The errors ``name`` of all rows."""
        return np.array([row.errors[name] for row in self.rows], dtype=float)

    def local_rates(self, name: str) -> np.ndarray:
        """Rates between consecutive rows (NaN in the first row)."""
        x = np.array([row.abscissa for row in self.rows], dtype=float)
        e = self.errors(name)
        rates = np.full(len(e), math.nan)
        with np.errstate(divide="ignore", invalid="ignore"):
            rates[1:] = np.log(e[1:] / e[:-1]) / np.log(x[1:] / x[:-1])
        return rates

    def __str__(self) -> str:
        names = self.names
        header = [self.key]
        if self.abscissa != "value":
            header.append(self.abscissa)
        show_ndof = self.abscissa != "ndof" and any(row.ndof is not None for row in self.rows)
        if show_ndof:
            header.append("ndof")
        for name in names:
            header += [name, "rate"]
        header.append("wall s")
        local = {name: self.local_rates(name) for name in names}
        lines = []
        for i, row in enumerate(self.rows):
            cells = [_format(row.value)]
            if self.abscissa != "value":
                cells.append(f"{row.abscissa:.6g}")
            if show_ndof:
                cells.append("" if row.ndof is None else str(row.ndof))
            for name in names:
                rate = local[name][i]
                cells += [f"{row.errors[name]:.3e}", "" if math.isnan(rate) else f"{rate:.2f}"]
            cells.append(f"{row.wall_s:.2f}")
            lines.append(cells)
        widths = [max(len(h), *(len(c[j]) for c in lines)) for j, h in enumerate(header)]
        text = ["  ".join(h.rjust(w) for h, w in zip(header, widths))]
        text += ["  ".join(c.rjust(w) for c, w in zip(cells, widths)) for cells in lines]
        fitted = ", ".join(f"{name} {self.rates[name]:.2f}" for name in names)
        text.append(f"fitted rates (polyfit of log error over log {self._abscissa_name}): {fitted}")
        return "\n".join(text)

    @property
    def _abscissa_name(self) -> str:
        return self.key if self.abscissa == "value" else self.abscissa

    def assert_rate(self, name: str, expected: float, tol: float, at_least: bool = False) -> None:
        """Check a fitted rate; the AssertionError carries the whole table.

        Parameters
        ----------
        name : str
            An error name given to the study.
        expected, tol : float
            Passes when ``|rate - expected| <= tol``.
        at_least : bool
            Pass also for any rate above ``expected - tol`` (superconvergence is fine).
        """
        if name not in self.rates:
            raise KeyError(f"no error named {name!r} in this study; it has {', '.join(self.rates)}")
        rate = self.rates[name]
        ok = rate >= expected - tol if at_least else abs(rate - expected) <= tol
        if not ok:  # also for a NaN rate
            wanted = f">= {expected - tol:g}" if at_least else f"{expected:g} +- {tol:g}"
            raise AssertionError(f"{name} rate {rate:.3f} against {self._abscissa_name}, "
                                 f"expected {wanted}\n{self}")


def fit_rate(abscissa: Sequence[float], errors: Sequence[float]) -> float:
    """Slope of ``numpy.polyfit(log(abscissa), log(errors), 1)`` over the points where both
    are positive and finite; NaN when fewer than two such points remain."""
    x = np.asarray(abscissa, dtype=float)
    e = np.asarray(errors, dtype=float)
    keep = np.isfinite(x) & np.isfinite(e) & (x > 0) & (e > 0)
    if np.count_nonzero(keep) < 2 or len(np.unique(x[keep])) < 2:
        return math.nan
    return float(np.polyfit(np.log(x[keep]), np.log(e[keep]), 1)[0])


def scene_with(scene: Scene, key: str, value: Any) -> Scene:
    """``scene`` with one dotted key set, validated as ``--set key=value`` would be.

    Raises :class:`~ngfrac.scene.SceneError` naming the key for an unknown key or a value
    out of range.
    """
    override = f"{key}={_toml(value, key)}"
    try:
        return Scene.from_dict(apply_overrides(scene.to_dict(), [override]), name=scene.name)
    except SceneError as err:
        raise SceneError(f"convergence study over {key!r}: {err}") from None


def convergence_study(scene: Scene, key: str, values: Sequence[Any],
                      errors: Mapping[str, ErrorFunction], *,
                      run: Callable[[Scene], Any] | None = None,
                      reference: Any = None,
                      abscissa: str | Callable[[Any, Any], float] = "value") -> StudyTable:
    """Run ``scene`` once per value of the setting ``key`` and fit convergence rates.

    Parameters
    ----------
    scene : Scene
        The scene every run starts from.
    key : str
        A dotted scene key, as for ``--set``: ``"geometry.mesh_size"``,
        ``"discretization.order"``, ``"adaptivity.max_vertices"``, ``"phase_field.epsilon"``,
        ``"time.dt"``, ...
    values : sequence
        The values of ``key``, at least two (all scenes are validated before the first run).
    errors : mapping of name to ``f(result, reference) -> float``
        The errors measured on each run's result.
    run : callable(scene) -> result, optional
        How to run one scene; the default runs every step of a ``PhaseFieldStepper`` and
        returns a :class:`StudyRun` (``.stepper``, ``.records``, ``.ndof``).
    reference : object or ``"last"``, optional
        Passed to every error function as its second argument. ``"last"`` runs the last value
        first and passes its result (the last value then gets no row).
    abscissa : ``"value"``, ``"ndof"`` or callable(value, result) -> float
        What the rates are fitted against: the setting's value, the result's ``ndof``
        attribute, or a number you compute.

    Returns
    -------
    StudyTable
    """
    values = list(values)
    if len(values) < 2:
        raise ValueError(f"a convergence study needs at least two values of {key!r}, got {values!r}")
    if not errors:
        raise ValueError("a convergence study needs at least one error function")
    if not (callable(abscissa) or abscissa in ("value", "ndof")):
        raise ValueError(f"abscissa = {abscissa!r}: choose 'value', 'ndof' or a callable(value, result)")
    scenes = [scene_with(scene, key, value) for value in values]  # fail before any run
    run = run or run_all_steps
    if isinstance(reference, str) and reference == LAST:
        if len(values) < 3:
            raise ValueError("reference='last' needs at least three values (two rows to fit)")
        reference = run(scenes[-1])
        values, scenes = values[:-1], scenes[:-1]
    rows = []
    for value, sc in zip(values, scenes):
        started = time.perf_counter()
        result = run(sc)
        wall = time.perf_counter() - started
        measured = {name: float(f(result, reference)) for name, f in errors.items()}
        ndof = _ndof(result)
        if callable(abscissa):
            x = float(abscissa(value, result))
        elif abscissa == "ndof":
            if ndof is None:
                raise TypeError(f"abscissa='ndof' needs a result with an ndof attribute; run "
                                f"returned {type(result).__name__}")
            x = float(ndof)
        else:
            x = _number(value, key)
        rows.append(StudyRow(value, x, measured, wall, ndof))
    x = [row.abscissa for row in rows]
    rates = {name: fit_rate(x, [row.errors[name] for row in rows]) for name in errors}
    name = abscissa if isinstance(abscissa, str) else getattr(abscissa, "__name__", "abscissa")
    return StudyTable(key, name, tuple(rows), rates)


def _ndof(result: Any) -> int | None:
    ndof = getattr(result, "ndof", None)
    if ndof is not None:
        return int(ndof)
    spaces = [getattr(result, name, None) for name in ("fes_u", "fes_z")]
    if all(space is not None for space in spaces):  # a PhaseFieldStepper
        return int(sum(space.ndof for space in spaces))
    return None


def _number(value: Any, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError(f"the values of {key!r} are not numbers ({value!r}); fit against "
                        "abscissa='ndof' or a callable")
    return float(value)


def _toml(value: Any, key: str) -> str:
    """A TOML literal for an override value."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise SceneError(f"convergence study over {key!r}: {value!r} is not a finite number")
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)  # a JSON string is a TOML basic string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v, key) for v in value) + "]"
    raise TypeError(f"convergence study over {key!r}: cannot write {value!r} as a scene value")


def _format(value: Any) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)


__all__ = ["LAST", "StudyRow", "StudyRun", "StudyTable", "convergence_study", "fit_rate",
           "run_all_steps", "scene_with"]
