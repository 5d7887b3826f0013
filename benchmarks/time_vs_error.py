"""Run time against error: uniform meshes, element orders, adaptive meshes and time steps.

    NGFRAC_THREADS=1 python benchmarks/time_vs_error.py [--preset quick|full|sent]
        [--out DIR] [--only SUBSTRING ...] [--fresh]

Each preset is one scene and a list of runs (name -> ``--set`` overrides):

- ``quick``: the mode III slit of Fig. 2 (demos/mode3_slit.toml) with epsilon = 0.04,
  dt = 1e-3 and t_end = 0.14 (140 steps). On one thread of a loaded machine the reference
  took 18 min, the uniform P2 run at h = 0.005 (45k vertices) 21 min, the other runs
  together about half an hour (docs/benchmarks.md);
- ``full``: the same scene as the demo file gives it (epsilon = 0.02, dt = 5e-4, 300 steps);
  not run yet: its reference (adaptive, cap 20,000, 300 steps) would take hours on one thread
  (an estimate from the quick one: cap 16,000, 140 steps, 18 min);
- ``sent``: single-edge notched tension with the notch as a z0 band
  (benchmarks/scenes/sent_band.toml, the SENT demo's scene until session 20; the demo now cuts
  the notch out of the geometry) with epsilon = 0.03 and 68 steps,
  with the force-displacement error (F_y on the top against its displacement).

The runs are uniform meshes at several h (orders 1 and 2, and order 3 for u at one h),
adaptive meshes at several vertex caps, and the same adaptive runs with adaptive time steps
(``time.adaptive = true``, everything else equal). Each run is compared with a reference
computed once with finer settings and cached in ``DIR/reference.h5``. Errors, each the
maximum over the reference's output times (a run is interpolated linearly in t onto them):

- ``crack_length_err``: |L - L_ref| / L_ref, L the Gamma-length 1/2 int(eps|grad z|^2 + z^2/eps);
- ``tip_err``: distance between the tips (x, y) at equal times, over the domain width (a crack
  that runs across in a few steps makes this one a measure of timing);
- ``path_err``: largest distance of the run's tips from the reference's tip path (a polyline),
  over the width: the path whatever the timing;
- ``energy_err``: |E_total - E_ref| / max|E_ref|;
- ``force_err`` (plane models): |F_y,top - F_ref| / max|F_ref|.

Wall time is that of the whole run (set-up, steps, a diagnosed record every step, no file
output). Each finished run is stored in ``DIR/runs.h5`` and skipped when the script runs
again (``--fresh`` reruns everything), so a long study can be done in parts. It writes
``DIR/time_vs_error.csv`` and ``DIR/time_vs_error.png`` (log-log wall time against
crack-length error) and prints the table, the Pareto front (runs no faster run beats in
crack-length error) and, for mode III, target (a) of issue #6 (1 % crack-length error
adaptively at least 10 times faster than uniformly) and the saving of adaptive time steps.
"""
from __future__ import annotations

import argparse
import csv
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

import ngfrac
from ngfrac import PhaseFieldStepper, load_scene
from ngfrac.physics.cracks import distance_to_polylines

ROOT = Path(__file__).resolve().parents[1]
COLUMNS = ("t", "crack_length", "tip_x", "tip_y", "E_total", "nv", "step_s", "solve_s", "adapt_s",
           "force", "solves")


@dataclass(frozen=True)
class Preset:
    scene: Path
    common: list[str]
    runs: dict[str, list[str]]
    reference: list[str]
    force: str | None = None
    """History column of the reaction force compared for the force-displacement error."""


def _uniform(h: float, order: int, order_z: int | None = None) -> list[str]:
    # fixed steps named: sent_band.toml sets adaptive ones, which the adaptive runs choose
    return ["adaptivity.enabled=false", f"geometry.mesh_size={h}", f"discretization.order={order}",
            f"discretization.order_z={order_z or min(order, 2)}", "time.adaptive=false"]


