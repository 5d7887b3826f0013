"""The finite-element spaces and fields of one mesh: u, u_prev and z, and the quadrature."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import ngsolve as ngs

from ..scene import Scene
from .nodal import LagrangeNodes


@dataclass(eq=False)
class MeshFields:
    """The mesh, the spaces of u (the elastic model's) and z (H1 of ``z_order``), the
    GridFunctions u, u_prev, z and the quadrature every form and energy uses.

    A mesh change makes a new ``MeshFields``; the sub-problems are built on it.
    """

    mesh: ngs.Mesh
    fes_u: ngs.FESpace
    fes_z: ngs.FESpace
    u: ngs.GridFunction
    u_prev: ngs.GridFunction
    z: ngs.GridFunction
    nodes: LagrangeNodes
    """The Lagrange nodes of fes_z (vertices, then edge midpoints for P2)."""
    integration_order: int
    dx: Any
    """``dx`` with the quadrature of :attr:`integration_order` on every element."""

    @classmethod
    def on(cls, mesh: ngs.Mesh, scene: Scene, model: Any) -> "MeshFields":
        """Spaces and zero fields on ``mesh`` for ``scene`` and its elastic ``model``.

        On an occ domain with a curved boundary and order >= 2 the mesh is curved
        (:meth:`ngfrac.mesh.cad.OccDomain.curve`, also a mesh read from a checkpoint) first.

        One quadrature in every form and energy (:func:`quadrature_order`): the u-step then
        minimizes exactly the energy that the diagnostics report.
        """
        disc = scene.discretization
        curved = disc.order >= 2 and scene.geometry.kind == "occ" and scene.geometry.domain().curved
        if curved:  # curved boundaries (ngfrac.mesh.cad): isoparametric u
            scene.geometry.domain().curve(mesh, disc.order, [c.points for c in scene.cracks])
        fes_u = model.space(mesh, disc.order, scene.loads)
        fes_z = ngs.H1(mesh, order=disc.z_order)
        exact = scene.material.gamma.is_constant and scene.material.split == "none" and not curved
        order = quadrature_order(disc.order, disc.z_order, exact=exact)
        return cls(mesh, fes_u, fes_z, ngs.GridFunction(fes_u, "u"),
                   ngs.GridFunction(fes_u, "u_prev"), ngs.GridFunction(fes_z, "z"),
                   LagrangeNodes(fes_z), order, dx_of_order(mesh, order))

    @property
    def ndof(self) -> int:
        """Unknowns of u and z together."""
        return self.fes_u.ndof + self.fes_z.ndof

    def z_values(self) -> np.ndarray:
        """z at the Lagrange nodes."""
        return self.nodes.values(self.z)


def dx_of_order(mesh: ngs.Mesh, order: int) -> Any:
    """``dx`` with NGSolve's integration rule of ``order`` on every element of ``mesh``."""
    element = ngs.TET if mesh.dim == 3 else ngs.TRIG
    return ngs.dx(intrules={element: ngs.IntegrationRule(element, order)})


def quadrature_order(order_u: int, order_z: int, exact: bool = True) -> int:
    """The degree of the highest polynomial integrand of the forms and energies.

    On affine elements with constant toughness every integrand is a polynomial:
    (1 - z)^2 sigma[u]:e[v] and the drive W zt w have degree 2 order_z + 2 (order_u - 1),
    the mass terms 2 order_u and 2 order_z, the surface terms at most 2 order_z. P2/P2: 6.
    ``exact = False`` (a toughness that varies, a split's non-polynomial energy, curved
    elements) adds 2.
    """
    degree = max(2 * order_z + 2 * max(order_u - 1, 0), 2 * order_u, 2 * order_z)
    return degree if exact else degree + 2
