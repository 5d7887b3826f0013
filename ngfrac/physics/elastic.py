"""The elastic part of the models: spaces, sigma[u]:e[v], Dirichlet data, body force.

Each model gives the phase-field stepper what it needs about u; the fracture part (the
degradation, the surface energy) is the crack model's (:mod:`ngfrac.physics.crack_models`).
The interface:

- ``space(mesh, order, loads)``: the u-space, Dirichlet where (and in the components where)
  a load prescribes u;
- ``stress_strain(u, v)`` = sigma[u]:e[v] and ``energy_density(u)`` = sigma[u]:e[u];
- ``boundary_values(mesh, loads, t)``: one CoefficientFunction with the prescribed values, and
  ``set_boundary(gf, cf)`` to put them on the Dirichlet dofs of a GridFunction;
- ``body_force(material, t)``: f as a CoefficientFunction of u's shape, or None when f = 0;
- ``boundary_force(mesh, loads, t, v)``: the work of the tractions and pressures,
  ``sum int_Gamma t.v ds`` (a linear-form integrand), or None when there are none.

Only loads of ``kind = "displacement"`` make Dirichlet boundaries; tractions and pressures
act on the boundary undegraded (the crack is inside).
"""
from __future__ import annotations

from typing import Any, Protocol, Sequence

import ngsolve as ngs

from .loads import LOAD_KINDS


class LoadSpec(Protocol):
    """What a model reads of a load (a scene's ``[[loads]]`` entry, :class:`ngfrac.scene.Load`):
    ``value`` is an expression (``to_coefficient(t)``) or, for a vector, a tuple of them
    whose ``free`` flags the components left free."""

    boundary: str
    kind: str
    value: Any
    is_dirichlet: bool
    free: tuple[bool, ...]


class MaterialSpec(Protocol):
    """What a model reads of the material: its body force (an expression, or a tuple of them)."""

    body_force: Any


class ElasticModel(Protocol):
    """What the stepper uses of a model."""

    name: str
    n_components: int
    component_names: tuple[str, ...]

    def space(self, mesh: ngs.Mesh, order: int, loads: Sequence[LoadSpec]) -> ngs.FESpace: ...
    def stress_strain(self, u: Any, v: Any) -> Any: ...
    def energy_density(self, u: Any) -> Any: ...
    def boundary_values(self, mesh: ngs.Mesh, loads: Sequence[LoadSpec], t: ngs.Parameter) -> Any: ...
    def set_boundary(self, gf: ngs.GridFunction, cf: Any) -> None: ...
    def body_force(self, material: MaterialSpec, t: ngs.Parameter) -> Any | None: ...
    def boundary_force(self, mesh: ngs.Mesh, loads: Sequence[LoadSpec], t: ngs.Parameter,
                       v: Any) -> Any | None: ...


def _is_zero(expression: Any) -> bool:
    """An expression that is the constant 0 (``"free"`` and other strings are not)."""
    return bool(getattr(expression, "is_constant", False)) and expression.value() == 0


def dirichlet_loads(loads: Sequence[LoadSpec]) -> Sequence[LoadSpec]:
    """The loads that prescribe u (``kind = "displacement"``)."""
    return tuple(load for load in loads if load.is_dirichlet)


def traction_of(load: LoadSpec, mesh: ngs.Mesh, t: ngs.Parameter) -> Any:
    """The traction sigma n a Neumann load prescribes, as its kind gives it
    (:data:`ngfrac.physics.loads.LOAD_KINDS`: the value, or -p n for a pressure)."""
    return LOAD_KINDS[load.kind].traction(load.value, mesh, t)


def boundary_work(mesh: ngs.Mesh, loads: Sequence[LoadSpec], t: ngs.Parameter, v: Any) -> Any | None:
    """``sum over Neumann loads of int_Gamma traction . v ds``, or None without any."""
    def dot(traction: Any) -> Any:
        return traction * v if v.dim == 1 else ngs.InnerProduct(traction, v)

    terms = [dot(traction_of(load, mesh, t)) * ngs.ds(definedon=mesh.Boundaries(load.boundary))
             for load in loads if not load.is_dirichlet]
    return sum(terms[1:], terms[0]) if terms else None


