"""The elastic part of the models: spaces, sigma[u]:e[v], Dirichlet data.

Each model gives the phase-field stepper what it needs about u; the fracture part (z, the
surface energy) is the same for all models and lives in the stepper.
"""
from __future__ import annotations

from typing import Any

import ngsolve as ngs

from .scene import Load, Scene


class AntiPlane:
    """Mode III: a scalar out-of-plane displacement u, ``sigma:e = mu |grad u|^2``.

    Parameters
    ----------
    mu : float
        Shear modulus.
    """

    name = "mode3"

    def __init__(self, mu: float) -> None:
        self.mu = mu

    def space(self, mesh: ngs.Mesh, order: int, dirichlet: str) -> ngs.FESpace:
        """The displacement space, Dirichlet on the boundaries in ``dirichlet`` ("a|b")."""
        return ngs.H1(mesh, order=order, dirichlet=dirichlet)

    def stress_strain(self, u: Any, v: Any) -> Any:
        """The bilinear integrand sigma[u]:e[v]."""
        return self.mu * ngs.grad(u) * ngs.grad(v)

    def energy_density(self, u: Any) -> Any:
        """sigma[u]:e[u] (twice the elastic energy density of the sound material)."""
        return self.mu * ngs.InnerProduct(ngs.grad(u), ngs.grad(u))

    def boundary_values(self, mesh: ngs.Mesh, loads: tuple[Load, ...], t: ngs.Parameter) -> Any:
        """One CoefficientFunction with each load's expression on its boundary."""
        return mesh.BoundaryCF({load.boundary: load.value.to_coefficient(t) for load in loads},
                               default=0)


def make_model(scene: Scene) -> AntiPlane:
    """The elastic model the scene asks for."""
    if scene.model.kind == "mode3":
        return AntiPlane(scene.material.mu)
    raise ValueError(f"model {scene.model.kind!r} is not implemented")  # scene validation prevents this
