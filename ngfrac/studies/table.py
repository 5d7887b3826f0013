"""The table of a study: one row per run folder, read from its ``history.csv`` and ``run.json``.

:func:`run_quantities` gives a run's headline numbers: the final ``crack_length`` and
``path_length``, ``peak_<F>`` (the value of largest magnitude, with its sign) of every reaction
column ``F`` of the history (``Fx_top``, ...), ``onset_t`` (the first time the crack set's
path length exceeds its initial value: the crack has grown; NaN if it never does, and in 3D,
where the history has no path length) and ``t_end`` (the last time reached).
:func:`write_table` writes ``study.csv`` atomically.
"""
from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

__all__ = ["FIXED_COLUMNS", "read_history", "read_table", "run_quantities", "write_table"]

FIXED_COLUMNS = ("name", "status", "error", "wall_s")
"""The columns of study.csv after the varied keys; the quantities follow."""
QUANTITIES = ("crack_length", "path_length", "onset_t", "t_end")


def read_history(path: Path) -> dict[str, list[float]]:
    """The columns of a ``history.csv`` as floats (an empty file: no columns)."""
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return {}
    header, body = rows[0], rows[1:]
    columns: dict[str, list[float]] = {name: [] for name in header}
    for row in body:
        for name, text in zip(header, row):
            try:
                columns[name].append(float(text))
            except ValueError:
                columns[name].append(math.nan)
    return columns


def _is_reaction(name: str) -> bool:
    """``Fx_top``, ``Fy_bottom``, ``Fz_...``, ``F_...`` (mode III): a reaction column."""
    head = name.split("_", 1)[0]
    return "_" in name and head in ("F", "Fx", "Fy", "Fz")


def _last_finite(values: Sequence[float]) -> float:
    return next((v for v in reversed(values) if math.isfinite(v)), math.nan)


def run_quantities(folder: Path) -> dict[str, float]:
    """The headline numbers of the run in ``folder`` (see the module's docstring)."""
    out = {name: math.nan for name in QUANTITIES}
    if not (folder / "history.csv").is_file():
        return out  # a run that failed before its first row
    history = read_history(folder / "history.csv")
    if not history.get("t"):
        return out
    out["t_end"] = history["t"][-1]
    out["crack_length"] = _last_finite(history.get("crack_length", []))
    out["path_length"] = _last_finite(history.get("path_length", []))
    path = history.get("path_length", [])
    finite = [(t, s) for t, s in zip(history["t"], path) if math.isfinite(s)]
    if finite:
        initial = finite[0][1]
        grown = next((t for t, s in finite if s > initial), math.nan)
        out["onset_t"] = grown
    for name, values in history.items():
        if _is_reaction(name):
            finite_values = [v for v in values if math.isfinite(v)]
            out[f"peak_{name}"] = max(finite_values, key=abs) if finite_values else math.nan
    return out


def _text(value: Any) -> str:
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ("nan" if value != value else repr(value))
    if isinstance(value, (list, tuple, dict)):
        import json

        return json.dumps(value)
    return "" if value is None else str(value)


def write_table(path: Path, rows: Iterable[Mapping[str, Any]], first: Sequence[str]) -> None:
    """Write ``rows`` to ``path`` (atomically, and not at all when the file already holds
    the same text): the columns ``first``, then every other key in the order first seen."""
    from ..io.output import atomic_write_text

    rows = list(rows)
    columns = list(first)
    for row in rows:
        columns += [key for key in row if key not in columns]
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow([_text(row.get(key)) for key in columns])
    text = buffer.getvalue()
    if path.is_file() and path.read_text() == text:
        return  # a study called again with nothing to do rewrites nothing
    atomic_write_text(path, text)


def read_table(path: Path) -> list[dict[str, str]]:
    """The rows of a ``study.csv`` as strings."""
    with path.open(newline="") as f:
        return list(csv.DictReader(f))
