"""The quadrature every form and energy of a run shares."""
from __future__ import annotations

from typing import Any

import ngsolve as ngs

__all__ = ["dx_of_order", "quadrature_order"]


def dx_of_order(mesh: ngs.Mesh, order: int) -> Any:
    """``dx`` with NGSolve's integration rule of ``order`` on every element of ``mesh``."""
    element = ngs.TET if mesh.dim == 3 else ngs.TRIG
    return ngs.dx(intrules={element: ngs.IntegrationRule(element, order)})


def quadrature_order(order_u: int, order_z: int, exact: bool = True) -> int:
    """The degree of the highest polynomial integrand of the forms and energies.

    On affine elements with constant toughness every integrand is a polynomial:
    (1 - z)^2 sigma[u]:e[v] and the drive W zt w have degree 2 order_z + 2 (order_u - 1),
    the mass terms 2 order_u and 2 order_z, the surface terms at most 2 order_z. P2/P2: 6.
    ``exact = False`` (a toughness that varies, a split's non-polynomial energy, a degradation
    other than (1 - z)^2, curved elements) adds 2.
    """
    degree = max(2 * order_z + 2 * max(order_u - 1, 0), 2 * order_u, 2 * order_z)
    return degree if exact else degree + 2
