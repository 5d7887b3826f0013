"""The derived VTK fields (energy density, stress, estimator, h), read back with meshio and
checked against a uniform strain state, where stress and energy are known in closed form."""
import warnings

import meshio
import numpy as np
import pytest

from ngfrac.post.diagnostics import element_diameters
from ngfrac.io.output import LARGE_SNAPSHOT, VTKSeries
from ngfrac.runner import write_snapshot
from ngfrac.scene import Scene
from ngfrac.solve.stepper import PhaseFieldStepper

LAM, MU, ETA = 2.0, 1.5, 1e-6
# u = grad_u . x on every side: P2 holds it exactly, so the FE state is this uniform strain
GRAD_U = np.array([[0.01, 0.002], [0.003, -0.02]])
SIDES = ("bottom", "right", "top", "left")
# float64 round-off of P2 point values and a 2x2 stress (closed form below): 1e-12 relative
RTOL = 1e-9


def _uniform_scene(kind: str, split: str = "none") -> Scene:
    if kind == "mode3":
        value = f"{GRAD_U[0, 0]}*x + {GRAD_U[0, 1]}*y"
        material = {"mu": MU}
    else:
        value = [f"{GRAD_U[i, 0]}*x + {GRAD_U[i, 1]}*y" for i in range(2)]
        material = {"lam": LAM, "mu": MU, "split": split}
    return Scene.from_dict({
        "name": "uniform", "model": {"kind": kind}, "material": material,
        "phase_field": {"epsilon": 0.1, "alpha2": 1e-3, "residual_stiffness": ETA},
        "geometry": {"width": 1.0, "height": 1.0, "mesh_size": 0.25},
        "loads": [{"boundary": side, "value": value} for side in SIDES],
        "time": {"dt": 0.01, "t_end": 0.01}, "output": {"vtk_every": 0}})


def _snapshot(tmp_path, scene, subdivision=0):
    stepper = PhaseFieldStepper(scene)  # z = 0 (no crack), u the uniform state
    series = VTKSeries(tmp_path, subdivision)
    write_snapshot(series, stepper)
    return stepper, meshio.read(tmp_path / series.entries[-1][1])


def _closed_form(grad_u, lam, mu, split="none"):
    """Stress and energy density of the sound material (z = 0, g = 1 + eta)."""
    e = 0.5 * (grad_u + grad_u.T)
    g = 1 + ETA
    sigma = 2 * mu * e + lam * np.trace(e) * np.eye(2)
    if split == "amor":  # plane strain: K = lam + 2 mu/3, deviator of the 3x3 strain
        bulk, tr = lam + 2 * mu / 3, np.trace(e)
        dev = e - tr / 3 * np.eye(2)
        plus = 2 * mu * dev + bulk * max(tr, 0) * np.eye(2)
        minus = bulk * min(tr, 0) * np.eye(2)
        psi_plus = 0.5 * bulk * max(tr, 0) ** 2 + mu * (np.sum(e * e) - tr * tr / 3)
        psi_minus = 0.5 * bulk * min(tr, 0) ** 2
        return g * plus + minus, g * psi_plus + psi_minus
    return g * sigma, 0.5 * g * np.sum(sigma * e)


def test_mode3_shear_stress_and_energy(tmp_path):
    stepper, mesh = _snapshot(tmp_path, _uniform_scene("mode3"))
    data = mesh.point_data
    assert {"u", "z", "gamma", "energy_density", "stress", "estimator", "h"} <= set(data)
    n = len(mesh.points)
    assert data["stress"].shape == (n, 2)
    tau = (1 + ETA) * MU * GRAD_U[0]
    np.testing.assert_allclose(data["stress"], np.tile(tau, (n, 1)), rtol=RTOL, atol=1e-14)
    density = 0.5 * (1 + ETA) * MU * GRAD_U[0] @ GRAD_U[0]
    np.testing.assert_allclose(data["energy_density"].ravel(), density, rtol=RTOL)


