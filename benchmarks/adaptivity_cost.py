"""Per-step cost split of an adaptive run: estimate, size field, Netgen, transfer vs the solves.

    python benchmarks/adaptivity_cost.py [SCENE] [--set key=value ...]

Runs the scene (default: demos/mode3_slit.toml, adaptive, cap 5,000 vertices) without output
and prints, per step on average and as medians, the time in the two sub-steps (assembly and
linear solves) and in each phase of the mesh changes. Ratios within one run are what to
compare; absolute seconds depend on the machine and its load.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import ngfrac
from ngfrac import PhaseFieldStepper, load_scene

ROOT = Path(__file__).resolve().parents[1]


def main(argv: list[str]) -> None:
    ngfrac.set_threads()  # NGFRAC_THREADS (importing ngfrac sets nothing)
    scene_path = argv.pop(0) if argv and not argv[0].startswith("--") else ROOT / "demos/mode3_slit.toml"
    overrides = [value for flag, value in zip(argv[::2], argv[1::2]) if flag == "--set"]
    scene = load_scene(scene_path, ["output.history_every=1000000", *overrides])
    stepper = PhaseFieldStepper(scene)
    records = list(stepper.run())
    steps = len(records)
    step = np.array([r.step_s for r in records])
    solve = np.array([r.solve_s for r in records])
    adapt = np.array([r.adapt_s for r in records])
    phases = {name: sum(getattr(a, name) for a in stepper.adaptations)
              for name in ("estimate_s", "mark_s", "remesh_s", "transfer_s")}
    nv = np.array([r.nv for r in records])
    print(f"scene {scene.name}: {steps} steps, {len(stepper.adaptations)} mesh changes, "
          f"vertices median {int(np.median(nv))}, max {nv.max()} (cap {scene.adaptivity.max_vertices})")
    print(f"{'phase':<28}{'total s':>10}{'per step s':>12}{'share of step':>15}")
    total = step.sum()
    rows = [("two sub-steps (solves)", solve.sum())]
    rows += [(f"  adapt: {name[:-2]}", value) for name, value in phases.items()]
    rows += [("  adapt: checks and rest", adapt.sum() - sum(phases.values())),
             ("adaptation, all", adapt.sum()),
             ("bounds, diagnostics, rest", total - solve.sum() - adapt.sum()),
             ("step, all", total)]
    for name, value in rows:
        print(f"{name:<28}{value:>10.2f}{value / steps:>12.4f}{value / total:>15.1%}")
    print(f"median step {np.median(step):.4f} s, median solves {np.median(solve):.4f} s, "
          f"step / solves (means) {total / solve.sum():.2f}, adaptation / step {adapt.sum() / total:.1%}")
    drops = [1 - a.crack_length_after / a.crack_length_before for a in stepper.adaptations]
    if drops:
        print(f"largest crack-length drop in a transfer {max(drops):.4%}")


if __name__ == "__main__":
    main(sys.argv[1:])
