"""Demo: the Fig. 2 slit with the AT1 crack model: the damage stays inside a band of width 2 eps.

    python demos/mode3_slit_at1.py [OUT_DIR] [--set key=value ...]

Runs `mode3_slit_at1.toml` (read it first: every parameter is there) through the Python API and
writes VTK (ParaView: open OUT_DIR/vtk/fields.pvd), history.csv, results.h5, history.png and
crack.png. The run itself is three lines::

    scene = load_scene("demos/mode3_slit_at1.toml")
    run_scene(scene, "out/mode3_slit_at1", overwrite=True)
    # or step by step: for record in PhaseFieldStepper(scene).run(): ...
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Sequence

from _common import command_line, run_and_report

from ngfrac import PhaseFieldStepper, RunSummary

SCENE = Path(__file__).with_suffix(".toml")


def main(out_dir: str | Path = "out/mode3_slit_at1", overrides: Sequence[str] = (),
         on_step: Callable[[PhaseFieldStepper], None] | None = None) -> RunSummary:
    return run_and_report(SCENE, out_dir, overrides, on_step)


if __name__ == "__main__":
    command_line(main, "out/mode3_slit_at1")
