"""Run every stability stress case (fast and slow) and print a markdown table.

    python benchmarks/stress_table.py [CASE ...] [--threads N]

The cases live in ngfrac/testing/stress_cases.py (the tests assert what this table reports).
Columns: steps; wall time (set-up, steps and checks; one NGSolve thread by default, so it
depends on the machine and its load); epsilon over the smallest element (longest edge of the
smallest element, over all steps); the largest violation of 0 <= z <= 1 at a node; the
largest decrease of z at a node on an unchanged mesh; the largest relative rise of E_total
between two steps with the load held on an unchanged mesh (and how many such steps there
were); the largest vertex count; the result (``ok`` or the failed checks).
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import ngsolve as ngs
import numpy as np
import ngfrac
from ngfrac.testing import stress_cases as sc

THREE_D = "three_d"
"""The 3D case of tests/stress/test_stress_3d.py (a unit cube pulled apart, P1)."""


def _patch(cls, name, function):
    original = getattr(cls, name)
    setattr(cls, name, function)
    return lambda: setattr(cls, name, original)


def _number(value: float) -> str:
    return "n/a" if value == float("-inf") else f"{value:.1e}"


def _verdict(found: list[str], energy: list[str], wrong_step: list[str] = ()) -> str:
    if found:
        return "FAILED: " + "; ".join(found)
    if energy:
        return "ok but the energy rises (known weakness, see docs/stress.md)"
    if wrong_step:
        return "ok but the message names the step before (known bug, see docs/stress.md)"
    return "ok"


def main(argv: list[str]) -> int:
    ngfrac.set_threads()  # NGFRAC_THREADS (importing ngfrac sets nothing)
    threads = 1
    if "--threads" in argv:
        i = argv.index("--threads")
        threads = int(argv[i + 1])
        del argv[i:i + 2]
    ngs.SetNumThreads(threads)
    extra = ("failure_u", "failure_z", THREE_D)
    unknown = [name for name in argv if name not in sc.CASE_BY_NAME and name not in extra]
    if unknown:
        print(f"unknown case(s) {', '.join(unknown)}; cases: {', '.join(sc.CASE_BY_NAME)}, "
              f"{', '.join(extra)}", file=sys.stderr)
        return 2
    names = argv or [*sc.CASE_BY_NAME, *extra]
    print("| case | what | steps | wall s | eps/hmin | z outside [0,1] | z decrease "
          "| energy rise (held steps) | max nv | result |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    failed = 0
    for name in names:
        if name.startswith("failure_"):
            sub_step = name[-1]
            with tempfile.TemporaryDirectory() as folder:
                result = sc.run_failure(sub_step, Path(folder) / "run", _patch)
            found = sc.failure_problems(result, sub_step)
            wrong_step = sc.failing_step_problems(result) if result.error is not None else []
            what = (f"NaN in the {sub_step}-solve at step {sc.FAIL_AT}, checkpoint every 2 "
                    f"(run_scene); error: {str(result.error).split(';')[-1].strip()!r}; "
                    f"checkpoint k = {result.checkpoint_step}, restart to k = {result.restarted_step}")
            print(f"| {name} | {what} | {sc.FAIL_AT} | {result.wall_s:.1f} | | | | | | "
                  f"{_verdict(found, [], wrong_step)} |", flush=True)
        else:
            case = sc.BOX_3D if name == THREE_D else sc.CASE_BY_NAME[name]
            result = sc.run_case(case)
            found = sc.problems(result)
            energy = sc.energy_problems(result) if case.energy_known else []
            description, slow = case.description, case.slow
            m = result.monitor
            ratio = result.scene.phase_field.epsilon / np.nanmin(result.series("hmin"))
            print(f"| {name}{' (slow)' if slow else ''} | {description} | {result.steps} "
                  f"| {result.wall_s:.1f} | {ratio:.2f} | {m.z_outside:.1e} | {m.z_decrease:.1e} "
                  f"| {_number(m.energy_rise)} ({m.held_steps}) | {m.max_nv} "
                  f"| {_verdict(found, energy)} |", flush=True)
        failed += bool(found)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
