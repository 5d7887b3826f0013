"""Tension/compression splits (ngfrac.physics.splits): the tangent, Newton, and what a split changes."""
import numpy as np
import ngsolve as ngs
import pytest
from netgen.geom2d import unit_square

from ngfrac import PhaseFieldStepper, Scene
from ngfrac.scene import SceneError
from ngfrac.physics.splits import EnergySplit, principal_strains_3d

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
    a, b, hu, gradient = automatic_and_written_tangents(split, fes, u, z)
    assert np.abs(a - b).max() < 1e-12 * np.abs(a).max()
    assert np.abs(hu - gradient).max() < 1e-12 * np.abs(hu).max()


def automatic_and_written_tangents(split, fes, u, z):
    """NGSolve's second derivative of the energy (Variation) and split.tangent at u, dense,
    with H(u) u and the energy's gradient at u."""
    trial, test = fes.TnT()
    dx = ngs.dx(bonus_intorder=2)
    auto = ngs.BilinearForm(fes)
    auto += ngs.Variation(split.elastic_density(trial, (1 - z) ** 2 + 1e-3) * dx)
    auto.AssembleLinearization(u.vec)
    gradient = u.vec.CreateVector()
    auto.Apply(u.vec, gradient)
    hand = ngs.BilinearForm(fes)
    hand += split.tangent(u, trial, test, (1 - z) ** 2 + 1e-3) * dx
    hand.Assemble()
    hu = (hand.mat * u.vec).Evaluate().FV().NumPy()
    return auto.mat.ToDense().NumPy(), hand.mat.ToDense().NumPy(), hu, gradient.FV().NumPy()


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
    residuals = np.array(stepper.u_problem.newton.residuals)
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


def slab(split, n_steps=6):
    """A 1 x 1 x 0.1 slab with a through-the-depth slit from the left face to x = 0.5,
    compressed towards its centre on every face."""
    faces = ("left", "right", "bottom", "top", "back", "front")
    load = ["-0.3*t*(x - 0.5)", "-0.3*t*(y - 0.5)", "-0.3*t*(z - 0.05)"]
    return Scene.from_dict({
        "model": {"kind": "elasticity_3d"},
        "material": {"lam": 1.0, "mu": 1.0, "gamma": 0.01, "split": split},
        "phase_field": {"epsilon": 0.15, "alpha2": 1e-3},
        "geometry": {"kind": "box", "width": 1.0, "height": 1.0, "depth": 0.1, "mesh_size": 0.1},
        "cracks": [{"points": [[0, 0.5, 0], [0.5, 0.5, 0], [0.5, 0.5, 0.1], [0, 0.5, 0.1]]}],
        "loads": [{"boundary": f, "value": load} for f in faces],
        "time": {"dt": 1.0 / n_steps, "t_end": 1.0},
        "discretization": {"order": 1},
        "output": {"vtk_every": 0},
    })


@pytest.mark.parametrize("split", SPLITS)
def test_splits_in_3d_agree_under_triaxial_stretch(split):
    """Every principal strain is positive (Miehe: all three about equal), psi+ = psi."""
    runs = {s: np.array([(r.E_el, r.E_surf) for r in PhaseFieldStepper(box(s)).run()])
            for s in ("none", split)}
    assert runs["none"][-1, 1] > 0
    np.testing.assert_allclose(runs[split], runs["none"], rtol=1e-9)


def test_compressed_3d_slit_cracks_only_without_a_split():
    """The 2D test above in a slab: compressed on every face, the slit runs through the
    slab without a split; with the spectral split psi+ = 0 and z does not change at all."""
    records = {s: list(PhaseFieldStepper(slab(s)).run()) for s in ("none", "miehe")}
    assert max(r.tip_x for r in records["none"]) > 0.6
    assert max(r.tip_x for r in records["miehe"]) == pytest.approx(0.5, abs=1e-9)
    miehe = records["miehe"]
    assert miehe[-1].crack_length == pytest.approx(miehe[0].crack_length, rel=1e-9)


# -- the 3D spectral split pointwise: principal strains, psi+ and the tangent -----------------
LAM, MU = 1.3, 0.7

DEGENERATE = {  # principal strains with a repeated value or a zero (the kink of <x>_+)
    "zero": (0.0, 0.0, 0.0),
    "equitriaxial": (1.0, 1.0, 1.0),
    "all_compression": (-1.0, -1.0, -1.0),
    "uniaxial": (1.0, 0.0, 0.0),
    "uniaxial_contracting": (1.0, -0.3, -0.3),
    "equibiaxial": (1.0, 1.0, 0.0),
    "equibiaxial_compressed": (1.0, 1.0, -0.5),
    "pure_shear": (1.0, 0.0, -1.0),
}


@pytest.fixture(scope="module")
def cube():
    return ngs.Mesh(ngs.unit_cube.GenerateMesh(maxh=0.5))


