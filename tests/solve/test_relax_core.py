"""After a mesh change the crack must stay as open as before (adaptivity.relax_core).

Interpolating z at new nodes that miss the ridge of a grown crack lowers z there by a few
percent; (1 - z)^2 then goes from ~1e-6 to ~1e-3 across the crack, which carries stress again:
in the SENT demo with adaptive steps the force of the first u-solve on a new mesh jumped by up
to 27 % before relax_core (one z-sub-step at the transferred u, kept where z >= 1/2 away from
the tip). Here: the quick SENT scene, run until its crack has grown to x > 0.6, then three
forced mesh changes at a fixed load; each time the u-solve on the new mesh must give the
force of the old one within 5 %.

The 5 % is the measured spread of these jumps, not one run's value: the meshes (and so the
jumps) change with the last bits of z (an ulp-level change of the z right-hand side's
summation order moved the first new mesh by 229 of 1,424 vertices), so six trajectories
were measured: ``force_jumps`` with QUICK_SENT as here and with one more override each of
time.dt=1.2e-4, time.dt=1.3e-4, adaptivity.max_vertices=1900, 2100 and 2200 (one thread,
ngsolve 6.2.2608). With relax_core 17 of the 18 jumps are within 1.5 %, the
largest is +3.79 % (the third change of the scene as here). Without relax_core the same
changes jump by up to 3.41 % on this quick scene, so the test guards against a return of the
27 % jumps, not the margin relax_core gives on this scene.
"""
import ngsolve as ngs
import numpy as np
import pytest

from ngfrac.post.reactions import reaction_columns
from ngfrac.solve.stepper import PhaseFieldStepper

from ngfrac.testing.scenes import benchmark_scene_data, scene_from

QUICK_SENT = ["phase_field.epsilon=0.03", "time.dt=1.25e-4", "time.t_end=8.5e-3", "output.vtk_every=0",
              "adaptivity.max_vertices=2000"]


def force_jumps(relax: bool) -> list[float]:
    scene = scene_from(benchmark_scene_data("sent_band"), *QUICK_SENT, f"adaptivity.relax_core={str(relax).lower()}")
    stepper = PhaseFieldStepper(scene)
    for record in stepper.run():
        if record.tip_x > 0.6:
            break
    else:
        pytest.fail("the quick SENT crack did not grow to x = 0.6")
    jumps = []
    with ngs.TaskManager():
        for _ in range(3):
            stepper.solve_u()
            before = reaction_columns(stepper.u_problem, stepper.scene.loads)["Fy_top"]
            stepper.adapt()
            stepper.solve_u()
            after = reaction_columns(stepper.u_problem, stepper.scene.loads)["Fy_top"]
            jumps.append(after / before - 1)
    return jumps


def test_a_mesh_change_keeps_the_force_of_a_grown_crack():
    jumps = force_jumps(relax=True)
    assert max(abs(j) for j in jumps) < 0.05, [f"{j:+.2%}" for j in jumps]