class AntiPlane:
    """Mode III: a scalar out-of-plane displacement u, ``sigma:e = mu |grad u|^2``.

    Parameters
    ----------
    mu : float
        Shear modulus.
    """

    name = "mode3"
    n_components = 1
    component_names = ("z",)
    """u is the out-of-plane displacement, so its reaction is a force along z."""

    def __init__(self, mu: float) -> None:
        self.mu = mu

    @classmethod
    def of(cls, material: Any) -> "AntiPlane":
        """The model of a scene's material (its shear modulus)."""
        return cls(material.shear_modulus)

    def space(self, mesh: ngs.Mesh, order: int, loads: Sequence[LoadSpec]) -> ngs.FESpace:
        """The displacement space, Dirichlet on every loaded boundary."""
        return ngs.H1(mesh, order=order,
                      dirichlet="|".join(load.boundary for load in dirichlet_loads(loads)))

    def stress_strain(self, u: Any, v: Any) -> Any:
        """The bilinear integrand sigma[u]:e[v]."""
        return self.mu * ngs.grad(u) * ngs.grad(v)

    def energy_density(self, u: Any) -> Any:
        """sigma[u]:e[u] (twice the elastic energy density of the sound material)."""
        return self.mu * ngs.InnerProduct(ngs.grad(u), ngs.grad(u))

    def stress(self, u: Any) -> Any:
        """The shear stress vector (sigma_xz, sigma_yz) = mu grad u of the sound material."""
        return self.mu * ngs.grad(u)

    def boundary_values(self, mesh: ngs.Mesh, loads: Sequence[LoadSpec], t: ngs.Parameter) -> Any:
        """One CoefficientFunction with each load's expression on its boundary."""
        return mesh.BoundaryCF({load.boundary: load.value.to_coefficient(t)
                                for load in dirichlet_loads(loads)}, default=0)

    def set_boundary(self, gf: ngs.GridFunction, cf: Any) -> None:
        """Interpolate ``cf`` into the Dirichlet dofs of ``gf`` (its other dofs are unspecified)."""
        gf.Set(cf, ngs.BND)

    def body_force(self, material: MaterialSpec, t: ngs.Parameter) -> Any | None:
        """The out-of-plane force f, or None when it is zero."""
        force = material.body_force
        return None if _is_zero(force) else force.to_coefficient(t)

    def boundary_force(self, mesh: ngs.Mesh, loads: Sequence[LoadSpec], t: ngs.Parameter,
                       v: Any) -> Any | None:
        """``int_Gamma tau v ds`` of the traction loads (tau = sigma_zn), or None."""
        return boundary_work(mesh, loads, t, v)


