"""The finite-element spaces and fields of one mesh: u, u_prev and z, and the quadrature."""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np
import ngsolve as ngs

from ..fem.nodal import LagrangeNodes
from ..fem.quadrature import dx_of_order, quadrature_order
from ..physics.crack_models import CrackModel
from ..scene import Scene


@dataclass(eq=False)
class MeshFields:
    """The mesh, the spaces of u (the elastic model's) and z (H1 of the order
    :meth:`~ngfrac.scene.sections.Discretization.z_order_for` gives), the
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
    def on(cls, mesh: ngs.Mesh, scene: Scene, model: Any, crack_model: CrackModel) -> "MeshFields":
        """Spaces and zero fields on ``mesh`` for ``scene``, its elastic ``model`` and its
        ``crack_model`` (a degradation other than (1 - z)^2 makes the integrands other polynomials).

        On an occ domain with a curved boundary and order >= 2 the mesh is curved
        (:meth:`ngfrac.geometry.cad.OccDomain.curve`, also a mesh read from a checkpoint) first.

        One quadrature in every form and energy (:func:`quadrature_order`): the u-step then
        minimizes exactly the energy that the diagnostics report.
        """
        disc = scene.discretization
        curved = disc.order >= 2 and scene.geometry.domain().curved
        if curved:  # curved boundaries (ngfrac.geometry.cad): isoparametric u
            scene.geometry.domain().curve(mesh, disc.order, [c.points for c in scene.cracks])
        fes_u = model.space(mesh, disc.order, scene.loads)
        z_order = disc.z_order_for(crack_model)
        damage_free = scene.phase_field.damage_free
        fes_z = (ngs.H1(mesh, order=z_order, dirichlet="|".join(damage_free)) if damage_free
                 else ngs.H1(mesh, order=z_order))
        exact = (scene.material.gamma.is_constant and scene.material.split == "none"
                 and not curved and crack_model.quadratic_degradation)
        order = quadrature_order(disc.order, z_order, exact=exact)
        return cls(mesh, fes_u, fes_z, ngs.GridFunction(fes_u, "u"),
                   ngs.GridFunction(fes_u, "u_prev"), ngs.GridFunction(fes_z, "z"),
                   LagrangeNodes(fes_z), order, dx_of_order(mesh, order))

    @property
    def ndof(self) -> int:
        """Unknowns of u and z together."""
        return self.fes_u.ndof + self.fes_z.ndof

    def clear_damage_free(self) -> None:
        """z = 0 at the nodes of the ``phase_field.damage_free`` boundaries, the other nodes'
        values kept (after z0 is set and after a mesh change's interpolation)."""
        fixed = self.damage_free_nodes
        if fixed.any():
            values = self.z_values()
            values[fixed] = 0.0
            self.nodes.assign(self.z, values)

    @functools.cached_property
    def damage_free_dofs(self) -> np.ndarray:
        """The dofs of fes_z held at z = 0 (bool; none without ``phase_field.damage_free``)."""
        return ~np.array(self.fes_z.FreeDofs(), dtype=bool)

    @functools.cached_property
    def damage_free_nodes(self) -> np.ndarray:
        """The Lagrange nodes held at z = 0 (bool): those a fixed dof's coefficient depends on
        (P1: the boundary's vertices; P2 also its edges' midpoints)."""
        fixed = np.zeros(self.nodes.n_nodes, dtype=bool)
        if self.damage_free_dofs.any():
            rows = self.nodes.coefficient_matrix().tocsr()[np.flatnonzero(self.damage_free_dofs)]
            fixed[np.unique(rows.indices[rows.data != 0])] = True
        return fixed

    def z_values(self) -> np.ndarray:
        """z at the Lagrange nodes."""
        return self.nodes.values(self.z)
