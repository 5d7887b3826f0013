"""The refinement around the tip against accuracy and run time, under several vertex caps.

    NGFRAC_THREADS=1 python benchmarks/tip_disc.py [--reference DIR/reference.h5]
        [--variant NAME ...] [CAP ...]

Runs the quick preset of :mod:`time_vs_error` (mode III slit, epsilon = 0.04, 140 steps)
adaptively at each cap with the default (tip disc at h_band within 4 epsilon, lane at h_crack
along the crack), without the lane, and with a disc at h_crack within 3 and 2 epsilon (no
lane), and prints wall time, the crack-length error (over the run, before and after the
reference's tip passes x = 0.95), path and energy errors against
the reference that ``time_vs_error.py --quick --out DIR`` cached (run that first), and the cost
split. The numbers in docs/adaptivity.md come from this loop.
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import h5py
import numpy as np

import ngfrac

HERE = Path(__file__).resolve().parent
VARIANTS = {
    "default": [],
    "no lane": ["adaptivity.tip_lane=false"],
    "h_crack, 3 eps": ["adaptivity.h_tip=0.004", "adaptivity.tip_margin=0.12", "adaptivity.tip_lane=false"],
    "h_crack, 2 eps": ["adaptivity.h_tip=0.004", "adaptivity.tip_margin=0.08", "adaptivity.tip_lane=false"],
}
"""Overrides per variant, for epsilon = 0.04 (h_crack = epsilon/10 = 0.004)."""


def _time_vs_error():
    spec = importlib.util.spec_from_file_location("time_vs_error", HERE / "time_vs_error.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["time_vs_error"] = module
    spec.loader.exec_module(module)
    return module


def main() -> None:
    ngfrac.set_threads()  # NGFRAC_THREADS (importing ngfrac sets nothing)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("caps", nargs="*", type=int, default=[2000, 3000, 4000, 6000])
    parser.add_argument("--reference", default="out/time_vs_error_quick/reference.h5")
    parser.add_argument("--variant", action="append", choices=list(VARIANTS),
                        help="run only these (repeatable; default: all)")
    args = parser.parse_args()
    if not Path(args.reference).is_file():
        sys.exit(f"tip_disc: no reference at {args.reference}: run "
                 "`python benchmarks/time_vs_error.py --quick` first or pass --reference")
    tve = _time_vs_error()
    preset = tve.presets()["quick"]
    with h5py.File(args.reference, "r") as f:
        group = f["reference"]
        ref = {c: group[c][()] for c in group.keys()}
    ref.setdefault("force", np.array([np.nan]))
    for cap in args.caps:
        for name in args.variant or VARIANTS:
            extra = VARIANTS[name]
            overrides = preset.common + tve._adaptive(cap, False) + extra
            data, wall = tve.history_of(preset.scene, overrides, None, tve.code_state())
            err, cost = tve.errors(data, ref, 1.0), tve.costs(data)
            before, after = errors_around_the_cut(data, ref)
            changes = int(np.count_nonzero(data["adapt_s"][1:] > 0.05 * np.median(data["step_s"][1:])))
            print(f"cap {cap:>5} {name:<16} wall {wall:6.1f} s  crack length {err['crack_length_err']:6.2%}"
                  f" (before the cut {before:6.2%}, after {after:6.2%})  path {err['path_err']:6.2%}"
                  f"  energy {err['energy_err']:6.2%}  max nv {cost['max_nv']:.0f}  changes {changes}"
                  f"  adaptation {cost['adapt_share']:.0%}", flush=True)


def errors_around_the_cut(run: dict, ref: dict, x_cut: float = 0.95) -> tuple[float, float]:
    """Largest relative crack-length error before and after the reference's tip passes
    ``x_cut`` (after the cut the vertex cap, not the tip refinement, limits the accuracy)."""
    t = ref["t"]
    error = np.abs(np.interp(t, run["t"], run["crack_length"]) - ref["crack_length"]) / ref["crack_length"]
    cut = t[np.argmax(ref["tip_x"] > x_cut)] if np.any(ref["tip_x"] > x_cut) else np.inf
    before, after = error[t < cut], error[t >= cut]
    return (float(before.max()) if len(before) else np.nan, float(after.max()) if len(after) else np.nan)


if __name__ == "__main__":
    main()