def _adaptive(cap: int, adaptive_dt: bool, size_field: str = "bands") -> list[str]:
    # the size field always named: the demo's scene sets "equidistributed", the default is
    # "bands" (before this was named, the "bands" runs of the quick preset took the scene's)
    return ["adaptivity.enabled=true", f"adaptivity.max_vertices={cap}",
            f"time.adaptive={'true' if adaptive_dt else 'false'}", f"adaptivity.size_field={size_field}"]


def _equidistributed_runs(caps: list[int]) -> dict[str, list[str]]:
    """The adaptive runs with ``adaptivity.size_field = "equidistributed"``."""
    runs = {f"adaptive P2 equidistributed cap={cap}": _adaptive(cap, False, "equidistributed")
            for cap in caps}
    runs.update({f"adaptive P2 equidistributed cap={cap} dt-adaptive": _adaptive(cap, True, "equidistributed")
                 for cap in caps})
    return runs


def _mode3_runs(uniform_h: list[float], p3_h: float, caps: list[int]) -> dict[str, list[str]]:
    runs: dict[str, list[str]] = {}
    for order in (1, 2):
        for h in uniform_h:
            runs[f"uniform P{order} h={h}"] = _uniform(h, order)
    runs[f"uniform P3/P2 h={p3_h}"] = _uniform(p3_h, 3)
    for cap in caps:
        runs[f"adaptive P2 cap={cap}"] = _adaptive(cap, False)
    for cap in caps:
        runs[f"adaptive P2 cap={cap} dt-adaptive"] = _adaptive(cap, True)
    return runs


def presets() -> dict[str, Preset]:
    mode3 = ROOT / "demos" / "mode3_slit.toml"
    quick = Preset(
        mode3, ["phase_field.epsilon=0.04", "time.dt=1e-3", "time.t_end=0.14"],
        {**_mode3_runs([0.04, 0.02, 0.01], 0.02, [1000, 2000, 3000, 4000, 6000]),
         **_equidistributed_runs([2000, 3000, 4000]),
         "uniform P1 h=0.005": _uniform(0.005, 1), "uniform P2 h=0.005": _uniform(0.005, 2),
         # where P2's rate between h = 0.01 and 0.005 puts 1 % (docs/benchmarks.md, target (a))
         "uniform P2 h=0.0063": _uniform(0.0063, 2)},
        # finer than every run at the crack: h = eps/20 in the core, eps/8 in the band (a
        # uniform P2 mesh of eps/8 is one of the runs, a check on the reference)
        _adaptive(16000, False) + ["adaptivity.h_crack=0.002", "adaptivity.h_band=0.005",
                                   "adaptivity.hmin=1e-3"])
    full = Preset(
        mode3, [],
        _mode3_runs([0.02, 0.01], 0.01, [2500, 5000]),
        # uniform h = 0.0025 would take hours; the reference is adaptive with twice the finest cap
        _adaptive(20000, False) + ["adaptivity.hmin=1e-3"])
    sent = Preset(
        # the coarse SENT of the demo tests (the band's scene): epsilon 0.03, 68 steps
        ROOT / "benchmarks" / "scenes" / "sent_band.toml",
        ["phase_field.epsilon=0.03", "time.dt=1.25e-4", "time.t_end=8.5e-3"],
        {**{f"uniform P1 h={h}": _uniform(h, 1) for h in (0.03, 0.015)},
         **{f"uniform P2 h={h}": _uniform(h, 2) for h in (0.03, 0.015)},
         **{f"adaptive P2 cap={c}": _adaptive(c, False) for c in (1000, 2000)},
         **{f"adaptive P2 cap={c} dt-adaptive": _adaptive(c, True) for c in (1000, 2000)}},
        _adaptive(6000, False) + ["adaptivity.h_crack=0.0015", "adaptivity.h_band=0.00375",
                                  "adaptivity.hmin=1e-3"], force="Fy_top")
    return {"quick": quick, "full": full, "sent": sent}


