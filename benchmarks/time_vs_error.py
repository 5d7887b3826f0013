"""Run time against error: uniform meshes, adaptive meshes, element orders, against a reference.

    python benchmarks/time_vs_error.py [--quick] [--out DIR]

For the mode III slit scene (demos/mode3_slit.toml; ``--quick`` uses epsilon = 0.04 and a
shorter time step so the whole study fits in minutes) it runs

- uniform meshes at several h (orders 1 and 2, and 3 for u),
- adaptive meshes at several vertex caps,

and compares each run with a reference computed once with the finest settings and cached in
``DIR/reference.h5``. Errors: the crack-length history (max over time, relative), the tip path
(max distance of tip_x over time, relative to the width) and the total energy history (max,
relative). It writes ``DIR/time_vs_error.csv``, ``DIR/time_vs_error.png`` (log-log wall time
against crack-length error) and prints the table and the Pareto front (runs no other run beats
in both time and error).
"""
from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import h5py
import numpy as np

from ngfrac import PhaseFieldStepper, load_scene

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "demos" / "mode3_slit.toml"
COLUMNS = ("t", "crack_length", "tip_x", "E_total")


def presets(quick: bool) -> tuple[list[str], dict[str, list[str]], list[str]]:
    """Common overrides, the runs (name -> overrides) and the reference's overrides."""
    if quick:
        common = ["phase_field.epsilon=0.04", "time.dt=1e-3", "time.t_end=0.14"]
        uniform_h = [0.04, 0.02, 0.01]
        caps = [1000, 2000, 4000]
        reference = ["adaptivity.enabled=false", "geometry.mesh_size=0.005"]
    else:
        common = []
        uniform_h = [0.02, 0.01, 0.005]
        caps = [2500, 5000, 10000]
        reference = ["adaptivity.enabled=false", "geometry.mesh_size=0.0025"]
    runs: dict[str, list[str]] = {}
    for order in (1, 2):
        for h in uniform_h:
            runs[f"uniform P{order} h={h}"] = ["adaptivity.enabled=false", f"geometry.mesh_size={h}",
                                               f"discretization.order={order}",
                                               f"discretization.order_z={order}"]
    runs[f"uniform P3/P2 h={uniform_h[1]}"] = ["adaptivity.enabled=false",
                                               f"geometry.mesh_size={uniform_h[1]}",
                                               "discretization.order=3"]
    for cap in caps:
        runs[f"adaptive P2 cap={cap}"] = ["adaptivity.enabled=true", f"adaptivity.max_vertices={cap}"]
    return common, runs, reference


def history_of(overrides: list[str]) -> tuple[dict[str, np.ndarray], float, int]:
    scene = load_scene(SCENE, overrides)
    started = time.perf_counter()
    stepper = PhaseFieldStepper(scene)
    records = [stepper.record()] + list(stepper.run())
    wall = time.perf_counter() - started
    data = {c: np.array([getattr(r, c) for r in records]) for c in COLUMNS}
    return data, wall, max(r.nv for r in records)


def reference_history(path: Path, overrides: list[str]) -> dict[str, np.ndarray]:
    key = "|".join(overrides)
    if path.exists():
        with h5py.File(path, "r") as f:
            if f.attrs.get("overrides") == key:
                return {c: f[c][()] for c in COLUMNS}
    data, wall, nv = history_of(overrides)
    with h5py.File(path, "w") as f:
        f.attrs["overrides"] = key
        f.attrs["wall_s"] = wall
        f.attrs["nv"] = nv
        for c in COLUMNS:
            f[c] = data[c]
    return data


def errors(run: dict[str, np.ndarray], ref: dict[str, np.ndarray], width: float) -> dict[str, float]:
    t = ref["t"]

    def on_ref(column: str) -> np.ndarray:
        return np.interp(t, run["t"], run[column])

    length = np.max(np.abs(on_ref("crack_length") - ref["crack_length"]) / ref["crack_length"])
    tip = np.max(np.abs(on_ref("tip_x") - ref["tip_x"])) / width
    energy = np.max(np.abs(on_ref("E_total") - ref["E_total"])) / np.max(np.abs(ref["E_total"]))
    return {"crack_length_err": float(length), "tip_err": float(tip), "energy_err": float(energy)}


def pareto(rows: list[dict]) -> list[dict]:
    front = []
    for row in sorted(rows, key=lambda r: r["wall_s"]):
        if not front or row["crack_length_err"] < front[-1]["crack_length_err"]:
            front.append(row)
    return front


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default="out/time_vs_error")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    common, runs, reference = presets(args.quick)
    ref = reference_history(out / "reference.h5", common + reference)
    width = load_scene(SCENE).geometry.width
    rows = []
    for name, overrides in runs.items():
        data, wall, nv = history_of(common + overrides)
        row = {"run": name, "wall_s": wall, "max_nv": nv, **errors(data, ref, width)}
        rows.append(row)
        print(f"{name:<28} {wall:8.1f} s  nv<={nv:6d}  crack length {row['crack_length_err']:.3%}  "
              f"tip {row['tip_err']:.3%}  energy {row['energy_err']:.3%}", flush=True)
    with (out / "time_vs_error.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print("Pareto front (wall time, crack-length error):")
    for row in pareto(rows):
        print(f"  {row['run']:<28} {row['wall_s']:8.1f} s  {row['crack_length_err']:.3%}")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5), constrained_layout=True)
    for kind, marker in (("uniform P1", "s"), ("uniform P2", "o"), ("uniform P3", "^"), ("adaptive", "*")):
        sel = [r for r in rows if r["run"].startswith(kind)]
        if sel:
            ax.loglog([r["wall_s"] for r in sel], [max(r["crack_length_err"], 1e-6) for r in sel],
                      marker, label=kind, ms=8)
    ax.set(xlabel="wall time (s)", ylabel="max relative crack-length error",
           title="Run time against error (mode III slit)")
    ax.legend()
    fig.savefig(out / "time_vs_error.png", dpi=110)


if __name__ == "__main__":
    main()
