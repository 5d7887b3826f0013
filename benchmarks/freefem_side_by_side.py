"""Side by side with FreeFEM++ (the paper's tool): the same scheme, scene and vertex caps.

    NGFRAC_THREADS=1 python benchmarks/freefem_side_by_side.py [--preset quick|full]
        [--caps 1350 2600 ...] [--set key=value ...] [--out DIR] [--fresh-reference]
        [--tools FreeFEM ngfrac] [--ngfrac-set key=value ...] [--freefem-isotropic]
        [--freefem-no-slit-edge]

FreeFEM runs ``benchmarks/freefem/phasefield.edp``, the paper's eq. 7 written for it (mode III,
P2 for u and z, z = min(1, max(zt, z_old)) at the P2 dofs, ``adaptmesh`` on z every step with
hmin and a vertex cap; the crack segment an internal edge of FreeFEM's meshes, as it is of
ngfrac's, unless ``--freefem-no-slit-edge``). Every parameter comes from the ngfrac scene (``ngfrac.load_scene`` with
``--set`` overrides) and is passed on FreeFEM's command line: epsilon, alpha1, alpha2,
residual_stiffness, mu, gamma, dt, t_end, hmin, hmax (ngfrac's resolved one), the cap, the
rectangle and the crack segment, the load slopes on top and bottom.

For each cap, in one process tree and in turn, FreeFEM (a child process; CPU time from
``resource.getrusage(RUSAGE_CHILDREN)``) and ngfrac (``PhaseFieldStepper`` in this process,
one NGSolve thread; CPU from ``getrusage(RUSAGE_SELF)``) run the scene; wall time of each
too. Both write a diagnosed record every step (energies, crack length, tip). A fine ngfrac
run (``--ref-cap`` vertices, hmin/2) is the reference, cached in ``DIR/reference.npz`` and
computed again only when its scene or settings change (or with ``--fresh-reference``).

Definitions (printed with the table):

- crack length: the Gamma-length 1/2 int (eps |grad z|^2 + z^2/eps) (ngfrac's crack_length,
  AT2); error e(t) = |L(t) - L_ref(t)| / L_ref(t) at the reference's output times, the run
  interpolated linearly in t;
- tip: for both tools the same simple definition, the largest x of a z-node (P2 dof) with
  z >= 1/2 (ngfrac's own tip, the end of the crack set's ridge, is in its history but not
  used here, as FreeFEM has no such thing);
- phases, from the reference: before growth t < t_grow, t_grow the first time the
  reference's tip is more than epsilon beyond its initial position; during propagation
  t_grow <= t < t_sep, t_sep the first time the reference's tip is on the far edge;
  after separation t >= t_sep;
- tip times: when the tip passes the middle x0 + W/2 (linear between steps) and the first
  step with the tip on the far edge x0 + W;
- time to accuracy: per tool, the runs (CPU s, max crack-length error) are reduced to their
  Pareto front (sorted by CPU time, each run kept when its error is below that of every
  cheaper one); T(e) is where the front, piecewise linear in (log CPU, log error), first
  reaches error e; no extrapolation: "< cheapest" when even the cheapest run is more
  accurate (then T is at most its CPU time) and "not reached" when no run is. The ratio is
  T_ngfrac(e) / T_FreeFEM(e), at 3 % and 1 %.

Without FreeFEM (``FreeFem++`` not on PATH) it prints why and exits with status 0.
"""
from __future__ import annotations

import argparse
import csv
import math
import os
import resource
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
EDP = ROOT / "benchmarks" / "freefem" / "phasefield.edp"
SCENE = ROOT / "demos" / "mode3_slit.toml"
COLUMNS = ("t", "nv", "crack_length", "E_el", "E_surf", "tip_x")


@dataclass(frozen=True)
class Preset:
    overrides: list[str]
    caps: list[int]
    ref_cap: int


