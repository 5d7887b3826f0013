"""Demo: a round bar with a V-notch, read from a STEP file, pulled along its axis (3D).

    python demos/notched_cylinder.py [OUT_DIR] [--set key=value ...]

`notched_cylinder.toml` reads its part from ``notched_cylinder.step``; this script writes that
file with netgen.occ when it is missing (:func:`write_step_file`): a quarter of a bar of
radius R = 1 and length L = 4 with a circumferential V-notch of depth a = 0.25 and opening
w = 0.3 at mid-length. The faces x = 0 and y = 0 are symmetry planes, the bottom is held in
z and the top pulled up by t.

What to expect. While z is still small the bar is elastic: the reaction on the top is
K t with K between the stiffness of the notch's core, E pi (R - a)^2 / (4 L), and that of the
bar without a notch, E pi R^2 / (4 L), close to the 1D estimate with the notch's cross-section
(:func:`stiffness`). The stress concentrates at the notch root (r = R - a, z = L/2): the crack
nucleates there (``stepper.nucleus``) and runs across the section while the force falls.
Writes history.csv (Fz_top, uz_top), force_displacement.png, specimen.json, VTK,
history.png and crack.png, and prints the stiffness against its estimate and the nucleus.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ngfrac import PhaseFieldStepper, RunSummary

from _common import command_line, run_specimen, write_json

SCENE = Path(__file__).with_suffix(".toml")
STEP_FILE = SCENE.with_suffix(".step")
"""The part the scene reads (``geometry.file``), written by :func:`write_step_file`."""
RADIUS, LENGTH, DEPTH, OPENING = 1.0, 4.0, 0.25, 0.3
"""The bar's radius R and length L, the notch's depth a and its opening w at the surface."""


def notched_bar(radius: float = RADIUS, length: float = LENGTH, depth: float = DEPTH,
                opening: float = OPENING) -> Any:
    """The quarter (x, y >= 0) of a bar along z with a V-notch at mid-length (a netgen.occ solid)."""
    from netgen import occ

    bar = occ.Cylinder(occ.Pnt(0, 0, 0), occ.Z, r=radius, h=length)
    # the notch: a triangle in the xz-plane (local x = X, local y = Z), beyond the surface by
    # `out` along its flanks, revolved about the axis
    out = 0.1 * radius
    rise = 0.5 * opening * (1 + out / depth)
    middle = 0.5 * length
    plane = occ.WorkPlane(occ.Axes(occ.Pnt(0, 0, 0), n=-occ.Y, h=occ.X))
    profile = (plane.MoveTo(radius + out, middle + rise).LineTo(radius - depth, middle)
               .LineTo(radius + out, middle - rise).Close().Face())
    notch = profile.Revolve(occ.Axis(occ.Pnt(0, 0, 0), occ.Z), 360)
    quarter = occ.Box(occ.Pnt(0, 0, 0), occ.Pnt(2 * radius, 2 * radius, length))
    return (bar - notch) * quarter


def write_step_file(path: str | Path = STEP_FILE, overwrite: bool = False) -> Path:
    """Write the part (:func:`notched_bar`) as STEP to ``path`` unless it exists."""
    path = Path(path)
    if overwrite or not path.is_file():
        notched_bar().WriteStep(str(path))
    return path


def stiffness(E: float = 1.0) -> dict[str, float]:
    """The quarter bar's axial stiffness: the bounds (the notch's core alone, the bar without
    the notch) and the 1D estimate 1/K = int dz / (E A(z)) with the notch's cross-section."""
    r, a, w, length = RADIUS, DEPTH, OPENING, LENGTH
    core = E * math.pi * (r - a) ** 2 / (4 * length)
    plain = E * math.pi * r ** 2 / (4 * length)
    compliance = (length - w) / (E * math.pi * r ** 2 / 4) + 4 * w / (E * math.pi * r * (r - a))
    return {"lower": core, "upper": plain, "estimate": 1 / compliance}


def initial_stiffness(history: dict[str, np.ndarray]) -> float:
    """F/u on the top at the first loaded step (z has hardly moved from 0 there)."""
    first = int(np.flatnonzero(history["uz_top"] > 0)[0])
    return float(history["Fz_top"][first] / history["uz_top"][first])


def main(out_dir: str | Path = "out/notched_cylinder", overrides: Sequence[str] = (),
         on_step: Callable[[PhaseFieldStepper], None] | None = None) -> RunSummary:
    write_step_file()
    run = run_specimen(SCENE, out_dir, overrides, on_step, ("uz_top", "Fz_top"))
    run.plot(("F_z top", "u_z top"), unit="")
    scene, summary, stepper, history, out = (run.scene, run.summary, run.stepper, run.history,
                                             run.out)
    u, force, peak = run.u, run.force, run.peak
    k, bounds = initial_stiffness(history), stiffness(scene.material.E)
    nucleus = stepper.nucleus
    root = (float(np.hypot(nucleus[0], nucleus[1])), float(nucleus[2])) if nucleus is not None else None
    write_json(out / "specimen.json", {"stiffness": k, "stiffness_bounds": bounds,
                                       "nucleus": nucleus, "nucleus_r_z": root,
                                       "peak_force": float(force[peak]),
                                       "u_at_peak": float(u[peak]), "final_force": float(force[-1])})
    where = "none" if root is None else f"r = {root[0]:.3f}, z = {root[1]:.3f}"
    print(f"{scene.name}: stiffness {k:.4f} (1D estimate {bounds['estimate']:.4f}, bounds "
          f"{bounds['lower']:.4f}..{bounds['upper']:.4f}); the crack nucleated at {where} "
          f"(notch root r = {RADIUS - DEPTH}, z = {LENGTH / 2}); peak force {force[peak]:.4f} at "
          f"u = {u[peak]:.3g}; wall time {summary.last.wall_s:.1f} s; results in {out_dir}")
    return summary


if __name__ == "__main__":
    command_line(main, "out/notched_cylinder")