def code_state() -> str:
    """The commit and the number of changed files under ngfrac/ and estimators/ (the tree is shared)."""
    def git(*args: str) -> str:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True).stdout.strip()

    dirty = len(git("status", "--porcelain", "ngfrac", "estimators").splitlines())
    return git("rev-parse", "--short", "HEAD") + (f"+{dirty} changed" if dirty else "")


def history_of(scene_path: Path, overrides: list[str], force: str | None,
               code: str) -> tuple[dict[str, np.ndarray], float]:
    """Run a scene (no files written); its history and the wall time of set-up and steps."""
    scene = load_scene(scene_path, overrides)
    started = time.perf_counter()
    stepper = PhaseFieldStepper(scene)
    records = [stepper.record()] + list(stepper.run(history_every=1))
    wall = time.perf_counter() - started
    data = {c: np.array([getattr(r, c) for r in records], dtype=float)
            for c in COLUMNS if c not in ("force", "solves")}
    data["force"] = np.array([r.forces.get(force, np.nan) if force else np.nan for r in records])
    # u-solves, rejected (redone) adaptive time steps included: a count the machine's load
    # does not change
    data["solves"] = np.array([stepper.timer.calls.get("u: solve", 0)])
    data["code"] = code
    return data, wall


def _load(group: h5py.Group) -> tuple[dict[str, np.ndarray], float]:
    data = {c: group[c][()] if c in group else np.array([np.nan]) for c in COLUMNS}
    data["code"] = str(group.attrs.get("code", "?"))
    return data, float(group.attrs["wall_s"])


def _store(group: h5py.Group, key: str, data: dict[str, np.ndarray], wall: float) -> None:
    group.attrs["overrides"] = key
    group.attrs["wall_s"] = wall
    group.attrs["code"] = data["code"]
    for c in COLUMNS:
        group[c] = data[c]


def cached_history(path: Path, name: str, scene: Path, overrides: list[str], force: str | None,
                   fresh: bool, code: str) -> tuple[dict[str, np.ndarray], float, bool]:
    """The run's history from ``path`` if it holds this exact run, else run it and store it."""
    key = f"{scene.name}|" + "|".join(overrides)
    with h5py.File(path, "a") as f:
        if not fresh and name in f and f[name].attrs.get("overrides") == key:
            return *_load(f[name]), True
    data, wall = history_of(scene, overrides, force, code)
    with h5py.File(path, "a") as f:
        if name in f:
            del f[name]
        _store(f.create_group(name), key, data, wall)
    return data, wall, False


def errors(run: dict[str, np.ndarray], ref: dict[str, np.ndarray], width: float) -> dict[str, float]:
    t = ref["t"]

    def on_ref(column: str) -> np.ndarray:
        return np.interp(t, run["t"], run[column])

    length = np.max(np.abs(on_ref("crack_length") - ref["crack_length"]) / ref["crack_length"])
    tips = np.hypot(on_ref("tip_x") - ref["tip_x"], on_ref("tip_y") - ref["tip_y"])
    tip = np.nanmax(tips) / width if np.any(np.isfinite(tips)) else np.nan
    # the path alone, whatever the timing: the run's tips against the polyline of the reference's
    ref_path = np.c_[ref["tip_x"], ref["tip_y"]]
    ref_path = ref_path[np.all(np.isfinite(ref_path), axis=1)]
    run_path = np.c_[run["tip_x"], run["tip_y"]]
    run_path = run_path[np.all(np.isfinite(run_path), axis=1)]
    path = (np.max(distance_to_polylines(run_path, [ref_path])) / width
            if len(ref_path) > 1 and len(run_path) else np.nan)
    energy = np.max(np.abs(on_ref("E_total") - ref["E_total"])) / np.max(np.abs(ref["E_total"]))
    out = {"crack_length_err": float(length), "tip_err": float(tip), "path_err": float(path),
           "energy_err": float(energy)}
    if np.all(np.isfinite(ref["force"])):
        out["force_err"] = float(np.max(np.abs(on_ref("force") - ref["force"])) / np.max(np.abs(ref["force"])))
    return out