class Elasticity:
    """Linear isotropic elasticity with a vector u, ``sigma = 2 mu e + lam tr(e) I``.

    Parameters
    ----------
    lam, mu : float
        The Lame constants that act in the model's dimension.
    dim : int
        Components of u (2 in the plane; 3 is for a 3D mesh).
    """

    name = "elasticity"
    COMPONENTS = ("x", "y", "z")
    bulk_dim = 3
    """The dimension of the strain whose trace and deviator a split takes: 3 (plane strain has
    e_zz = 0 in a 3D strain), 2 in plane stress."""

    def __init__(self, lam: float, mu: float, dim: int = 2) -> None:
        self.lam, self.mu, self.n_components = lam, mu, dim
        self.lam_3d = lam
        """The 3D Lame constant lam (plane stress: ``lam`` is the effective lam*)."""
        self.component_names = self.COMPONENTS[:dim]

    @classmethod
    def of(cls, material: Any) -> "Elasticity":
        """The model of a scene's material (its 3D Lame constants)."""
        return cls(*material.lame)

    @property
    def poisson_ratio(self) -> float:
        """nu of the 3D material, ``lam/(2 (lam + mu))``."""
        return self.lam_3d / (2 * (self.lam_3d + self.mu))

    @property
    def kolosov(self) -> float:
        """Kolosov's constant kappa: ``3 - 4 nu`` (plane strain, 3D), ``(3 - nu)/(1 + nu)``
        (plane stress); the LEFM modulus is ``E' = 8 mu / (kappa + 1)``."""
        nu = self.poisson_ratio
        return (3 - nu) / (1 + nu) if self.name == "plane_stress" else 3 - 4 * nu

    def out_of_plane_stress(self, stress: Any) -> Any:
        """sigma_zz of a plane model from its in-plane stress: ``nu (sxx + syy)`` in plane
        strain, 0 in plane stress."""
        if self.name == "plane_strain":
            return self.poisson_ratio * (stress[0, 0] + stress[1, 1])
        return 0.0

    def space(self, mesh: ngs.Mesh, order: int, loads: Sequence[LoadSpec]) -> ngs.FESpace:
        """VectorH1, Dirichlet in component i on the boundaries whose load gives that component."""
        flags = {f"dirichlet{c}": "|".join(load.boundary for load in dirichlet_loads(loads)
                                           if not load.free[i])
                 for i, c in enumerate(self.component_names)}
        return ngs.VectorH1(mesh, order=order, **flags)

    def strain(self, u: Any) -> Any:
        """e[u] = sym(grad u)."""
        return ngs.Sym(ngs.grad(u))

    def stress_strain(self, u: Any, v: Any) -> Any:
        """The bilinear integrand ``sigma[u]:e[v] = 2 mu e[u]:e[v] + lam tr e[u] tr e[v]``."""
        eu, ev = self.strain(u), self.strain(v)
        return 2 * self.mu * ngs.InnerProduct(eu, ev) + self.lam * ngs.Trace(eu) * ngs.Trace(ev)

    def energy_density(self, u: Any) -> Any:
        """sigma[u]:e[u] (twice the elastic energy density of the sound material)."""
        return self.stress_strain(u, u)

    def stress(self, u: Any) -> Any:
        """sigma[u] (of the sound material), a dim x dim CoefficientFunction."""
        e = self.strain(u)
        return 2 * self.mu * e + self.lam * ngs.Trace(e) * ngs.Id(self.n_components)

    def boundary_values(self, mesh: ngs.Mesh, loads: Sequence[LoadSpec], t: ngs.Parameter) -> Any:
        """One vector CoefficientFunction with each load's components on its boundary
        (0 in free components, which :meth:`set_boundary` never reads)."""
        def vector(value: Any) -> Any:
            return ngs.CoefficientFunction(tuple(
                0.0 if free else entry.to_coefficient(t) for entry, free in zip(value, value.free)))

        return mesh.BoundaryCF({load.boundary: vector(load.value) for load in dirichlet_loads(loads)},
                               default=ngs.CoefficientFunction((0.0,) * self.n_components))

    def set_boundary(self, gf: ngs.GridFunction, cf: Any) -> None:
        """Interpolate ``cf`` into the Dirichlet dofs of ``gf``, component by component.

        Each component space knows its own Dirichlet boundaries; ``Set(cf, BND)`` on the whole
        VectorH1 would not, and would average a free component's placeholder into a corner.
        """
        for i, component in enumerate(gf.components):
            component.Set(cf[i], ngs.BND)

    def body_force(self, material: MaterialSpec, t: ngs.Parameter) -> Any | None:
        """f = [fx, fy] (3D: [fx, fy, fz]) as a vector CoefficientFunction, or None when zero."""
        force = material.body_force
        if not isinstance(force, tuple):
            return None  # a scalar body force is only allowed when it is 0 (Model.check)
        if all(_is_zero(entry) for entry in force):
            return None
        return ngs.CoefficientFunction(tuple(entry.to_coefficient(t) for entry in force))

    def boundary_force(self, mesh: ngs.Mesh, loads: Sequence[LoadSpec], t: ngs.Parameter,
                       v: Any) -> Any | None:
        """``int_Gamma t.v ds`` of the traction and pressure loads (t = -p n), or None."""
        return boundary_work(mesh, loads, t, v)


class PlaneStrain(Elasticity):
    """Plane strain: the in-plane part of 3D elasticity with e_zz = 0 (3D Lame constants)."""

    name = "plane_strain"
    n_components = 2

    def __init__(self, lam: float, mu: float) -> None:
        super().__init__(lam, mu, dim=2)


class PlaneStress(Elasticity):
    """Plane stress (sigma_zz = 0): ``lam* = 2 lam mu / (lam + 2 mu)`` replaces lam.

    Parameters
    ----------
    lam, mu : float
        The 3D Lame constants; ``self.lam`` is the effective lam*.
    """

    name = "plane_stress"
    n_components = 2
    bulk_dim = 2

    def __init__(self, lam: float, mu: float) -> None:
        super().__init__(2 * lam * mu / (lam + 2 * mu), mu, dim=2)
        self.lam_3d = lam


class Elasticity3D(Elasticity):
    """3D elasticity on a box: u = (ux, uy, uz), ``sigma = 2 mu e + lam tr(e) I``.

    Loads give ``[ux, uy, uz]`` (each component may be ``"free"``) and reactions are
    reported as Fx, Fy, Fz.

    Parameters
    ----------
    lam, mu : float
        The Lame constants.
    """

    name = "elasticity_3d"
    n_components = 3

    def __init__(self, lam: float, mu: float) -> None:
        super().__init__(lam, mu, dim=3)


ELASTIC_MODELS: dict[str, type[AntiPlane] | type[Elasticity]] = {
    "mode3": AntiPlane, "plane_strain": PlaneStrain, "plane_stress": PlaneStress,
    "elasticity_3d": Elasticity3D}
"""The values of ``model.kind``: each class builds itself from a scene's material (``of``) and
says how many components u has (3: a 3D model, on a 3D domain)."""
