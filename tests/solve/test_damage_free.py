"""``phase_field.damage_free``: z = 0 on named boundaries, a Dirichlet condition of the z-solve.

What it must be: the sub-step's system solved on the free dofs with z = 0 on the others (not
a clamp after an unconstrained solve), z = 0 there at every step and after a mesh change, for
the direct solve, CG and AT1's obstacle problem; bad names get one line.
"""
import re

import numpy as np
import pytest
from ngfrac.testing.scenes import quick_slit

from ngfrac import PhaseFieldStepper
from ngfrac.mesh.adapter import transfer_fields
from ngfrac.mesh.fields import MeshFields
from ngfrac.scene import SceneError

SHORT = ("time.t_end=0.02", "time.dt=4e-3", 'phase_field.damage_free=["left"]')


def _left_nodes(fields):
    return np.isclose(fields.nodes.points[:, 0], 0.0)


@pytest.mark.parametrize("extra", [(), ("discretization.order=1",),
                                   ('discretization.z_solver="cg"',)],
                         ids=["P2-direct", "P1-direct", "P2-cg"])
def test_the_z_solve_is_the_dirichlet_problem(extra):
    stepper = PhaseFieldStepper(quick_slit(*SHORT, *extra))
    for _ in stepper.run():
        pass
    f = stepper.fields
    fixed = f.damage_free_dofs
    assert fixed.any() and np.all(f.z.vec.FV().NumPy()[fixed] == 0.0)
    assert np.all(f.z_values()[_left_nodes(f)] == 0.0)
    # the slit's mouth touches the left edge: without the condition z = 1 there (z0)
    assert f.z_values().max() == pytest.approx(1.0)
    problem = stepper.z_problem
    trial = problem.z_trial.vec
    residual = (problem.system.matrix * trial).Evaluate().FV().NumPy() - problem.rhs.FV().NumPy()
    scale = np.abs(problem.rhs.FV().NumPy()).max()
    # the equations of the free dofs hold (CG: its 1e-10 relative tolerance), not those of the
    # fixed ones, where z = 0 is imposed instead
    assert np.abs(residual[~fixed]).max() < 1e-8 * scale
    assert np.abs(residual[fixed]).max() > 1e-3 * scale
    assert np.all(trial.FV().NumPy()[fixed] == 0.0)


def test_at1_obstacle_holds_the_boundary_at_zero():
    stepper = PhaseFieldStepper(quick_slit(*SHORT, 'phase_field.model="AT1"'))
    assert stepper.z_problem.update == "obstacle"
    previous = None
    for _ in stepper.run():
        z = stepper.fields.z_values()
        assert np.all(z[_left_nodes(stepper.fields)] == 0.0)
        if previous is not None:
            assert np.all(z >= previous)
        previous = z


def test_a_mesh_change_keeps_the_boundary_at_zero():
    stepper = PhaseFieldStepper(quick_slit(*SHORT))
    old = stepper.fields
    old.nodes.assign(old.z, np.ones(old.nodes.n_nodes))  # z = 1 everywhere, the edge too
    mesh = stepper.domain.build_mesh(0.03, stepper.tracker.polylines)
    new = MeshFields.on(mesh, stepper.scene, stepper.model, stepper.crack_model)
    transfer_fields(old, new)
    z = new.z_values()
    assert np.all(z[_left_nodes(new)] == 0.0)
    assert np.abs(z[~_left_nodes(new)] - 1.0).max() < 1e-12


@pytest.mark.parametrize("value, message", [
    ('["lft"]', "'lft' is not a boundary of the geometry (did you mean 'left'?)"),
    ('"left"', "must be a list of names"),
    ('["left", "left"]', "names a boundary twice"),
])
def test_bad_damage_free_names_say_so_in_one_line(value, message):
    with pytest.raises(SceneError, match=re.escape(message)) as err:
        quick_slit(f"phase_field.damage_free={value}")
    assert "\n" not in str(err.value)