PRESETS = {
    # eps twice the demo's, dt 2e-3: 70 steps, the crack starts near t = 0.07 and cuts the
    # plate before t_end = 0.14; a minute or two per tool on one loaded core
    "quick": Preset(["phase_field.epsilon=0.04", "time.dt=2e-3", "time.t_end=0.14"], [500, 1000, 2000], 4000),
    # the demo file as it is (eps 0.02, dt 5e-4, 300 steps)
    "full": Preset([], [1350, 2600, 5000], 20000),
}


def cpu_seconds(who: int) -> float:
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


# -- the scene as FreeFEM arguments ---------------------------------------------------------
def _slope(expression, what: str) -> float:
    """a of a load a*t (refused otherwise: the FreeFEM script knows only linear loads)."""
    if expression.names - {"t"}:
        raise SystemExit(f"{what} = {expression.text}: the FreeFEM script takes loads a*t only")
    a = float(expression.evaluate_numpy({"t": 1.0}))
    for t in (0.0, 0.37):
        if not math.isclose(float(expression.evaluate_numpy({"t": t})), a * t, abs_tol=1e-12 * (1 + abs(a))):
            raise SystemExit(f"{what} = {expression.text}: the FreeFEM script takes loads a*t only")
    return a


def freefem_arguments(scene) -> list[str]:
    """The scene as the FreeFEM script's ``-name value`` pairs; refuses what it cannot do."""
    from ngfrac.mesh.adapter import AdaptivitySizes

    g, pf, m, d = scene.geometry, scene.phase_field, scene.material, scene.discretization
    problems = []
    if scene.model.kind != "mode3":
        problems.append(f"model.kind = {scene.model.kind!r} (mode3 only)")
    if g.kind != "rectangle":
        problems.append(f"geometry.kind = {g.kind!r} (rectangle only)")
    if len(scene.cracks) != 1 or len(scene.cracks[0].points) != 2:
        problems.append("cracks: one straight segment only")
    if pf.model != "AT2" or d.coupling != "paper" or d.order != 2 or d.order_z not in (0, 2):
        problems.append("AT2, coupling 'paper', P2 for u and z only")
    if not m.gamma.is_constant:
        problems.append("a constant gamma only")
    if scene.time.adaptive:
        problems.append("fixed time steps only")
    if not scene.adaptivity.enabled:
        problems.append("adaptive meshes only (adaptivity.enabled = true)")
    loads = {load.boundary: load.value for load in scene.loads}
    if set(loads) != {"top", "bottom"}:
        problems.append(f"loads on top and bottom only (got {sorted(loads)})")
    if problems:
        raise SystemExit("the FreeFEM script cannot run this scene: " + "; ".join(problems))
    (cx0, cy0), (cx1, cy1) = scene.cracks[0].points
    values = {
        "eps": pf.epsilon, "alpha1": pf.alpha1, "alpha2": pf.alpha2, "eta": pf.residual_stiffness,
        "mu": m.mu, "gamma": m.gamma.value(), "dt": scene.time.dt, "tend": scene.time.t_end,
        "hmin": scene.adaptivity.hmin, "hmax": AdaptivitySizes.of(scene).hmax,
        "cap": scene.adaptivity.max_vertices, "x0": g.origin[0], "y0": g.origin[1],
        "width": g.width, "height": g.height, "cx0": cx0, "cy0": cy0, "cx1": cx1, "cy1": cy1,
        "gtop": _slope(loads["top"], "loads top"), "gbot": _slope(loads["bottom"], "loads bottom"),
    }
    return [item for k, v in values.items() for item in (f"-{k}", repr(v) if isinstance(v, float) else str(v))]


def freefem_command() -> list[str] | None:
    exe = shutil.which("FreeFem++-nw") or shutil.which("FreeFem++")
    return None if exe is None else [exe, "-nw", "-v", "0"] if exe.endswith("FreeFem++") else [exe, "-v", "0"]


