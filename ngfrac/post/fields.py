"""Derived fields of a state, for the VTK snapshots: energy density, stress, estimator, h.

All of them are what the stepper itself uses, with the degradation g(z) = (1-z)^2 + eta
(eta = ``phase_field.residual_stiffness``) that the u-equation and the diagnostics carry:

- ``energy_density``: the integrand of E_el, ``1/2 g(z) sigma[u]:e[u]``; with a split
  ``g(z) psi+ + psi-`` (:mod:`ngfrac.physics.splits`);
- ``stress``: the degraded stress dW/de of that density (with a split g(z) sigma+ + sigma-).
  Mode III: the shear stress vector ``g(z) mu grad u`` = (sigma_xz, sigma_yz); plane models:
  (sigma_xx, sigma_yy, sigma_xy); 3D: (xx, yy, zz, xy, yz, xz), the order VTK reads as a
  symmetric tensor;
- ``von_mises`` and ``principal_stress`` (largest first; plane strain includes sigma_zz =
  nu (sigma_xx + sigma_yy), exact without a split, plane stress sigma_zz = 0); with the 3D
  spectral split all three come from the stress projected per element (:func:`projected`);
- ``estimator``: the scene's indicator on z (``adaptivity.estimator``) per element, and ``h``:
  the longest edge per element, both piecewise constant (L2 of order 0); not on a
  distributed mesh (an MPI run) yet.
"""
from __future__ import annotations

from typing import Any

import numpy as np
import ngsolve as ngs

from ..mesh.adapter import z_indicators
from .diagnostics import element_diameters
from ..physics.crack_models import CrackModel
from ..physics.splits import EnergySplit, principal_strains_3d

__all__ = ["elastic_energy_density", "undegraded_density", "degraded_stress", "split_stresses",
           "stress_components", "von_mises", "principal_stresses", "projected",
           "piecewise_constant", "snapshot_fields"]


def elastic_energy_density(model: Any, split: EnergySplit | None, crack_model: CrackModel,
                           u: Any, z: Any, eta: float) -> Any:
    """The integrand of E_el.

    ``1/2 g(z) sigma[u]:e[u]`` without a split, ``g(z) psi+ + psi-`` with one; ``g`` is the
    crack model's degradation (residual stiffness included).

    Parameters
    ----------
    model : the elastic model (``ngfrac.physics.elastic``)
    split : the energy split, or None
    crack_model : the crack model, whose ``degradation`` g is used
    u, z : the displacement and the phase field
    eta : the residual stiffness
    """
    if split is None:
        return 0.5 * crack_model.degradation(z, eta) * undegraded_density(model, split, crack_model,
                                                                            u, z, eta)
    return split.elastic_density(u, crack_model.degradation(z, eta))


def undegraded_density(model: Any, split: EnergySplit | None, crack_model: CrackModel,
                       u: Any, z: Any, eta: float) -> Any:
    """W with ``E_el = 1/2 int g(z) W``: what :func:`ngfrac.post.diagnostics.energies` takes.

    ``sigma[u]:e[u]`` without a split; with one ``2 (g(z) psi+ + psi-) / g(z)``, i.e.
    2 :func:`elastic_energy_density` / g. Parameters as for :func:`elastic_energy_density`.
    """
    if split is None:
        return model.energy_density(u)
    return 2 * elastic_energy_density(model, split, crack_model, u, z, eta) / crack_model.degradation(z, eta)


def degraded_stress(model: Any, split: EnergySplit | None, crack_model: CrackModel, u: Any,
                    z: Any, eta: float) -> Any:
    """The stress of the degraded material, dW/de of :func:`elastic_energy_density`.

    Mode III: the vector ``g(z) mu grad u``; plane and 3D models: a dim x dim matrix,
    ``g(z) sigma[u]`` without a split, ``g(z) sigma+ + sigma-`` with one
    (:func:`split_stresses`). Parameters as for :func:`elastic_energy_density`.
    """
    g = crack_model.degradation(z, eta)
    if split is None:  # mode III: model.stress is the shear stress vector
        return g * model.stress(u)
    plus, minus = split_stresses(split, ngs.Sym(ngs.grad(u)))
    return g * plus + minus