def rotated(principal, rng):
    """A symmetric matrix with these eigenvalues and random eigenvectors."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q @ np.diag(principal) @ q.T


def linear_field(fes, a):
    """The GridFunction u = A x (exact in VectorH1): its strain is sym(A) everywhere."""
    u = ngs.GridFunction(fes)
    u.Set(ngs.CF(tuple(a[i, 0] * ngs.x + a[i, 1] * ngs.y + a[i, 2] * ngs.z for i in range(3))))
    return u


def reference_psi_plus(a):
    w = np.linalg.eigvalsh(a)
    return 0.5 * LAM * max(np.trace(a), 0.0) ** 2 + MU * np.sum(np.maximum(w, 0.0) ** 2)


def reference_gradient(a, damage):
    """d/de of ((1-z)^2 + eta) psi+ + psi-, with (1-z)^2 + eta = damage: psi+' = lam <tr e>_+
    I + 2 mu <e>_+ (the positive part of the matrix, from numpy's eigh); no second
    derivative is involved."""
    w, v = np.linalg.eigh(a)
    plus = LAM * max(np.trace(a), 0.0) * np.eye(3) + 2 * MU * (v * np.maximum(w, 0.0)) @ v.T
    full = LAM * np.trace(a) * np.eye(3) + 2 * MU * a
    return damage * plus + full - plus


def random_smooth_field(rng):
    """A smooth displacement whose strain has 0, 1, 2 and 3 positive principal values."""
    x = (ngs.x, ngs.y, ngs.z)
    return ngs.CF(tuple(
        sum(0.5 * c * ngs.sin(sum(k * xi for k, xi in zip(w, x)) + phase)
            for c, w, phase in zip(rng.normal(size=3), rng.normal(size=(3, 3)) * 4,
                                   rng.uniform(0, 2 * np.pi, 3)))
        for _ in range(3)))


@pytest.mark.parametrize("state", ["random_0", "random_2", "random_3",
                                   "zero", "equitriaxial", "all_compression"])
def test_3d_tangent_is_the_second_derivative(state, cube):
    """3D Miehe: the hand-written tangent equals NGSolve's automatic second derivative
    (Variation) and H(u) u equals the gradient, for random smooth u (every sign pattern of
    the principal strains occurs, checked) and for the constant strains 0, sI and -sI
    (p = 0: all three equal). Where exactly two principal strains are equal Variation is NaN
    (the derivative of acos at 1), and at a rotated zero principal strain the two evaluations
    may land on different sides of the kink by round-off: those states are checked by
    test_3d_tangent_at_repeated_and_zero_principal_strains."""
    rng = np.random.default_rng(int(state[-1]) if state.startswith("random")
                                else sum(map(ord, state)))
    fes = ngs.VectorH1(cube, order=2)
    z = ngs.GridFunction(ngs.H1(cube, order=1))
    z.Set(0.5 * ngs.x)
    if state.startswith("random"):
        u = ngs.GridFunction(fes)
        u.Set(random_smooth_field(rng))
        points = rng.uniform(0.0, 1.0, size=(3, 2000))
        strains = ngs.CF(principal_strains_3d(ngs.Sym(ngs.grad(u))))(cube(*points))
        counts = np.bincount((np.asarray(strains) > 0).sum(axis=1), minlength=4)
        assert np.all(counts > 0), f"positive principal strains 0, 1, 2, 3: {counts}"
    else:
        u = linear_field(fes, 0.3 * rotated(DEGENERATE[state], rng))
    split = EnergySplit("miehe", LAM, MU, dim=3, bulk_dim=3)
    a, b, hu, gradient = automatic_and_written_tangents(split, fes, u, z)
    assert np.all(np.isfinite(a))
    assert np.abs(a - b).max() < 1e-12 * np.abs(a).max()
    if np.abs(hu).max() > 0:
        assert np.abs(hu - gradient).max() < 1e-12 * np.abs(hu).max()


@pytest.mark.parametrize("state", DEGENERATE)
def test_3d_tangent_at_repeated_and_zero_principal_strains(state, cube):
    """At the constant strain e = R diag(state) R^T (random rotation R) the tangent, evaluated
    with constant strains h, k, equals the derivative of the gradient (numpy eigh, no second
    derivative) in the direction h, by finite differences with Richardson extrapolation.

    Where no principal strain (and not tr e) is 0 the energy is smooth: h is any symmetric
    matrix and the differences central. A zero is a kink of <x>_+ (the energy is C^1 only):
    the tangent is the second derivative from one side, the one where the computed principal
    strain (or trace) lies; round-off of ~1e-17 decides which, and either is a valid Newton
    matrix. There h moves the zero principal strains (and the trace) into that side, and
    the differences are one-sided, from e."""
    rng = np.random.default_rng(sum(map(ord, state)))
    fes = ngs.VectorH1(cube, order=1)
    split = EnergySplit("miehe", LAM, MU, dim=3, bulk_dim=3)
    z, eta = 0.3, 1e-3
    damage = (1 - z) ** 2 + eta
    a = rotated(DEGENERATE[state], rng)
    u = linear_field(fes, a)
    point = cube(0.3, 0.4, 0.5)
    e = ngs.Sym(ngs.grad(u))
    computed = np.asarray(ngs.CF(principal_strains_3d(e))(point)).ravel()[::-1]  # ascending
    w, v = np.linalg.eigh(a)
    zero = np.abs(w) < 1e-12
    trace_kink = abs(np.trace(a)) < 1e-12
    kink = bool(zero.any() or trace_kink)

    def direction():
        m = rng.normal(size=(3, 3))
        m = (m + m.T) / np.linalg.norm(m + m.T)
        if not kink:
            return m
        d = rng.uniform(-1.0, 1.0, 3)
        d[zero] = np.where(computed[zero] > 0, 1.0, -1.0)
        if trace_kink and not zero.all():
            d[~zero] = 2.0 if ngs.Trace(e)(point) > 0 else -2.0
        return v @ np.diag(d) @ v.T + 0.3 * m  # the zero strains move by d +- 0.3

    def derivative(h, t):
        if kink:  # one-sided, second order
            return (-3 * reference_gradient(a, damage) + 4 * reference_gradient(a + t * h, damage)
                    - reference_gradient(a + 2 * t * h, damage)) / (2 * t)
        return (reference_gradient(a + t * h, damage)
                - reference_gradient(a - t * h, damage)) / (2 * t)

    for _ in range(4):
        h, k = direction(), rng.normal(size=(3, 3))
        k = k + k.T
        value = split.tangent(u, linear_field(fes, h), linear_field(fes, k), (1 - ngs.CF(z)) ** 2 + eta)(point)
        t = 1e-4
        expected = np.sum((4 * derivative(h, t / 2) - derivative(h, t)) / 3 * k)
        scale = np.linalg.norm(h) * np.linalg.norm(k)
        assert abs(value - expected) < 1e-9 * scale, (value, expected, computed)


@pytest.mark.parametrize("state", ["random"] * 4 + list(DEGENERATE) + ["near_pair_at_zero"])
def test_3d_psi_plus_against_eigvalsh(state, cube):
    """Principal strains (closed form) and psi+, psi- of u = A x at points, against numpy's
    eigvalsh, for random symmetric A and the repeated / zero principal strains above (rotated,
    so that round-off splits the repeated pairs)."""
    rng = np.random.default_rng(sum(map(ord, state)) + len(state))
    if state == "random":
        a = rng.normal(size=(3, 3))
        a = a + a.T
    elif state == "near_pair_at_zero":  # snapped to a pair: psi+ is still right
        a = rotated((1.0, 1e-9, -1e-9), rng)
    else:
        a = rotated(DEGENERATE[state], rng) * rng.uniform(0.01, 10.0)
    u = linear_field(ngs.VectorH1(cube, order=1), a)
    e = ngs.Sym(ngs.grad(u))
    split = EnergySplit("miehe", LAM, MU, dim=3, bulk_dim=3)
    points = cube(*rng.uniform(0.0, 1.0, size=(3, 5)))
    psi = 0.5 * LAM * np.trace(a) ** 2 + MU * np.sum(a * a)
    plus = np.asarray(split.psi_plus(e)(points)).ravel()
    minus = np.asarray(split.psi_minus(e)(points)).ravel()
    np.testing.assert_allclose(plus, reference_psi_plus(a), rtol=0, atol=1e-14 * max(psi, 1e-300))
    np.testing.assert_allclose(plus + minus, psi, rtol=1e-14, atol=1e-300)
    if state != "near_pair_at_zero":
        strains = np.asarray(ngs.CF(principal_strains_3d(e))(points))
        expected = np.linalg.eigvalsh(a)[::-1]
        np.testing.assert_allclose(strains, np.broadcast_to(expected, strains.shape), rtol=0,
                                   atol=1e-14 * max(np.abs(a).max(), 1e-300))


def test_differentiating_integrators_give_the_same_3d_tangent_and_are_switched_back(cube):
    """The stepper creates the 3D Miehe u-form inside tangent_integrators (8x faster to
    assemble): the matrix must not change, and the global flag must be restored."""
    from ngfrac.physics.splits import tangent_integrators
    rng = np.random.default_rng(7)
    fes = ngs.VectorH1(cube, order=2)
    z = ngs.GridFunction(ngs.H1(cube, order=1))
    z.Set(0.5 * ngs.x)
    u = ngs.GridFunction(fes)
    u.Set(random_smooth_field(rng))
    split = EnergySplit("miehe", LAM, MU, dim=3, bulk_dim=3)
    trial, test = fes.TnT()
    matrices = []
    for fast in (False, True):
        form = ngs.BilinearForm(fes, symmetric=True)
        with tangent_integrators(split if fast else None):
            form += split.tangent(u, trial, test, (1 - z) ** 2 + 1e-3) * ngs.dx(bonus_intorder=2)
        assert ngs.ngsglobals.symbolic_integrator_uses_diff is False
        matrices.append(form.Assemble().mat.ToDense().NumPy())
    plain, fast = matrices
    assert np.abs(fast - plain).max() < 1e-12 * np.abs(plain).max()