# -- the two tools ----------------------------------------------------------------------------
def run_freefem(command: list[str], scene, out_csv: Path, isotropic: bool = False,
                slit_edge: bool = True) -> tuple[dict[str, np.ndarray], float, float]:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    args = [*command, str(EDP), *freefem_arguments(scene), "-out", str(out_csv),
            "-iso", "1" if isotropic else "0", "-slitedge", "1" if slit_edge else "0"]
    cpu0, wall0 = cpu_seconds(resource.RUSAGE_CHILDREN), time.perf_counter()
    done = subprocess.run(args, env=env, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - wall0, cpu_seconds(resource.RUSAGE_CHILDREN) - cpu0
    if done.returncode != 0:
        raise SystemExit(f"FreeFEM failed ({done.returncode}): {' '.join(args)}\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    with open(out_csv) as f:
        rows = list(csv.DictReader(f))
    data = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    data["tip_x"] = np.where(data["tip_x"] < -1e29, np.nan, data["tip_x"])
    return data, cpu, wall


def _xmax_tip(stepper) -> float:
    """The largest x of a z-node with z >= 1/2 (the FreeFEM script's tip)."""
    nodes = stepper.nodes
    z = nodes.values(stepper.fields.z)
    inside = z >= 0.5
    return float(np.max(np.asarray(nodes.points)[inside, 0])) if np.any(inside) else math.nan


def run_ngfrac(scene) -> tuple[dict[str, np.ndarray], float, float]:
    from ngfrac import PhaseFieldStepper

    cpu0, wall0 = cpu_seconds(resource.RUSAGE_SELF), time.perf_counter()
    stepper = PhaseFieldStepper(scene)
    rows = []

    def keep(record) -> None:
        rows.append((record.t, record.nv, record.crack_length, record.E_el, record.E_surf,
                     _xmax_tip(stepper), record.tip_x, record.tip_y))

    keep(stepper.record())
    for record in stepper.run(history_every=1):
        keep(record)
    wall, cpu = time.perf_counter() - wall0, cpu_seconds(resource.RUSAGE_SELF) - cpu0
    table = np.array(rows, dtype=float)
    data = dict(zip((*COLUMNS, "ridge_tip_x", "ridge_tip_y"), table.T))
    return data, cpu, wall


def reference(scene_path: Path, overrides: list[str], out: Path, fresh: bool) -> dict[str, np.ndarray]:
    from ngfrac import load_scene

    key = f"{scene_path.resolve()}|" + "|".join(overrides)
    path = out / "reference.npz"
    if path.exists() and not fresh:
        stored = np.load(path, allow_pickle=False)
        if str(stored["key"]) == key:
            print(f"reference: cached in {path}")
            return {k: stored[k] for k in stored.files if k != "key"}
    print(f"reference: ngfrac {' '.join(overrides)} ...", flush=True)
    data, cpu, wall = run_ngfrac(load_scene(scene_path, overrides))
    print(f"reference: {cpu:.0f} s CPU, {wall:.0f} s wall, at most {int(np.max(data['nv']))} vertices")
    np.savez(path, key=np.array(key), cpu=np.array(cpu), wall=np.array(wall), **data)
    return {**data, "cpu": np.array(cpu), "wall": np.array(wall)}


# -- the comparison ---------------------------------------------------------------------------
def first_time(t: np.ndarray, x: np.ndarray, level: float, interpolate: bool) -> float:
    """The first time x(t) >= level (linear between the steps, or the step itself)."""
    above = np.flatnonzero(np.nan_to_num(x, nan=-np.inf) >= level)
    if not len(above):
        return math.nan
    i = above[0]
    if not interpolate or i == 0 or not np.isfinite(x[i - 1]):
        return float(t[i])
    return float(t[i - 1] + (level - x[i - 1]) / (x[i] - x[i - 1]) * (t[i] - t[i - 1]))


@dataclass(frozen=True)
class Phases:
    t_grow: float
    t_sep: float


def phases(ref: dict[str, np.ndarray], eps: float, x_far: float, tol: float) -> Phases:
    """The phase boundaries (inf when the reference never gets there)."""
    tip0 = ref["tip_x"][0]
    grow = first_time(ref["t"], ref["tip_x"], tip0 + eps, False)
    sep = first_time(ref["t"], ref["tip_x"], x_far - tol, False)
    return Phases(grow if np.isfinite(grow) else math.inf, sep if np.isfinite(sep) else math.inf)


def length_errors(run: dict[str, np.ndarray], ref: dict[str, np.ndarray], ph: Phases) -> dict[str, float]:
    t = ref["t"]
    err = np.abs(np.interp(t, run["t"], run["crack_length"]) - ref["crack_length"]) / ref["crack_length"]
    inside = t <= run["t"][-1] + 1e-12
    parts = {"max": inside, "before": inside & (t < ph.t_grow),
             "during": inside & (t >= ph.t_grow) & (t < ph.t_sep), "after": inside & (t >= ph.t_sep)}
    out = {f"{k}_max": float(np.max(err[m])) if np.any(m) else math.nan for k, m in parts.items()}
    out["mean"] = float(np.mean(err[inside]))
    return out


def time_to_accuracy(points: list[tuple[float, float]], target: float) -> tuple[float, str]:
    """T(target) on the Pareto front of (time, error) points; (value, note)."""
    front: list[tuple[float, float]] = []
    for cost, error in sorted(points):
        if np.isfinite(error) and (not front or error < front[-1][1]):
            front.append((cost, error))
    if not front:
        return math.nan, "not reached"
    if front[0][1] <= target:
        return front[0][0], "<"
    for (c0, e0), (c1, e1) in zip(front, front[1:]):
        if e1 <= target:
            s = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(c0) + s * (math.log(c1) - math.log(c0))), ""
    return math.nan, "not reached"


def monotonicity(rows: list[dict]) -> list[str]:
    """One line per tool: is each phase's largest error non-increasing as the cap grows?"""
    lines = []
    for tool in ("ngfrac", "FreeFEM"):
        mine = sorted((r for r in rows if r["tool"] == tool), key=lambda r: r["cap"])
        if len(mine) < 2:
            continue
        parts = []
        for key, name in (("max_max", "overall"), ("during_max", "propagation"), ("after_max", "after separation")):
            errors = [r[key] for r in mine]
            rises = [f"{a['cap']}->{b['cap']}" for a, b in zip(mine, mine[1:]) if b[key] > a[key]]
            parts.append(f"{name} {'monotone' if not rises else 'rises at ' + ', '.join(rises)} "
                         f"({' / '.join(_pct(e) for e in errors)})")
        lines.append(f"- {tool}, error over caps {', '.join(str(r['cap']) for r in mine)}: " + "; ".join(parts))
    return lines


def _pct(x: float) -> str:
    return "–" if not np.isfinite(x) else f"{100 * x:.2f} %"


def _t(x: float) -> str:
    return "–" if not np.isfinite(x) else f"{x:.4f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--preset", choices=sorted(PRESETS), default="full")
    parser.add_argument("--quick", action="store_const", const="quick", dest="preset",
                        help="the quick preset (epsilon 0.04, dt 2e-3, t_end 0.14, caps 500 1000 2000)")
    parser.add_argument("--scene", type=Path, default=SCENE)
    parser.add_argument("--caps", type=int, nargs="+", help="vertex caps (default: the preset's)")
    parser.add_argument("--ref-cap", type=int, help="vertex cap of the ngfrac reference")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--out", type=Path, help="folder for histories, the cached reference, the table")
    parser.add_argument("--fresh-reference", action="store_true")
    parser.add_argument("--tools", nargs="+", choices=("FreeFEM", "ngfrac"), default=["FreeFEM", "ngfrac"],
                        help="run only these (ngfrac alone: the monotonicity over caps, no FreeFEM needed)")
    parser.add_argument("--ngfrac-set", dest="ngfrac_overrides", action="append", default=[],
                        metavar="KEY=VALUE",
                        help="an override for the compared ngfrac runs only (not the reference, not "
                             "FreeFEM), e.g. adaptivity.size_field=equidistributed")
    parser.add_argument("--freefem-isotropic", action="store_true",
                        help="FreeFEM's adaptmesh with an isotropic metric (iso = true), as Netgen's "
                             "meshes are: how much of FreeFEM's accuracy per vertex is anisotropy")
    parser.add_argument("--freefem-no-slit-edge", action="store_true",
                        help="FreeFEM's meshes without the crack segment as an internal edge (before "
                             "session 25: z0's crack length then 0.9 %% low, docs/benchmarks.md 17)")
    args = parser.parse_args()

    command = freefem_command() if "FreeFEM" in args.tools else []
    if command is None:
        print("FreeFEM++ is not installed (no FreeFem++ on PATH; Debian: apt-get install freefem++): "
              "the side-by-side benchmark is skipped.")
        return

    import ngfrac
    from ngfrac import load_scene

    ngfrac.set_threads(1)
    preset = PRESETS[args.preset]
    caps = args.caps or preset.caps
    common = preset.overrides + args.overrides + ["adaptivity.enabled=true"]
    out = args.out or ROOT / "benchmarks" / "out" / f"freefem_{args.preset}"
    out.mkdir(parents=True, exist_ok=True)
    base = load_scene(args.scene, common)
    eps, g = base.phase_field.epsilon, base.geometry
    ref_cap = args.ref_cap or preset.ref_cap
    # the reference's size field named (the demo's scene sets "equidistributed"): "bands", as
    # for the tables of docs/benchmarks.md sections 7, 9 and 11
    ref = reference(args.scene, common + [f"adaptivity.max_vertices={ref_cap}",
                                          f"adaptivity.hmin={base.adaptivity.hmin / 2}",
                                          "adaptivity.size_field=bands"], out,
                    args.fresh_reference)
    x_far, x_mid, tol = g.origin[0] + g.width, g.origin[0] + g.width / 2, 1e-6 * g.width
    ph = phases(ref, eps, x_far, tol)
    slit_length = float(np.linalg.norm(np.diff(np.asarray(base.cracks[0].points, dtype=float), axis=0)))

    rows, notes = [], []
    for cap in caps:
        scene = load_scene(args.scene, common + [f"adaptivity.max_vertices={cap}"])
        for tool in [t for t in ("FreeFEM", "ngfrac") if t in args.tools]:
            print(f"{tool} cap {cap} ...", flush=True)
            if tool == "FreeFEM":
                data, cpu, wall = run_freefem(command, scene, out / f"freefem_cap{cap}.csv",
                                              args.freefem_isotropic, not args.freefem_no_slit_edge)
                notes.append(f"FreeFEM cap {cap}: z in [{np.min(data['zmin']):.3g}, {np.max(data['zmax']):.6g}], "
                             f"smallest z^k - z^(k-1) on a step's mesh {np.min(data['dzmin'][1:]):.3g}, "
                             f"at most {int(np.max(data['nv']))} vertices, {int(np.sum(data['tries'] > 1))} "
                             f"steps with a rejected mesh; crack length lost at mesh changes: "
                             f"{-np.sum(np.minimum(data['dL_transfer'], 0)):.4f} in all, at most "
                             f"{-np.min(data['dL_transfer']):.2e} in one step")
            else:
                data, cpu, wall = run_ngfrac(load_scene(args.scene, common + args.ngfrac_overrides
                                                        + [f"adaptivity.max_vertices={cap}"]))
                np.savetxt(out / f"ngfrac_cap{cap}.csv", np.column_stack([data[k] for k in data]),
                           delimiter=",", header=",".join(data), comments="")
            errors = length_errors(data, ref, ph)
            rows.append(dict(tool=tool, cap=cap, nv=float(np.mean(data["nv"])), cpu=cpu, wall=wall,
                             L0=float(data["crack_length"][0]), **errors,
                             t_mid=first_time(data["t"], data["tip_x"], x_mid, True),
                             t_far=first_time(data["t"], data["tip_x"], x_far - tol, False)))
            print(f"  {cpu:.1f} s CPU, {wall:.1f} s wall, max error {_pct(errors['max_max'])}", flush=True)

    lines = [f"Scene {args.scene.name} with {' '.join(common)}; reference: ngfrac, cap {ref_cap}, "
             f"hmin {base.adaptivity.hmin / 2:g} (at most {int(np.max(ref['nv']))} vertices). "
             f"Phases from the reference: growth from t = {_t(ph.t_grow)}, separation at t = {_t(ph.t_sep)}. "
             f"L(0): the crack length of z0 (for a slit from an edge exactly l + pi eps/4 = "
             f"{slit_length + math.pi * eps / 4:.4f})."
             + (" FreeFEM's metric isotropic (adaptmesh iso = true)." if args.freefem_isotropic else "")
             + (" FreeFEM's meshes without the slit as an edge." if args.freefem_no_slit_edge else "")
             + (f" ngfrac runs with {' '.join(args.ngfrac_overrides)}." if args.ngfrac_overrides else ""),
             "",
             "| tool | cap | mean nv | CPU s | wall s | L(0) | L err max | L err mean | before growth | "
             "propagation | after separation | t tip at x = mid | t tip at far edge |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    lines.append(f"| ngfrac reference | {ref_cap} | {np.mean(ref['nv']):.0f} | "
                 f"{float(ref['cpu']) if 'cpu' in ref else math.nan:.1f} | "
                 f"{float(ref['wall']) if 'wall' in ref else math.nan:.1f} | {ref['crack_length'][0]:.4f} | – | – | – | – | – | "
                 f"{_t(first_time(ref['t'], ref['tip_x'], x_mid, True))} | {_t(ph.t_sep)} |")
    for r in rows:
        lines.append(f"| {r['tool']} | {r['cap']} | {r['nv']:.0f} | {r['cpu']:.1f} | {r['wall']:.1f} | "
                     f"{r['L0']:.4f} | {_pct(r['max_max'])} | {_pct(r['mean'])} | {_pct(r['before_max'])} | "
                     f"{_pct(r['during_max'])} | {_pct(r['after_max'])} | {_t(r['t_mid'])} | {_t(r['t_far'])} |")
    lines.append("")
    for target in (0.03, 0.01) if "FreeFEM" in args.tools else ():
        parts = []
        for clock in ("cpu", "wall"):
            values = {}
            for tool in ("ngfrac", "FreeFEM"):
                values[tool] = time_to_accuracy([(r[clock], r["max_max"]) for r in rows if r["tool"] == tool], target)
            (tn, nn), (tf, nf) = values["ngfrac"], values["FreeFEM"]
            text = "–"
            if np.isfinite(tn) and np.isfinite(tf):
                # "<": T at most that time, so the ratio is a bound (or unknown if both are)
                bound = {("", ""): "", ("", "<"): ">= ", ("<", ""): "<= "}.get((nn, nf))
                if bound is not None:
                    text = f"{bound}{tn / tf:.2f}"

            def shown(value: float, note: str) -> str:
                return "not reached" if note == "not reached" else f"{note}{value:.1f} s"

            parts.append(f"{clock.upper() if clock == 'cpu' else clock}: ngfrac {shown(tn, nn)}, "
                         f"FreeFEM {shown(tf, nf)}, ratio ngfrac/FreeFEM {text}")
        lines.append(f"- time to {100 * target:g} % max crack-length error: " + "; ".join(parts))
    lines += ["", *[f"- {n}" for n in notes], *monotonicity(rows)]
    text = "\n".join(lines)
    (out / "table.md").write_text(text + "\n")
    print()
    print(text)


if __name__ == "__main__":
    sys.exit(main())