def split_stresses(split: EnergySplit, e: Any) -> tuple[Any, Any]:
    """sigma+ = dpsi+/de and sigma- = dpsi-/de of a split at the strain e (dim x dim), in
    closed form (why not NGSolve's ``Diff``: docs/user-guide.md, "Cost of the split stresses").

    Amor: ``sigma+ = K <tr e>_+ I + 2 mu dev e``, ``sigma- = K <tr e>_- I``. Miehe:
    ``sigma+ = lam <tr e>_+ I + 2 mu <e>_+`` with ``<e>_+ = sum_i <e_i>_+ P_i`` (the
    eigenprojections as in :mod:`ngfrac.physics.splits`), ``sigma- = sigma - sigma+``.
    """
    dim, lam, mu = split.dim, split.lam, split.mu
    identity = ngs.Id(dim)
    tr = ngs.Trace(e)
    if split.kind == "amor":
        bulk = lam + 2 * mu / split.bulk_dim
        plus = bulk * ngs.IfPos(tr, tr, 0.0) * identity + 2 * mu * (e - tr / split.bulk_dim * identity)
        return plus, bulk * ngs.IfPos(tr, 0.0, tr) * identity
    zero = ngs.CF((0.0,) * (dim * dim), dims=(dim, dim))
    if dim == 2:
        half_gap = ngs.sqrt(0.25 * (e[0, 0] - e[1, 1]) ** 2 + e[0, 1] ** 2)
        e1, e2 = 0.5 * tr + half_gap, 0.5 * tr - half_gap
        # e1 > 0 >= e2 keeps e1 - e2 > 0; IfPos selects, the branches not taken may divide by 0
        one = e1 * (e - e2 * identity) / (e1 - e2)
        positive = ngs.IfPos(e2, e, ngs.IfPos(e1, one, zero))
    else:
        e1, e2, e3 = principal_strains_3d(e)
        one = e1 * (e - e2 * identity) * (e - e3 * identity) / ((e1 - e2) * (e1 - e3))
        two = e - e3 * (e - e1 * identity) * (e - e2 * identity) / ((e3 - e1) * (e3 - e2))
        positive = ngs.IfPos(e3, e, ngs.IfPos(e2, two, ngs.IfPos(e1, one, zero)))
    plus = lam * ngs.IfPos(tr, tr, 0.0) * identity + 2 * mu * positive
    return plus, 2 * mu * e + lam * tr * identity - plus


def stress_components(stress: Any, dim: int) -> Any:
    """A symmetric stress matrix as a vector: (xx, yy, xy) in 2D, (xx, yy, zz, xy, yz, xz) in 3D."""
    pairs = ((0, 0), (1, 1), (0, 1)) if dim == 2 else ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2))
    return ngs.CoefficientFunction(tuple(stress[i, j] for i, j in pairs))


def _with_out_of_plane(stress: Any, model: Any) -> Any:
    """The 3x3 stress of a plane model: sigma_zz = nu (sxx + syy) in plane strain, 0 in plane stress."""
    szz = model.out_of_plane_stress(stress)
    return ngs.CoefficientFunction((stress[0, 0], stress[0, 1], 0.0,
                                    stress[1, 0], stress[1, 1], 0.0,
                                    0.0, 0.0, szz), dims=(3, 3))


def von_mises(stress: Any, model: Any) -> Any:
    """sqrt(3/2 s:s) with s the deviator of the 3x3 stress (plane models: see the module)."""
    full = stress if model.n_components == 3 else _with_out_of_plane(stress, model)
    deviator = full - ngs.Trace(full) / 3 * ngs.Id(3)
    return ngs.sqrt(1.5 * ngs.InnerProduct(deviator, deviator))


def principal_stresses(stress: Any, dim: int) -> Any:
    """The principal values of the (in-plane, 2D) stress matrix, largest first."""
    if dim == 3:
        return ngs.CoefficientFunction(principal_strains_3d(stress))
    mean = 0.5 * (stress[0, 0] + stress[1, 1])
    radius = ngs.sqrt(0.25 * (stress[0, 0] - stress[1, 1]) ** 2 + stress[0, 1] ** 2)
    return ngs.CoefficientFunction((mean + radius, mean - radius))


def projected(stress: Any, mesh: ngs.Mesh, order: int) -> ngs.GridFunction:
    """A 3x3 stress as its L2 projection per element, of polynomial order ``order``.

    Used for the 3D spectral split, whose closed-form stress is slow to evaluate entry by
    entry (docs/user-guide.md, "Cost of the split stresses").
    """
    gf = ngs.GridFunction(ngs.MatrixValued(ngs.L2(mesh, order=order), dim=3), "stress")
    gf.Set(stress)
    return gf


def piecewise_constant(mesh: ngs.Mesh, values: np.ndarray, name: str) -> ngs.GridFunction:
    """One value per volume element (in NGSolve's element order) as an L2 order-0 GridFunction."""
    gf = ngs.GridFunction(ngs.L2(mesh, order=0), name)
    gf.vec.FV().NumPy()[:] = np.asarray(values, dtype=float)
    return gf


def snapshot_fields(stepper: Any) -> dict[str, Any]:
    """The fields of one VTK snapshot of a stepper, by name (see the module docstring)."""
    mesh, u, z = stepper.mesh, stepper.u, stepper.z
    eta = stepper.scene.phase_field.residual_stiffness
    model, split, crack_model = stepper.model, stepper.split, stepper.crack_model
    gamma = stepper.gamma
    fields: dict[str, Any] = {"u": u, "z": z,
                              "gamma": (ngs.CoefficientFunction(float(gamma)) if isinstance(gamma, (int, float))
                                        else gamma),
                              "energy_density": elastic_energy_density(model, split, crack_model, u, z, eta)}
    stress = degraded_stress(model, split, crack_model, u, z, eta)
    if model.n_components == 1:
        fields["stress"] = stress
    else:
        if mesh.dim == 3 and split is not None and split.kind == "miehe":
            stress = projected(stress, mesh, max(stepper.scene.discretization.order - 1, 0))
        fields["stress"] = stress_components(stress, mesh.dim)
        fields["von_mises"] = von_mises(stress, model)
        fields["principal_stress"] = principal_stresses(stress, mesh.dim)
    if mesh.comm.size > 1:  # per-element fields of a distributed mesh: not yet
        return fields
    fields["estimator"] = piecewise_constant(mesh, z_indicators(stepper.scene, z), "estimator")
    fields["h"] = piecewise_constant(mesh, element_diameters(mesh), "h")
    return fields
