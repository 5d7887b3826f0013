"""The figures of a study: each headline quantity against each varied key, ``plots/<key>.png``.

Runs that differ in the other keys are separate lines (labelled by those values). In a
refinement study the figure of a grouping key shows the finest level of each group with its
GCI as an error bar (where the estimate converged), the Richardson-extrapolated value as an
open marker and the range of the group's levels as a grey bar; the figure of the refined key
shows every level.
"""
from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from .plan import StudyPlan

__all__ = ["plot_study"]


def _number(value: Any) -> float | None:
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return float(value)
    try:
        return float(value)
    except (TypeError, ValueError):
        return None


def _finite(value: Any) -> float:
    number = _number(value)
    return number if number is not None and math.isfinite(number) else math.nan


def plot_study(out: Path, plan: StudyPlan, table: list[dict[str, Any]]) -> list[Path]:
    """Write ``out/plots/<key>.png`` for every varied key; returns the files written."""
    from ..io.plotting import new_figure  # Agg, outside pyplot: the session's backend stays
    from .engine import FINISHED, quantity_names

    finished = [row for row in table if row.get("status") == FINISHED]
    quantities = [name for name in quantity_names(table)
                  if any(math.isfinite(_finite(row.get(name))) for row in finished)]
    if not finished or not quantities:
        return []
    (out / "plots").mkdir(exist_ok=True)
    written = []
    for key in plan.keys:
        refined = key in plan.refine_keys
        if plan.refine_keys and not refined and key not in plan.grouping_keys:
            continue
        if refined and key != plan.refine_keys[0]:
            continue  # the keys refined together: one figure, against the first
        rows = finished if refined or not plan.refine_keys else [
            row for row in finished if row.get("level") == plan.levels - 1]
        if not rows:
            continue
        columns = min(3, len(quantities))
        lines = math.ceil(len(quantities) / columns)
        fig = new_figure(figsize=(4.2 * columns, 3.3 * lines))
        axes = fig.subplots(lines, columns, squeeze=False)
        others = [k for k in (plan.grouping_keys if plan.refine_keys else plan.keys) if k != key]
        numeric = all(_number(row.get(key)) is not None for row in rows)
        categories = list(dict.fromkeys(json.dumps(row.get(key)) for row in rows))
        for ax, name in zip(axes.flat, quantities):
            groups: dict[str, list[dict[str, Any]]] = {}
            for row in rows:
                label = ", ".join(f"{k.rsplit('.', 1)[-1]}={row.get(k)}" for k in others)
                groups.setdefault(label, []).append(row)
            for label, members in groups.items():
                xs = [(_number(r.get(key)) if numeric else categories.index(json.dumps(r.get(key))))
                      for r in members]
                order = sorted(range(len(xs)), key=lambda i: xs[i])
                xs = [xs[i] for i in order]
                members = [members[i] for i in order]
                ys = [_finite(r.get(name)) for r in members]
                gci = [_finite(r.get(f"{name}_gci")) for r in members]
                line = ax.errorbar(xs, ys, yerr=[0 if g != g else g for g in gci], marker="o",
                                   capsize=3, label=label or None)
                if plan.refine_keys and not refined:  # the levels behind each point
                    for x, r in zip(xs, members):
                        levels = [_finite(o.get(name)) for o in finished
                                  if all(o.get(k) == r.get(k) for k in plan.grouping_keys)]
                        levels = [v for v in levels if math.isfinite(v)]
                        if len(levels) > 1:
                            ax.vlines(x, min(levels), max(levels), color="0.6", linewidth=6,
                                      alpha=0.35, zorder=0)
                extrapolated = [(x, _finite(r.get(f"{name}_extrapolated")))
                                for x, r in zip(xs, members)]
                extrapolated = [(x, e) for x, e in extrapolated if math.isfinite(e)]
                if extrapolated:
                    ax.plot(*zip(*extrapolated), linestyle="none", marker="o",
                            markerfacecolor="none", color=line[0].get_color(),
                            label="extrapolated" if not label else None)
            if refined and numeric:
                from matplotlib.ticker import NullFormatter

                ax.set_xscale("log")
                levels = sorted({_number(row.get(key)) for row in rows})
                ax.set_xticks(levels, [f"{x:.3g}" for x in levels])
                ax.xaxis.set_minor_formatter(NullFormatter())
            if not numeric:
                ax.set_xticks(range(len(categories)), [json.loads(c) for c in categories],
                              rotation=20)
            ax.set_xlabel(key)
            ax.set_ylabel(name)
            ax.grid(alpha=0.3)
        for ax in list(axes.flat)[len(quantities):]:
            ax.set_visible(False)
        handles, labels = axes.flat[0].get_legend_handles_labels()
        if labels:
            fig.legend(handles, labels, loc="upper center", ncol=min(4, len(labels)),
                       fontsize="small", frameon=False)
        title = ("finest level; bars: GCI (where converged); grey: range of the levels"
                 if plan.refine_keys and not refined else "")
        fig.suptitle(title, y=0.01, va="bottom", fontsize="small")
        fig.tight_layout(rect=(0, 0.03, 1, 0.93 if labels else 1))
        path = out / "plots" / f"{key}.png"
        fig.savefig(path, dpi=100)
        written.append(path)
    return written
