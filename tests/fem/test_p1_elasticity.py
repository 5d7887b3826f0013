"""The degraded P1 stiffness by element weights equals NGSolve's assembly of the same form."""
import ngsolve as ngs
import numpy as np
import pytest
import scipy.sparse as sp
from netgen.geom2d import unit_square
from netgen.occ import Box, OCCGeometry, Pnt

from ngfrac.fem.p1_elasticity import P1ElasticStiffness, _upper_entries
from ngfrac.fem.quadrature import dx_of_order
from ngfrac.fem.threads import single_thread
from ngfrac.physics.elastic import Elasticity
from ngfrac.scene import Scene
from ngfrac.solve.stepper import PhaseFieldStepper

from tests.solve.test_3d import box_data

LAM, MU, ETA = 0.5769, 0.3846, 1e-6


def ngsolve_form(mesh, dirichlet):
    """The u-step's form for P1 u and z, with the exact quadrature of its degree-2 integrand
    (NGSolve's default rule for it is not exact)."""
    fes = ngs.VectorH1(mesh, order=1, **dirichlet)
    fes_z = ngs.H1(mesh, order=1)
    z = ngs.GridFunction(fes_z)
    u, v = fes.TnT()
    form = ngs.BilinearForm(fes, symmetric=True)
    model = Elasticity(LAM, MU, dim=mesh.dim)
    form += ((1 - z) ** 2 + ETA) * model.stress_strain(u, v) * dx_of_order(mesh, 2)
    return fes, fes_z, z, form


@pytest.mark.parametrize("dim", [2, 3])
def test_element_weights_give_ngsolve_s_matrix(dim):
    if dim == 3:
        mesh = ngs.Mesh(OCCGeometry(Box(Pnt(0, 0, 0), Pnt(1, 0.6, 0.4))).GenerateMesh(maxh=0.15))
        dirichlet = {"dirichletx": "left", "dirichlety": "bottom"}
    else:
        mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.08))
        dirichlet = {"dirichlety": "bottom"}
    fes, fes_z, z, form = ngsolve_form(mesh, dirichlet)
    assert P1ElasticStiffness.applies(fes, fes_z)
    with single_thread():
        z.Set(ngs.x * ngs.y)
        form.Assemble()
        weights = P1ElasticStiffness(form.mat, fes, LAM, MU, ETA)
        # a z with values in [0, 1] and steep in places (a crack band across the middle)
        z.Set(ngs.exp(-((ngs.y - 0.3) / 0.05) ** 2) * (0.5 + 0.5 * ngs.sin(7 * ngs.x)))
        form.Assemble()
        expected = np.array(form.mat.CSR()[0])
        assert weights.writes_into(form.mat)
        weights.assemble(z)
        got = np.asarray(form.mat.CSR()[0])
    # round-off of sums of ~20 (3D) element entries of size ~ max |A|
    scale = np.abs(expected).max()
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-13 * scale)


def test_applies_only_to_p1_spaces():
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.3))
    assert not P1ElasticStiffness.applies(ngs.VectorH1(mesh, order=2), ngs.H1(mesh, order=1))
    assert not P1ElasticStiffness.applies(ngs.VectorH1(mesh, order=1), ngs.H1(mesh, order=2))


def test_upper_entries_find_their_mirrors_and_refuse_an_unsymmetric_pattern():
    pattern = sp.random(30, 30, density=0.2, random_state=1, format="csr")
    pattern = (pattern + pattern.T + sp.identity(30)).tocsr()
    pattern.sort_indices()
    upper, mirror = _upper_entries(pattern.indices, pattern.indptr)
    rows = np.repeat(np.arange(30), np.diff(pattern.indptr))
    assert len(upper) == (pattern.nnz - 30) // 2
    assert np.array_equal(rows[upper], pattern.indices[mirror])
    assert np.array_equal(pattern.indices[upper], rows[mirror])
    with pytest.raises(ValueError, match="not symmetric"):
        _upper_entries(np.array([0, 1, 1]), np.array([0, 2, 3]))  # (0, 1) without (1, 0)


def box_history(monkeypatch, element_weights, steps=6):
    """Reactions and energies of tests/solve/test_3d.py's P1 box after each step: the edge
    crack runs through it (surface energy 0.21 -> 1.86, force down to 2 % of its peak)."""
    if not element_weights:
        monkeypatch.setattr(P1ElasticStiffness, "applies", staticmethod(lambda *a: False))
    scene = Scene.from_dict(box_data(loads__0=True, time__t_end=1.0))
    with single_thread():
        stepper = PhaseFieldStepper(scene)
        rows = []
        for _ in range(steps):
            record = stepper.step()
            rows.append([stepper.forces["Fy_top"], record.E_el, record.E_surf])
    used = stepper.u_problem._element_weights is not None
    return np.array(rows), used


def test_a_3d_p1_run_gives_the_same_history_with_element_weights(monkeypatch):
    fast, used = box_history(monkeypatch, True)
    assert used
    with monkeypatch.context() as patch:
        slow, used = box_history(patch, False)
    assert not used
    assert fast[-1, 2] > 2 * fast[0, 2]  # the crack grew: z (and so the matrix) changed
    # measured: 1.1e-15 (force), 2e-16 (energies) relative on one and on two threads; the
    # bound is round-off of the matrix (1e-16) times the u-solve's condition (eta = 1e-6)
    np.testing.assert_allclose(fast, slow, rtol=1e-10)