@pytest.mark.parametrize("split", ["none", "amor"])
def test_plane_strain_stress_von_mises_principal(tmp_path, split):
    # tr e = -0.01 < 0: with Amor's split the volumetric part is compressive and not degraded,
    # which checks the symbolic derivative of the split's density
    stepper, mesh = _snapshot(tmp_path, _uniform_scene("plane_strain", split))
    data = mesh.point_data
    n = len(mesh.points)
    sigma, density = _closed_form(GRAD_U, LAM, MU, split)
    assert data["stress"].shape == (n, 3)
    expected = np.array([sigma[0, 0], sigma[1, 1], sigma[0, 1]])
    np.testing.assert_allclose(data["stress"], np.tile(expected, (n, 1)), rtol=RTOL, atol=1e-14)
    np.testing.assert_allclose(data["energy_density"].ravel(), density, rtol=RTOL)
    principal = np.sort(np.linalg.eigvalsh(sigma))[::-1]
    np.testing.assert_allclose(data["principal_stress"], np.tile(principal, (n, 1)), rtol=RTOL,
                               atol=1e-14)
    nu = LAM / (2 * (LAM + MU))
    full = np.zeros((3, 3))
    full[:2, :2] = sigma
    full[2, 2] = nu * np.trace(sigma)
    deviator = full - np.trace(full) / 3 * np.eye(3)
    np.testing.assert_allclose(data["von_mises"].ravel(), np.sqrt(1.5 * np.sum(deviator ** 2)),
                               rtol=RTOL)


def test_element_fields_are_one_value_per_element(tmp_path):
    stepper, mesh = _snapshot(tmp_path, _uniform_scene("mode3"))
    # subdivision 0: NGSolve writes each triangle's three corners on their own, in element order
    h = mesh.point_data["h"].reshape(stepper.mesh.ne, 3)
    np.testing.assert_array_equal(h, np.repeat(element_diameters(stepper.mesh)[:, None], 3, axis=1))
    estimator = mesh.point_data["estimator"].reshape(stepper.mesh.ne, 3)
    assert np.all(estimator == estimator[:, :1])
    assert np.all(np.isfinite(estimator)) and np.all(estimator >= 0)


def test_size_estimate_and_warning(tmp_path):
    scene = _uniform_scene("mode3")
    stepper = PhaseFieldStepper(scene)
    for subdivision in (0, 2):
        series = VTKSeries(tmp_path / str(subdivision), subdivision)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            write_snapshot(series, stepper)
        written = (series.folder / series.entries[-1][1]).stat().st_size
        estimate = series.estimate_bytes(stepper.mesh, 8)  # u z gamma W stress(2) estimator h
        # measured: the estimate is 3-10 % above the file (the XML header is not counted)
        assert 0.9 * written < estimate < 1.25 * written, (estimate, written)
    big = VTKSeries(tmp_path / "big", 5)
    assert big.estimate_bytes(stepper.mesh, 8) < LARGE_SNAPSHOT  # 32 triangles: still small
    big.subdivision = 12  # 4096 intervals per edge: ~3e11 bytes, warned before writing
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the warning raises, so nothing is written
        with pytest.raises(UserWarning, match="output.vtk_subdivision"):
            big.write(stepper.mesh, {"z": stepper.z}, 0.0)
    assert not big.entries


def _symmetric(eigenvalues, seed):
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.standard_normal((len(eigenvalues),) * 2))
    return q @ np.diag(eigenvalues) @ q.T


@pytest.mark.parametrize("kind", ["amor", "miehe"])
@pytest.mark.parametrize("eigenvalues", [(-0.01, -0.02), (0.01, -0.02), (0.03, 0.01),
                                         (-0.01, -0.02, -0.005), (0.01, -0.02, -0.005),
                                         (0.01, 0.02, -0.005), (0.01, 0.02, 0.005)])