def costs(run: dict[str, np.ndarray]) -> dict[str, float]:
    """Steps, vertices and the per-step cost split (records after the initial one)."""
    step, solve, adapt = run["step_s"][1:], run["solve_s"][1:], run["adapt_s"][1:]
    changed = adapt > 0.05 * np.median(step)  # steps with a new mesh (the check alone is ~ms)
    plain = ~changed
    return {"steps": len(step), "solves": int(run["solves"][0]) if np.isfinite(run["solves"][0]) else "",
            "max_nv": int(run["nv"].max()), "median_nv": int(np.median(run["nv"])),
            "step_over_solves": float(step.sum() / solve.sum()),
            "plain_step_over_solves": float(np.median(step[plain] / solve[plain])) if plain.any() else np.nan,
            "adapt_share": float(adapt.sum() / step.sum())}


def pareto(rows: list[dict], key: str = "crack_length_err") -> list[dict]:
    front = []
    for row in sorted(rows, key=lambda r: r["wall_s"]):
        if not front or row[key] < front[-1][key]:
            front.append(row)
    return front


def targets(rows: list[dict], level: float = 0.01) -> None:
    """The issue's targets: time to `level` crack-length error, adaptive against uniform."""
    def best(prefix: str) -> dict | None:
        ok = [r for r in rows if r["run"].startswith(prefix) and r["crack_length_err"] <= level]
        return min(ok, key=lambda r: r["wall_s"]) if ok else None

    uniform, adaptive = best("uniform"), best("adaptive")
    print(f"Target (a): time to <= {level:.0%} crack-length error")
    for label, row in (("uniform", uniform), ("adaptive", adaptive)):
        print(f"  best {label:<9}: " + (f"{row['run']} {row['wall_s']:.1f} s ({row['crack_length_err']:.2%})"
                                        if row else "none reaches it"))
    if uniform and adaptive:
        print(f"  speed-up {uniform['wall_s'] / adaptive['wall_s']:.2f}x (target >= 10x)")
    fixed = {r["run"]: r for r in rows if r["run"].startswith("adaptive") and "dt-adaptive" not in r["run"]}
    for r in rows:
        if r["run"].endswith(" dt-adaptive") and r["run"][:-len(" dt-adaptive")] in fixed:
            f = fixed[r["run"][:-len(" dt-adaptive")]]
            print(f"  adaptive time steps, {f['run']}: {r['steps']} vs {f['steps']} steps "
                  f"({r['solves'] or '?'} vs {f['solves'] or '?'} solve pairs with redone steps), "
                  f"{r['wall_s']:.1f} vs {f['wall_s']:.1f} s ({f['wall_s'] / r['wall_s']:.2f}x), "
                  f"crack-length error {r['crack_length_err']:.2%} vs {f['crack_length_err']:.2%}")


