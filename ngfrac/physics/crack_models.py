"""Crack models: the phase-field functional in one object (``phase_field.model``).

A crack model owns its mathematics: the degradation g(z) of the elastic energy and what the
z-sub-step needs of it (:meth:`CrackModel.drive_factors`), the surface density and its
constant, the z-forms, the optimal profile. AT2 and AT1 share ``g(z) = (1 - z)^2 + eta``
and differ in the surface term ``gamma w(z, grad z)``:

- ``AT2`` (the paper's, Ambrosio-Tortorelli): ``w = 1/2 (eps |grad z|^2 + z^2/eps)``; optimal
  profile ``exp(-d/eps)``; no elastic threshold (damage at any load);
- ``AT1``: ``w = 3/8 (z/eps + eps |grad z|^2)``; optimal profile ``(1 - d/(2 eps))^2`` for
  ``d <= 2 eps`` (compact support); an elastic threshold: a homogeneous state stays undamaged
  up to ``sigma_c = sqrt(3 E gamma / (8 eps))`` (mode III: the shear stress, mu for E).

The z-sub-step of the paper's semi-implicit scheme (its eq. 7) with drive ``W = sigma:e`` of
the previous u::

    alpha2 (zt - z_old)/dt = -dw/dz-terms + W (1 - zt)

is linear for both: ``a(zt, v) = (alpha2/dt) (zt, v) + K(zt, v) + (W zt, v)`` with ``K`` from
:meth:`CrackModel.stiffness`, and the right-hand side ``(alpha2/dt) (z_old, v) + (W, v) +``
:meth:`CrackModel.source`. AT1's ``z/eps`` term is a constant source (``-3 gamma/(8 eps)``):
below the threshold zt < z_old and the bound ``z = max(zt, z_old)`` keeps z as it was, which
is what makes the elastic phase (the paper's scheme needs nothing else).

A model with another degradation (``quadratic_degradation = False``) gives g, g' and g''; the
drive ``-1/2 g'(zt) W`` of its z-sub-step is linearized at z_old,
``-1/2 g'(z_old) - 1/2 g''(z_old)^+ (zt - z_old)`` (the curvature's positive part implicit,
so the z-matrix stays symmetric positive definite): one linear solve per step, as the
paper's scheme, exact where g is quadratic.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
import ngsolve as ngs

__all__ = ["AT1", "AT2", "CRACK_MODELS", "CrackModel", "crack_model"]


class CrackModel:
    """The phase-field functional of one crack model (subclass per model).

    Attributes
    ----------
    name : str
        The scene's ``phase_field.model``.
    z_update : str
        The z-update of ``discretization.z_update = "auto"``: ``"projection"`` (the paper's)
        or ``"obstacle"`` (the z-step minimized under z >= z_old) where the unconstrained
        sub-step leaves the admissible set by far.
    c_w : float
        The normalization of the surface density, ``w = (alpha(z)/eps + eps |grad z|^2) / c_w``
        with ``c_w = 4 int_0^1 sqrt(alpha(s)) ds``: ``alpha(z) = z^2``, c_w = 2 (AT2) or
        ``alpha(z) = z``, c_w = 8/3 (AT1); then the optimal profile costs gamma per unit length.
    """

    name = ""
    c_w = math.nan
    z_update = "projection"
    quadratic_degradation = True
    """g(z) = (1 - z)^2 + eta: the z-step's drive is exactly ``W (1 - zt)`` (the paper's), and
    with w at most quadratic in z every form and energy is a polynomial of the degree
    :func:`ngfrac.fem.quadrature.quadrature_order` integrates exactly on affine elements."""

    def resolve_z_update(self, requested: str) -> str:
        """The z-update a run uses for ``discretization.z_update = requested`` (``"auto"``:
        this model's :attr:`z_update`)."""
        return self.z_update if requested == "auto" else requested

    def degradation(self, z: Any, eta: float) -> Any:
        """``g(z) = (1 - z)^2 + eta``, the factor of the elastic energy (z a
        CoefficientFunction or a number)."""
        return (1 - z) ** 2 + eta

    def degradation_slope(self, z: Any) -> Any:
        """g'(z) (``-2 (1 - z)``)."""
        return -2 * (1 - z)

    def degradation_curvature(self, z: Any) -> Any:
        """g''(z) (``2``)."""
        return 2.0 + 0 * z

    def drive_factors(self, z_old: Any) -> tuple[Any, Any] | None:
        """The z-sub-step's elastic drive ``-1/2 g'(zt) W`` as ``W (explicit - implicit zt)``.

        Returns (implicit, explicit), CoefficientFunctions of ``z_old`` with implicit >= 0,
        from the linearization at z_old (module docstring); None for the quadratic g, whose
        drive is ``W (1 - zt)`` exactly (implicit = explicit = 1: the z-step then builds its
        right-hand side from the drive matrix, :mod:`ngfrac.solve.z_problem`).
        """
        if self.quadratic_degradation:
            return None
        curvature = 0.5 * self.degradation_curvature(z_old)
        implicit = ngs.IfPos(curvature, curvature, 0.0)
        return implicit, -0.5 * self.degradation_slope(z_old) + implicit * z_old

    def surface_density(self, z: Any, epsilon: float) -> ngs.CoefficientFunction:
        """``w(z, grad z)``: its integral is the crack length (the Gamma-limit), and
        ``int gamma w`` the surface energy."""
        raise NotImplementedError

    def stiffness(self, trial: Any, test: Any, gamma: Any, epsilon: float) -> ngs.CoefficientFunction:
        """The integrand of ``K`` in the z-sub-step's matrix (its z-part of dE_surf/dz)."""
        raise NotImplementedError

    def source(self, test: Any, gamma: Any, epsilon: float) -> ngs.CoefficientFunction | None:
        """The integrand of the z-sub-step's constant right-hand side, None if there is none."""
        return None

    def profile(self, distance: np.ndarray, epsilon: float) -> np.ndarray:
        """The 1D optimal profile with z = 1 on the crack, at distance ``distance``."""
        raise NotImplementedError

    def half_width(self, epsilon: float, level: float = 0.5) -> float:
        """The distance from the crack where the optimal profile falls to ``level``."""
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class AT2(CrackModel):
    """The paper's functional: ``w = 1/2 (eps |grad z|^2 + z^2/eps)``."""

    name = "AT2"
    c_w = 2.0

    def surface_density(self, z: Any, epsilon: float) -> ngs.CoefficientFunction:
        return 0.5 * (epsilon * ngs.InnerProduct(ngs.grad(z), ngs.grad(z)) + z * z / epsilon)

    def stiffness(self, trial: Any, test: Any, gamma: Any, epsilon: float) -> ngs.CoefficientFunction:
        return epsilon * gamma * ngs.grad(trial) * ngs.grad(test) + gamma / epsilon * trial * test

    def profile(self, distance: np.ndarray, epsilon: float) -> np.ndarray:
        return np.exp(-np.asarray(distance, dtype=float) / epsilon)

    def half_width(self, epsilon: float, level: float = 0.5) -> float:
        return epsilon * math.log(1.0 / level)


class AT1(CrackModel):
    """``w = 3/8 (z/eps + eps |grad z|^2)``: an elastic threshold, a band of width 4 eps."""

    name = "AT1"
    c_w = 8.0 / 3.0
    z_update = "obstacle"  # the unconstrained z-step is far below z_old: ngfrac/solve/obstacle.py

    def surface_density(self, z: Any, epsilon: float) -> ngs.CoefficientFunction:
        return 0.375 * (z / epsilon + epsilon * ngs.InnerProduct(ngs.grad(z), ngs.grad(z)))

    def stiffness(self, trial: Any, test: Any, gamma: Any, epsilon: float) -> ngs.CoefficientFunction:
        return 0.75 * epsilon * gamma * ngs.grad(trial) * ngs.grad(test)

    def source(self, test: Any, gamma: Any, epsilon: float) -> ngs.CoefficientFunction:
        return -0.375 * gamma / epsilon * test

    def profile(self, distance: np.ndarray, epsilon: float) -> np.ndarray:
        s = np.clip(1.0 - np.asarray(distance, dtype=float) / (2.0 * epsilon), 0.0, 1.0)
        return s * s

    def half_width(self, epsilon: float, level: float = 0.5) -> float:
        return 2.0 * epsilon * (1.0 - math.sqrt(level))


CRACK_MODELS: dict[str, type[CrackModel]] = {"AT2": AT2, "AT1": AT1}
"""The values of ``phase_field.model``."""


def crack_model(name: str) -> CrackModel:
    """The crack model of ``phase_field.model`` (``"AT2"`` or ``"AT1"``)."""
    try:
        return CRACK_MODELS[name]()
    except KeyError:
        raise ValueError(f"unknown crack model {name!r}: choose one of {', '.join(CRACK_MODELS)}") from None