def test_split_stresses_are_the_derivatives_of_the_split_densities(kind, eigenvalues):
    """sigma+- in closed form against NGSolve's symbolic derivative of psi+- (every count of
    positive principal strains, 2D and 3D)."""
    import ngsolve as ngs
    from netgen.csg import unit_cube
    from netgen.geom2d import unit_square

    from ngfrac.post.fields import split_stresses
    from ngfrac.physics.splits import EnergySplit

    dim = len(eigenvalues)
    strain = _symmetric(eigenvalues, seed=7)  # a rotation that mixes all entries
    geometry = unit_square if dim == 2 else unit_cube
    mesh = ngs.Mesh(geometry.GenerateMesh(maxh=1.0))
    e = ngs.CF(tuple(strain.ravel()), dims=(dim, dim))
    split = EnergySplit(kind, LAM, MU, dim, bulk_dim=3)
    point = mesh(*([0.3] * dim))
    for closed, density in zip(split_stresses(split, e), (split.psi_plus(e), split.psi_minus(e))):
        derivative = np.array(density.Diff(e)(point)).reshape(dim, dim)
        # the density may use e_xy and e_yx unevenly: its symmetric part is the stress
        np.testing.assert_allclose(np.array(closed(point)).reshape(dim, dim),
                                   0.5 * (derivative + derivative.T), rtol=1e-9, atol=1e-15)


def test_3d_stress_von_mises_principal(tmp_path):
    grad_u = np.array([[0.01, 0.002, 0.0], [0.003, -0.02, 0.001], [0.0, 0.004, 0.005]])
    faces = ("left", "right", "bottom", "top", "back", "front")
    scene = Scene.from_dict({
        "name": "uniform3d", "model": {"kind": "elasticity_3d"},
        "material": {"lam": LAM, "mu": MU},
        "phase_field": {"epsilon": 0.1, "alpha2": 1e-3, "residual_stiffness": ETA},
        "geometry": {"kind": "box", "width": 1.0, "height": 1.0, "depth": 0.5, "mesh_size": 0.5},
        "loads": [{"boundary": face, "value": [" + ".join(f"{grad_u[i, j]}*{x}" for j, x in
                                                         enumerate("xyz")) for i in range(3)]}
                  for face in faces],
        "time": {"dt": 0.01, "t_end": 0.01}, "output": {"vtk_every": 0},
        "discretization": {"order": 1}})
    _, mesh = _snapshot(tmp_path, scene)
    data, n = mesh.point_data, len(mesh.points)
    e = 0.5 * (grad_u + grad_u.T)
    sigma = (1 + ETA) * (2 * MU * e + LAM * np.trace(e) * np.eye(3))
    expected = [sigma[0, 0], sigma[1, 1], sigma[2, 2], sigma[0, 1], sigma[1, 2], sigma[0, 2]]
    np.testing.assert_allclose(data["stress"], np.tile(expected, (n, 1)), rtol=RTOL, atol=1e-14)
    np.testing.assert_allclose(data["principal_stress"],
                               np.tile(np.sort(np.linalg.eigvalsh(sigma))[::-1], (n, 1)),
                               rtol=1e-7)  # the trigonometric formula: ~1e-9 relative measured
    deviator = sigma - np.trace(sigma) / 3 * np.eye(3)
    np.testing.assert_allclose(data["von_mises"].ravel(), np.sqrt(1.5 * np.sum(deviator ** 2)),
                               rtol=RTOL)


def test_size_warning_once_per_series(tmp_path):
    stepper = PhaseFieldStepper(_uniform_scene("mode3"))
    series = VTKSeries(tmp_path, 0, large=1000)  # every snapshot is "large"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        write_snapshot(series, stepper)
        write_snapshot(series, stepper)
    sizes = [w for w in caught if "output.vtk_subdivision" in str(w.message)]
    assert len(sizes) == 1 and len(series.entries) == 2