def plot(rows: list[dict], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4), constrained_layout=True)
    kinds = (("uniform P1", "s", "uniform P1"), ("uniform P2", "o", "uniform P2"),
             ("uniform P3", "^", "uniform P3 (u) / P2 (z)"), ("adaptive", "*", "adaptive P2, bands"),
             ("dt-adaptive", "P", "adaptive P2, bands, adaptive time steps"),
             ("equidistributed", "D", "adaptive P2, equidistributed"),
             ("equidistributed dt-adaptive", "X", "adaptive P2, equidistributed, adaptive time steps"))

    def chosen(run: str, kind: str) -> bool:
        if not kind.startswith(("adaptive", "dt-adaptive", "equidistributed")):
            return run.startswith(kind)
        return (run.startswith("adaptive") and ("equidistributed" in run) == kind.startswith("equi")
                and ("dt-adaptive" in run) == kind.endswith("dt-adaptive"))

    for kind, marker, label in kinds:
        sel = [r for r in rows if chosen(r["run"], kind)]
        if sel:
            ax.loglog([r["wall_s"] for r in sel], [max(r["crack_length_err"], 1e-6) for r in sel],
                      marker, label=label, ms=7)
            for r in sel:  # "h=0.01" or "cap=4000": the legend says the rest
                ax.annotate(r["run"].replace(" dt-adaptive", "").split()[-1],
                            (r["wall_s"], max(r["crack_length_err"], 1e-6)), fontsize=6,
                            xytext=(4, 2), textcoords="offset points")
    ax.axhline(0.01, color="0.6", lw=0.8, ls="--")
    ax.set(xlabel="wall time (s, one thread)", ylabel="max relative crack-length error", title=title)
    ax.legend(fontsize=7)
    fig.savefig(path, dpi=90)


def main() -> None:
    ngfrac.set_threads()  # NGFRAC_THREADS (importing ngfrac sets nothing)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", choices=sorted(presets()), default="full")
    parser.add_argument("--quick", action="store_true", help="same as --preset quick")
    parser.add_argument("--out", default=None, help="output folder (default out/time_vs_error_PRESET)")
    parser.add_argument("--only", nargs="*", default=None,
                        help="run only the runs whose name contains one of these strings")
    parser.add_argument("--fresh", action="store_true", help="rerun runs stored in DIR/runs.h5")
    args = parser.parse_args()
    name = "quick" if args.quick else args.preset
    preset = presets()[name]
    out = Path(args.out or f"out/time_vs_error_{name}")
    out.mkdir(parents=True, exist_ok=True)
    code = code_state()  # ngfrac is imported now; later edits of the shared tree do not count
    ref, ref_wall, cached = cached_history(out / "reference.h5", "reference", preset.scene,
                                           preset.common + preset.reference, preset.force,
                                           args.fresh, code)
    print(f"reference ({' '.join(preset.reference)}): {ref_wall:.1f} s, {len(ref['t']) - 1} steps, "
          f"nv <= {int(ref['nv'].max())}{' (cached)' if cached else ''}", flush=True)
    width = load_scene(preset.scene).geometry.width
    rows = []
    for run_name, overrides in preset.runs.items():
        if args.only is not None and not any(s in run_name for s in args.only):
            continue
        data, wall, cached = cached_history(out / "runs.h5", run_name, preset.scene,
                                            preset.common + overrides, preset.force, args.fresh,
                                            code)
        row = {"run": run_name, "wall_s": round(wall, 2), **costs(data), **errors(data, ref, width),
               "code": data["code"]}
        rows.append(row)
        force = f"  force {row['force_err']:.3%}" if "force_err" in row else ""
        print(f"{run_name:<34} {wall:8.1f} s  {row['steps']:4d} steps  nv<={row['max_nv']:6d}  "
              f"crack length {row['crack_length_err']:.3%}  tip {row['tip_err']:.3%}  "
              f"path {row['path_err']:.3%}  "
              f"energy {row['energy_err']:.3%}{force}  step/solves {row['step_over_solves']:.2f}"
              f"{' (cached)' if cached else ''}", flush=True)
    if not rows:
        return
    with (out / "time_vs_error.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print("Pareto front (wall time, crack-length error):")
    for row in pareto(rows):
        print(f"  {row['run']:<34} {row['wall_s']:8.1f} s  {row['crack_length_err']:.3%}")
    if preset.force is None:
        targets(rows)
    plot(rows, out / "time_vs_error.png", f"Run time against error ({preset.scene.stem}, preset {name})")


if __name__ == "__main__":
    main()
