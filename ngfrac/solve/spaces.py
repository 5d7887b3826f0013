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
        (``mesh.Curve(order)``) first.

        One quadrature, exact for constant toughness, in every form and energy
        (2 order_u + 2 order_z): the u-step then minimizes exactly the energy that the
        diagnostics report.
        """
        disc = scene.discretization
        if disc.order >= 2 and scene.geometry.kind == "occ" and scene.geometry.domain().curved:
            mesh.Curve(disc.order)  # curved boundaries (ngfrac.mesh.cad): isoparametric u
        fes_u = model.space(mesh, disc.order, scene.loads)
        fes_z = ngs.H1(mesh, order=disc.z_order)
        order = 2 * disc.order + 2 * disc.z_order
        element = ngs.TET if mesh.dim == 3 else ngs.TRIG
        dx = ngs.dx(intrules={element: ngs.IntegrationRule(element, order)})
        return cls(mesh, fes_u, fes_z, ngs.GridFunction(fes_u, "u"),
                   ngs.GridFunction(fes_u, "u_prev"), ngs.GridFunction(fes_z, "z"),
                   LagrangeNodes(fes_z), order, dx)

    @property
    def ndof(self) -> int:
        """Unknowns of u and z together."""
        return self.fes_u.ndof + self.fes_z.ndof

    def z_values(self) -> np.ndarray:
        """z at the Lagrange nodes."""
        return self.nodes.values(self.z)
