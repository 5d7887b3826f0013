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

A surface term that is concave in z (PF-CZM's ``-z^2/eps``) is not put in the matrix, which
it could make indefinite: :meth:`CrackModel.concave` gives it, the z-step takes it at z_old
(its ``-C z_old`` on the right-hand side: a convex-concave splitting, so each sub-step still
minimizes a convex quadratic) and the surface energy counts it in full.

``PF-CZM`` (Wu 2017, Wu & Nguyen 2018), :class:`PFCZM`: ``alpha(z) = 2z - z^2``, c_w = pi,
and a rational degradation that depends on eps, E, G_f = gamma and the strength f_t, so the
damage starts at ``sigma = f_t`` and the softening law does not depend on eps.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
import ngsolve as ngs

from .splits import principal_strains_3d

__all__ = ["AT1", "AT2", "CRACK_MODELS", "CrackModel", "PFCZM", "SOFTENING_LAWS", "crack_model",
           "largest_principal_stress"]


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
    """Whether ``g(z) = (1 - z)^2 + eta``. Then the z-step's drive is exactly ``W (1 - zt)``
    (the paper's), and with w at most quadratic in z every form and energy is a polynomial of
    the degree :func:`ngfrac.fem.quadrature.quadrature_order` integrates exactly on affine
    elements."""
    default_z_order: int | None = None
    """The order of z when ``discretization.order_z`` is unset (0); None: that of u, at most 2
    (:meth:`ngfrac.scene.sections.Discretization.z_order_for`)."""

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

    def concave(self, trial: Any, test: Any, gamma: Any,
                epsilon: float) -> ngs.CoefficientFunction | None:
        """The integrand of a negative semidefinite part C of the surface energy's quadratic
        form (``E_surf = 1/2 z.(K + C) z - s.z``), None if there is none. The z-step takes it
        explicitly (``-C z_old`` on its right-hand side), so its matrix stays K + (alpha2/dt) M
        + D, symmetric positive definite."""
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


SOFTENING_LAWS: dict[str, tuple[float, float, float]] = {
    "linear": (2.0, -0.5, 0.0),
    "exponential": (2.5, 2.0 ** (5.0 / 3.0) - 3.0, 0.0),
    "cornelissen": (2.0, 1.3868, 0.6567),
}
"""(p, a2, a3) of PF-CZM's degradation per ``phase_field.softening`` (Wu 2017; Wu & Nguyen
2018): linear, exponential and Cornelissen et al.'s (1986) concrete softening."""

CONVEX_A1: dict[str, float] = {law: p + a2 for law, (p, a2, _) in SOFTENING_LAWS.items()}
"""The smallest a1 for which PF-CZM's g is convex on [0, 1]: ``g''(0) = 2 a1 (a1 - p - a2)``,
so a1 >= p + a2 (for the three laws the smallest g'' on [0, 1] is at z = 0 then: checked on
4e5 points); linear: 3/2, Wu's ``eps <= 8 l_ch/(3 pi)``; exponential 2^(5/3) - 1/2 = 2.675;
Cornelissen 3.387. The epsilon limit is ``eps <= 4 l_ch/(pi a1_min)``."""


def _nonnegative(x: Any) -> Any:
    """max(x, 0) of a CoefficientFunction or an array/number."""
    if isinstance(x, ngs.CoefficientFunction):
        return ngs.IfPos(x, x, 0.0)
    return np.maximum(x, 0.0)


class PFCZM(CrackModel):
    """Wu's phase-field cohesive zone model: a strength f_t, a softening law, eps-insensitive.

    ``w = (2z - z^2)/eps + eps |grad z|^2`` over c_w = pi (optimal profile
    ``z = 1 - sin(d/eps)`` for ``d <= pi eps/2``: a band of half width pi eps/2), and

        g(z) = (1 - z)^p / ((1 - z)^p + a1 z (1 + a2 z + a2 a3 z^2)) + eta,
        a1 = 4 l_ch/(pi eps),   l_ch = E G_f/f_t^2

    with (p, a2, a3) from :data:`SOFTENING_LAWS`. g'(0) = -a1, and ``alpha'(0) = 2``: below
    ``sigma = f_t`` (uniaxial; ``W = f_t^2/E``) the drive ``-1/2 g'(0) W`` is smaller than
    the constant source ``2 G_f/(pi eps)`` and z stays 0 (an elastic phase, as AT1's).

    The z-sub-step is no longer linear in z: the drive ``-1/2 g'(zt) W`` is linearized at
    z_old (:meth:`CrackModel.drive_factors`, the positive part of g'' implicit; g'' < 0 near
    z = 0 when a1 is near its limit), and the concave ``-z^2/eps`` is taken at z_old
    (:meth:`concave`): one linear (or obstacle) solve per step, as AT1's, not a Newton loop.

    Parameters
    ----------
    young : float
        E of the onset (mode III: mu, the onset is then at the shear stress f_t).
    toughness : float
        G_f, the scene's ``material.gamma`` (a constant).
    strength : float
        f_t (``material.strength``).
    epsilon : float
        The regularization length (``phase_field.epsilon``); at most :meth:`epsilon_limit`.
    softening : str
        A key of :data:`SOFTENING_LAWS`.

    Raises
    ------
    ValueError
        A non-positive parameter, an unknown softening law, or eps above the limit.
    """

    name = "PF-CZM"
    c_w = math.pi
    z_update = "obstacle"  # the constant source pulls the unconstrained step far below z_old
    quadratic_degradation = False
    default_z_order = 1
    """P1 z unless asked: with P2 z the nodal obstacle lets z grow below f_t at vertex nodes
    (the elastic phase is lost; docs/theory.md, "PF-CZM and the hybrid formulation")."""
    """The rational g: the z-step takes its drive linearized at z_old (``drive_factors``)."""

    def __init__(self, young: float, toughness: float, strength: float, epsilon: float,
                 softening: str = "linear") -> None:
        for key, value in (("E", young), ("G_f", toughness), ("f_t", strength),
                           ("epsilon", epsilon)):
            if not (value > 0 and math.isfinite(value)):
                raise ValueError(f"PF-CZM needs {key} > 0, not {value!r}")
        if softening not in SOFTENING_LAWS:
            raise ValueError(f"softening = {softening!r}: choose one of {', '.join(SOFTENING_LAWS)}")
        self.young, self.toughness, self.strength = float(young), float(toughness), float(strength)
        self.epsilon, self.softening = float(epsilon), softening
        self.p, self.a2, self.a3 = SOFTENING_LAWS[softening]
        self.l_ch = self.young * self.toughness / self.strength ** 2
        """Irwin's length E G_f / f_t^2."""
        self.a1 = 4.0 * self.l_ch / (math.pi * self.epsilon)
        limit = self.epsilon_limit()
        if self.epsilon > limit:
            raise ValueError(f"epsilon = {epsilon!r} is above PF-CZM's limit {limit:.4g} for the "
                             f"{softening} law (4 l_ch/(pi a1_min), l_ch = E G_f/f_t^2 = "
                             f"{self.l_ch:.4g}, a1_min = p + a2 = {CONVEX_A1[softening]:.4g}): "
                             "lower it")

    def epsilon_limit(self) -> float:
        """The largest eps for which g is convex on [0, 1]: ``4 l_ch/(pi a1_min)``
        (:data:`CONVEX_A1`; linear: ``8 l_ch/(3 pi)``)."""
        return 4.0 * self.l_ch / (math.pi * CONVEX_A1[self.softening])

    def _parts(self, z: Any) -> tuple[Any, Any, Any, Any, Any, Any]:
        """N = (1-z)^p, Q = a1 z (1 + a2 z + a2 a3 z^2) and their first two derivatives."""
        p, a1, a2, a3 = self.p, self.a1, self.a2, self.a3
        s = _nonnegative(1 - z)  # a P2 z may pass 1 between its nodes
        n = s ** p
        n1 = -p * s ** (p - 1)
        n2 = p * (p - 1) * (s ** (p - 2) if p != 2 else 1.0 + 0 * s)
        q = a1 * z * (1 + a2 * z + a2 * a3 * z * z)
        q1 = a1 * (1 + 2 * a2 * z + 3 * a2 * a3 * z * z)
        q2 = a1 * (2 * a2 + 6 * a2 * a3 * z)
        return n, n1, n2, q, q1, q2

    def degradation(self, z: Any, eta: float) -> Any:
        n, _, _, q, _, _ = self._parts(z)
        return n / (n + q) + eta

    def degradation_slope(self, z: Any) -> Any:
        n, n1, _, q, q1, _ = self._parts(z)
        return (n1 * q - n * q1) / (n + q) ** 2

    def degradation_curvature(self, z: Any) -> Any:
        n, n1, n2, q, q1, q2 = self._parts(z)
        d = n + q
        return (n2 * q - n * q2) / d ** 2 - 2 * (n1 * q - n * q1) * (n1 + q1) / d ** 3

    def surface_density(self, z: Any, epsilon: float) -> ngs.CoefficientFunction:
        return ((2 * z - z * z) / epsilon
                + epsilon * ngs.InnerProduct(ngs.grad(z), ngs.grad(z))) / math.pi

    def stiffness(self, trial: Any, test: Any, gamma: Any, epsilon: float) -> ngs.CoefficientFunction:
        return 2 * epsilon / math.pi * gamma * ngs.grad(trial) * ngs.grad(test)

    def concave(self, trial: Any, test: Any, gamma: Any, epsilon: float) -> ngs.CoefficientFunction:
        return -2 / (math.pi * epsilon) * gamma * trial * test

    def source(self, test: Any, gamma: Any, epsilon: float) -> ngs.CoefficientFunction:
        return -2 / (math.pi * epsilon) * gamma * test

    def profile(self, distance: np.ndarray, epsilon: float) -> np.ndarray:
        x = np.clip(np.asarray(distance, dtype=float) / epsilon, 0.0, math.pi / 2)
        return 1.0 - np.sin(x)

    def half_width(self, epsilon: float, level: float = 0.5) -> float:
        return epsilon * math.asin(1.0 - level)

    def rankine_drive(self, stress: Any, n_components: int) -> ngs.CoefficientFunction:
        """Wu's Rankine drive ``W = <sigma_1>^2 / E`` (twice his ``Ybar``): sigma_1 the
        largest principal stress of the undegraded stress ``stress`` (a CF: the model's
        ``stress(u)``; mode III: the shear stress vector, sigma_1 = its length).

        Wu takes the history maximum of Ybar; this drive keeps none: under monotone loading W
        does not fall where z grows, and the non-repair bound z >= z_old already keeps what
        z reached (a history would only change when z grows again after unloading)."""
        sigma_1 = largest_principal_stress(stress, n_components)
        return (_nonnegative(sigma_1) ** 2 / self.young).Compile()

    def __repr__(self) -> str:
        return (f"PFCZM(young={self.young!r}, toughness={self.toughness!r}, strength="
                f"{self.strength!r}, epsilon={self.epsilon!r}, softening={self.softening!r})")


def largest_principal_stress(stress: Any, n_components: int) -> ngs.CoefficientFunction:
    """The largest principal value of a symmetric stress CF: 2x2 or 3x3 in closed form; for
    mode III (``n_components = 1``, the shear stress vector) its length."""
    if n_components == 1:
        return ngs.sqrt(ngs.InnerProduct(stress, stress))
    if n_components == 2:
        half_gap = ngs.sqrt(0.25 * (stress[0, 0] - stress[1, 1]) ** 2 + stress[0, 1] ** 2)
        return 0.5 * ngs.Trace(stress) + half_gap
    return principal_strains_3d(stress)[0]  # the closed form holds for any symmetric 3x3


CRACK_MODELS: dict[str, type[CrackModel]] = {"AT2": AT2, "AT1": AT1, "PF-CZM": PFCZM}
"""The values of ``phase_field.model``."""


def crack_model(name: str, **parameters: Any) -> CrackModel:
    """The crack model of ``phase_field.model`` (``"AT2"``, ``"AT1"``; ``"PF-CZM"`` needs its
    :class:`PFCZM` parameters, :func:`ngfrac.scene.build.crack_model_of` gives them)."""
    try:
        cls = CRACK_MODELS[name]
    except KeyError:
        raise ValueError(f"unknown crack model {name!r}: choose one of {', '.join(CRACK_MODELS)}") from None
    return cls(**parameters)
