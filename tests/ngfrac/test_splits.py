"""Tension/compression splits (ngfrac.splits): the tangent, Newton, and what a split changes."""
import numpy as np
import ngsolve as ngs
import pytest
from netgen.geom2d import unit_square

from ngfrac import PhaseFieldStepper, Scene
from ngfrac.scene import SceneError
from ngfrac.splits import EnergySplit

SPLITS = ["amor", "miehe"]


def scene(split, load, n_steps=12, crack=True, gamma="0.01", order=1, model="plane_strain"):
    data = {
        "model": {"kind": model},
        "material": {"lam": 1.0, "mu": 1.0, "gamma": gamma, "split": split},
        "phase_field": {"epsilon": 0.04, "alpha2": 1e-3},
        "geometry": {"width": 1.0, "height": 1.0, "mesh_size": 0.02},
        "loads": [{"boundary": b, "value": load} for b in ("bottom", "right", "top", "left")],
        "time": {"dt": 1.0 / n_steps, "t_end": 1.0},
        "discretization": {"order": order},
        "output": {"vtk_every": 0},
    }
    if crack:
        data["cracks"] = [{"points": [[0.0, 0.5], [0.5, 0.5]]}]
    return Scene.from_dict(data)


@pytest.mark.parametrize("kind", SPLITS)
def test_tangent_is_the_second_derivative(kind):
    """The hand-written tangent equals NGSolve's automatic second derivative of the energy,
    and H(u) u equals the gradient (the energy is homogeneous of degree 2)."""
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.1))
    fes = ngs.VectorH1(mesh, order=2)
    z = ngs.GridFunction(ngs.H1(mesh, order=1))
    z.Set(0.5 * ngs.x)
    u = ngs.GridFunction(fes)  # tension, compression and mixed principal strains
    u.Set(ngs.CF((ngs.sin(3 * ngs.x + ngs.y), ngs.cos(2 * ngs.y - ngs.x * ngs.y))))
    split = EnergySplit(kind, 1.3, 0.7, dim=2, bulk_dim=3)
    trial, test = fes.TnT()
    dx = ngs.dx(bonus_intorder=2)
    auto = ngs.BilinearForm(fes)
    auto += ngs.Variation(split.elastic_density(trial, z, 1e-3) * dx)
    auto.AssembleLinearization(u.vec)
    gradient = u.vec.CreateVector()
    auto.Apply(u.vec, gradient)
    hand = ngs.BilinearForm(fes)
    hand += split.tangent(u, trial, test, z, 1e-3) * dx
    hand.Assemble()
    a, b = auto.mat.ToDense().NumPy(), hand.mat.ToDense().NumPy()
    assert np.abs(a - b).max() < 1e-12 * np.abs(a).max()
    hu = (hand.mat * u.vec).Evaluate().FV().NumPy()
    assert np.abs(hu - gradient.FV().NumPy()).max() < 1e-12 * np.abs(hu).max()


def test_pure_tension_energies_agree():
    """Equibiaxial stretch: every principal strain is positive, psi+ = psi, so the split and
    the paper's model give the same run (non-uniform gamma: z and u are not uniform)."""
    runs = {}
    for split in ["none"] + SPLITS:
        stepper = PhaseFieldStepper(scene(split, ["0.2*t*x", "0.2*t*y"], n_steps=5, crack=False,
                                          gamma="1 + 0.5*x"))
        runs[split] = np.array([(r.E_el, r.E_surf, r.forces["Fx_right"]) for r in stepper.run()])
    assert runs["none"][-1, 1] > 1e-9  # z did grow
    for split in SPLITS:
        np.testing.assert_allclose(runs[split], runs["none"], rtol=1e-9)


def test_compressed_slit_cracks_only_without_a_split():
    """Equibiaxial compression of a slit plate: the paper's model lets the soft band close
    and the slit runs; with a split the band carries the compression and the slit stays put
    (spectral: psi+ = 0 in this state, nothing grows; Amor: the deviatoric part damages the
    plate diffusely, but the tip does not move)."""
    load = ["-0.3*t*(x - 0.5)", "-0.3*t*(y - 0.5)"]
    tips, lengths = {}, {}
    for split in ["none"] + SPLITS:
        records = list(PhaseFieldStepper(scene(split, load)).run())
        tips[split] = max(r.tip_x for r in records)
        lengths[split] = (records[0].crack_length, records[-1].crack_length)
    assert tips["none"] > 0.6, tips
    for split in SPLITS:
        assert tips[split] < 0.5 + 0.04, (split, tips, lengths)
    assert lengths["miehe"][1] == pytest.approx(lengths["miehe"][0], rel=1e-9), lengths


def test_newton_converges_quadratically():
    """A slit under tension and shear: the active sets (tension/compression, principal
    strains of mixed sign) change during the solve; once they settle the residual r_k
    falls quadratically: the order log(r_{k+1}/r_k) / log(r_k/r_{k-1}) of the last three
    residuals above round-off is about 2 (linear convergence gives 1)."""
    stepper = PhaseFieldStepper(scene("miehe", ["0.01*t*y", "0.01*t*y"], n_steps=1, order=2,
                                      gamma="1.0"))
    stepper.step()
    residuals = np.array(stepper.newton.residuals)
    table = ", ".join(f"{r:.2e}" for r in residuals)
    assert residuals[-1] <= 1e-10, table
    above = residuals[residuals > 1e-12]
    assert len(above) >= 4, f"too few steps to see an order: {table}"
    r0, r1, r2 = above[-3:]
    order = np.log(r2 / r1) / np.log(r1 / r0)
    assert order > 1.7, f"convergence order {order:.2f}: {table}"


def test_split_needs_a_vector_model():
    with pytest.raises(SceneError, match="split"):
        scene("amor", "t", model="mode3")
    with pytest.raises(SceneError, match="material.split"):
        scene("tresca", ["t", "t"])


def box(split, n_steps=3):
    faces = ("left", "right", "bottom", "top", "back", "front")
    return Scene.from_dict({
        "model": {"kind": "elasticity_3d"},
        "material": {"lam": 1.0, "mu": 1.0, "gamma": "1 + 0.5*x", "split": split},
        "phase_field": {"epsilon": 0.2, "alpha2": 1e-3},
        "geometry": {"kind": "box", "width": 1.0, "height": 1.0, "depth": 0.5, "mesh_size": 0.2},
        "loads": [{"boundary": f, "value": ["0.2*t*x", "0.2*t*y", "0.2*t*z"]} for f in faces],
        "time": {"dt": 1.0 / n_steps, "t_end": 1.0},
        "discretization": {"order": 1},
        "output": {"vtk_every": 0},
    })


def test_amor_in_3d_agrees_under_triaxial_stretch():
    runs = {split: np.array([(r.E_el, r.E_surf) for r in PhaseFieldStepper(box(split)).run()])
            for split in ("none", "amor")}
    assert runs["none"][-1, 1] > 0
    np.testing.assert_allclose(runs["amor"], runs["none"], rtol=1e-9)
    with pytest.raises(SceneError, match="miehe.*plane models"):
        box("miehe")
