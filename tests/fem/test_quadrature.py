"""The forms' quadrature (ngfrac.mesh.fields.quadrature_order) integrates every form exactly
on affine elements with constant toughness: assembling with it or with a rule four orders
higher gives the same matrices and vectors to round-off."""
import numpy as np
import ngsolve as ngs
import pytest
from netgen.geom2d import unit_square

from ngfrac.fem.quadrature import dx_of_order, quadrature_order


@pytest.mark.parametrize("order_u, order_z", [(1, 1), (2, 2), (1, 2), (3, 2)])
def test_degree_is_exact(order_u, order_z):
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.25))
    fes_u, fes_z = ngs.H1(mesh, order=order_u), ngs.H1(mesh, order=order_z)
    rng = np.random.default_rng(1)
    z, u_old = ngs.GridFunction(fes_z), ngs.GridFunction(fes_u)
    z.vec.FV().NumPy()[:] = rng.random(fes_z.ndof)
    u_old.vec.FV().NumPy()[:] = rng.random(fes_u.ndof)
    order = quadrature_order(order_u, order_z)

    def assembled(q):
        dx = dx_of_order(mesh, q)
        u, v = fes_u.TnT()
        a_u = ngs.BilinearForm(((1 - z) ** 2 + 1e-6) * ngs.grad(u) * ngs.grad(v) * dx + u * v * dx)
        zt, w = fes_z.TnT()
        drive = ngs.grad(u_old) * ngs.grad(u_old)
        a_z = ngs.BilinearForm(drive * zt * w * dx + ngs.grad(zt) * ngs.grad(w) * dx + zt * w * dx)
        energy = ngs.Integrate(((1 - z) ** 2) * drive, mesh, order=q)
        return [a_u.Assemble().mat.AsVector().FV().NumPy().copy(),
                a_z.Assemble().mat.AsVector().FV().NumPy().copy(), np.array([energy])]

    for ours, fine in zip(assembled(order), assembled(order + 4)):
        np.testing.assert_allclose(ours, fine, rtol=1e-11, atol=1e-13 * np.abs(fine).max())


def test_inexact_integrands_get_two_more_orders():
    assert quadrature_order(2, 2) == 6
    assert quadrature_order(2, 2, exact=False) == 8
