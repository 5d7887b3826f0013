"""u_solver = 'cg' (CG with BDDC) and 'reused_cholesky' (CG preconditioned with an earlier
factorization; ngfrac.fem.linear), and z_solver = 'reused_cholesky', against the sparse direct
solver."""
import functools
from types import SimpleNamespace

import ngsolve as ngs
import numpy as np
import pytest

from ngfrac.fem import linear
from ngfrac.fem.threads import single_thread

from ngfrac import PhaseFieldStepper, Scene
from ngfrac.scene import SceneError
from ngfrac.scene.sections import Discretization


def sent_like(u_solver, split="none", order=2, z_solver="sparsecholesky"):
    """A slit plate pulled apart: the band (z = 1 on the slit, eta = 1e-6) makes the u-matrix
    ill-conditioned, and the slit grows within the run."""
    return Scene.from_dict({
        "model": {"kind": "plane_strain"},
        "material": {"lam": 121.15, "mu": 80.77, "gamma": 2.7e-3, "split": split},
        "phase_field": {"epsilon": 0.04, "alpha2": 1e-7},
        "geometry": {"width": 1.0, "height": 1.0, "mesh_size": 0.03},
        "cracks": [{"points": [[0.0, 0.5], [0.5, 0.5]]}],
        "loads": [{"boundary": "bottom", "value": ["0", "0"]},
                  {"boundary": "top", "value": ["0", "t"]}],
        "time": {"dt": 5e-4, "t_end": 1e-2},
        "discretization": {"order": order, "u_solver": u_solver, "z_solver": z_solver},
        "output": {"vtk_every": 0},
    })


def history(scene):
    stepper = PhaseFieldStepper(scene)
    rows = np.array([(r.E_el, r.E_surf, r.forces["Fy_top"], r.tip_x) for r in stepper.run()])
    return rows, stepper


@functools.cache
def direct_history(split, order):
    return history(sent_like("sparsecholesky", split, order))[0]


@pytest.mark.parametrize("solver", ["cg", "reused_cholesky"])
@pytest.mark.parametrize("split", ["none", "amor"])
def test_iterative_solvers_match_the_direct_solver(split, solver):
    order = 2 if split == "none" else 1  # with a split, P1 keeps the Newton runs short
    direct = direct_history(split, order)
    iterative, stepper = history(sent_like(solver, split, order))
    assert direct[-1, 3] > 0.55, "the slit did not grow: the test needs a growing crack"
    # both stop CG at a relative residual of 1e-10: BDDC's histories agree to 1e-6, the
    # reused factor's to 1e-9 (measured: 6e-12 at most)
    rtol = 1e-9 if solver == "reused_cholesky" else 1e-6
    np.testing.assert_allclose(iterative[:, :3], direct[:, :3], rtol=rtol)
    inverse = stepper.u_problem.linear.inverse
    if solver == "reused_cholesky" and split == "none":
        # 20 steps on one mesh: the factor was reused, and renewed while the slit grew
        assert 1 < inverse.factorizations < 20
    elif split == "none":
        assert 0 < stepper.u_problem.iterations < 1000


def test_the_z_solve_with_a_reused_factor_matches_the_direct_one():
    direct = direct_history("none", 2)
    reused, stepper = history(sent_like("sparsecholesky", z_solver="reused_cholesky"))
    # CG to a relative residual of 1e-10 with a near-exact preconditioner, as for u above
    np.testing.assert_allclose(reused[:, :3], direct[:, :3], rtol=1e-9)
    np.testing.assert_allclose(reused[:, 3], direct[:, 3], rtol=0, atol=1e-12)  # the same tip
    inverse = stepper.z_problem.system._inverse.inverse  # the SystemInverse's operator
    assert isinstance(inverse, linear.ReusedCholesky) and inverse.factorizations < 20


def test_a_stale_factor_is_renewed_when_cg_stalls():
    """A matrix far from the factored one: CG stops at REUSE_MAXITER, the factor is renewed
    and the solve is direct (the same answer as a fresh factorization)."""
    mesh = ngs.Mesh(ngs.unit_square.GenerateMesh(maxh=0.1))
    fes = ngs.H1(mesh, order=2, dirichlet="left")
    u, v = fes.TnT()
    k = ngs.Parameter(1.0)
    coefficient = 1 + k * ngs.IfPos(ngs.x - 0.5, 1.0, 0.0)
    a = ngs.BilinearForm(ngs.grad(u) * ngs.grad(v) * coefficient * ngs.dx, symmetric=True)
    a.Assemble()
    # factorizations and solves with one thread, as the stepper makes them
    # (fem.threads.single_thread): with two, sparsecholesky's bits vary from run to run
    with single_thread():
        inverse = linear.ReusedCholesky(a.mat, fes.FreeDofs())
        rhs = a.mat.CreateColVector()
        rhs.FV().NumPy()[:] = 1.0
        result = a.mat.CreateColVector()
        result.data = inverse * rhs
        assert inverse.iterations <= 2 and inverse.factorizations == 1  # its own factor: exact
        k.Set(1e6)
        a.Assemble()
        inverse.update()  # the last solve was cheap: no refactorization yet
        assert inverse.factorizations == 1
        result.data = inverse * rhs
        assert inverse.factorizations == 2 and inverse.iterations == 0
        expected = rhs.CreateVector()
        expected.data = a.mat.Inverse(fes.FreeDofs(), inverse="sparsecholesky") * rhs
    np.testing.assert_array_equal(result.FV().NumPy(), expected.FV().NumPy())


def test_u_solver_is_validated():
    with pytest.raises(SceneError, match="u_solver"):
        sent_like("gmres")


def test_auto_reuses_a_factorization_on_large_3d_meshes_only():
    limit = linear.AUTO_REUSE_VERTICES
    assert linear.resolve_u_solver("auto", SimpleNamespace(dim=3, nv=limit)) == "reused_cholesky"
    assert linear.resolve_u_solver("auto", SimpleNamespace(dim=3, nv=limit - 1)) == "sparsecholesky"
    assert linear.resolve_u_solver("auto", SimpleNamespace(dim=2, nv=100 * limit)) == "sparsecholesky"
    for explicit in ("sparsecholesky", "umfpack", "cg", "reused_cholesky"):
        assert linear.resolve_u_solver(explicit, SimpleNamespace(dim=3, nv=limit)) == explicit
    assert sent_like("auto").discretization.u_solver == "auto"
    assert Discretization().u_solver == "auto"
