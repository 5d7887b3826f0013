"""The refinement around the tip against accuracy and run time, under several vertex caps.

    NGFRAC_THREADS=1 python benchmarks/tip_disc.py [--reference DIR/reference.h5]
        [--variant NAME ...] [CAP ...]

Runs the quick preset of :mod:`time_vs_error` (mode III slit, epsilon = 0.04, 140 steps)
adaptively at each cap with the default (tip disc at h_band within 4 epsilon, lane at h_crack
along the crack), without the lane, and with a disc at h_crack within 3 and 2 epsilon (no
lane), and prints wall time, the crack-length, path and energy errors against
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
            print(f"cap {cap:>5} {name:<24} wall {wall:7.1f} s  crack length {err['crack_length_err']:7.2%}"
                  f"  path {err['path_err']:6.2%}  energy {err['energy_err']:6.2%}  max nv "
                  f"{cost['max_nv']:.0f}  adaptation {cost['adapt_share']:.0%}", flush=True)


if __name__ == "__main__":
    main()
