"""The z-step's right-hand side and the surface energy come from the assembled matrices
(ngfrac.solve.z_system.AssembledSystem): they must equal the integrals they replace, for AT2 and AT1, with
constant and varying toughness, and with a crack pressure.

Both sides use the same quadrature rule, so they differ by round-off only: the tolerance,
1e-13 relative, is ~500 times the double-precision unit and well below what any test of the
physics resolves (1e-6 and coarser)."""
import ngsolve as ngs
import numpy as np
import pytest

from ngfrac import PhaseFieldStepper, Scene
from ngfrac.post.diagnostics import energies
from ngfrac.fem.threads import integrate

ROUND_OFF = 1e-13


def mode3_scene(crack_model="AT2", gamma=1.0):
    return Scene.from_dict({
        "model": {"kind": "mode3"},
        "material": {"mu": 1.0, "gamma": gamma},
        "phase_field": {"epsilon": 0.05, "alpha2": 1e-3, "model": crack_model},
        "geometry": {"width": 1.0, "height": 1.0, "mesh_size": 0.05},
        "cracks": [{"points": [[0.0, 0.5], [0.4, 0.5]]}],
        "loads": [{"boundary": "top", "value": "t"}, {"boundary": "bottom", "value": "-t"}],
        "time": {"dt": 0.05, "t_end": 0.6},
        "output": {"vtk_every": 0},
    })


def pressurized_scene():
    return Scene.from_dict({
        "model": {"kind": "plane_strain"},
        "material": {"lam": 1.0, "mu": 1.0, "gamma": 1.0},
        "phase_field": {"epsilon": 0.05, "alpha2": 1e-3, "crack_pressure": "1e-2*t"},
        "geometry": {"width": 2.0, "height": 2.0, "mesh_size": 0.08},
        "cracks": [{"points": [[0.7, 1.0], [1.3, 1.0]]}],
        "loads": [{"boundary": side, "value": ["0", "0"]}
                  for side in ("left", "right", "top", "bottom")],
        "time": {"dt": 0.1, "t_end": 0.3},
        "output": {"vtk_every": 0},
    })


def stepped(scene):
    stepper = PhaseFieldStepper(scene)
    for _ in stepper.run():
        pass
    return stepper


def linear_form_rhs(stepper):
    """The z-step's right-hand side as the linear form it replaces, for the current z_old
    and drive (what the forms held before the matrices took over)."""
    problem, f, pf = stepper.z_problem, stepper.fields, stepper.scene.phase_field
    _, w = f.fes_z.TnT()
    u_drive = f.u_prev if stepper.scene.discretization.coupling == "paper" else f.u
    integrand = (pf.alpha2 * stepper.context.inv_dt * f.z + stepper.u_problem.drive(u_drive)) * w
    source = stepper.crack_model.source(w, stepper.gamma, pf.epsilon)
    if source is not None:
        integrand = integrand + source
    if pf.pressurized:
        integrand = integrand - pf.crack_pressure.to_coefficient(stepper.context.time) \
            * ngs.InnerProduct(u_drive, ngs.grad(w))
    return ngs.LinearForm(integrand * f.dx).Assemble().vec.FV().NumPy().copy()


@pytest.mark.parametrize("scene", [mode3_scene(), mode3_scene("AT1"),
                                   mode3_scene(gamma="1 + 0.5*sin(10*x)"), pressurized_scene()],
                         ids=["AT2", "AT1", "varying-gamma", "pressure"])
def test_rhs_from_matrices_equals_the_linear_form(scene):
    stepper = stepped(scene)
    problem = stepper.z_problem
    problem.system.assemble()  # the next step's system, from the current z_old and drive
    ours, form = problem.rhs.FV().NumPy(), linear_form_rhs(stepper)
    assert np.abs(form).max() > 0
    np.testing.assert_allclose(ours, form, rtol=0, atol=ROUND_OFF * np.abs(form).max())


@pytest.mark.parametrize("scene", [mode3_scene(), mode3_scene("AT1"),
                                   mode3_scene(gamma="1 + 0.5*sin(10*x)"),
                                   mode3_scene("AT1", gamma="1 + 0.5*sin(10*x)")],
                         ids=["AT2", "AT1", "varying-gamma", "AT1-varying-gamma"])
def test_surface_energy_from_the_matrix_equals_its_integral(scene):
    stepper = stepped(scene)
    f, pf, model = stepper.fields, stepper.scene.phase_field, stepper.crack_model
    density = model.surface_density(f.z, pf.epsilon)
    e_surf, length = integrate(ngs.CoefficientFunction((stepper.gamma * density, density)),
                               f.mesh, order=f.integration_order)
    ours = stepper.z_problem.surface_energy()
    assert length > 0.4, "the crack set must be non-trivial"
    assert ours[0] == pytest.approx(e_surf, rel=ROUND_OFF)
    assert ours[1] == pytest.approx(length, rel=ROUND_OFF)
    # and the stepper's records use it: the record of the final state matches the integral
    whole = energies(f.mesh, f.z, stepper.u_problem.elastic_density(), stepper.gamma,
                     pf.epsilon, pf.residual_stiffness, order=f.integration_order,
                     crack_model=model)
    record = stepper.record()
    assert record.E_surf == pytest.approx(whole.E_surf, rel=ROUND_OFF)
    assert record.E_el == whole.E_el
