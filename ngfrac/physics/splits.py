"""Tension/compression splits of the elastic energy and the Newton u-solve they need.

The paper's model degrades all of the elastic energy, so compression also drives z. A split
writes the energy density psi = 1/2 sigma:e as psi+ + psi- and degrades only psi+::

    E_el = int g(z) psi+(e[u]) + psi-(e[u])      (g the crack model's degradation)
    alpha2 dz/dt = ( eps div(gamma grad z) - gamma z/eps - g'(z) psi+(e[u]) )_+

(with no split 2 psi+ = sigma:e, the paper's model). The splits (``material.split``):

- ``"amor"`` (volumetric-deviatoric, Amor et al. 2009):
  ``psi+ = K/2 <tr e>_+^2 + mu |dev e|^2``, ``psi- = K/2 <tr e>_-^2``;
- ``"miehe"`` (spectral, Miehe et al. 2010):
  ``psi+ = lam/2 <tr e>_+^2 + mu sum_i <e_i>_+^2``, ``psi- = psi - psi+``;

with ``<x>_+ = max(x, 0)``, ``<x>_- = min(x, 0)``, e_i the principal strains. Plane strain
and 3D use the 3D strain (plane strain: e_zz = 0, so K = lam + 2 mu/3 and dev e = e - tr e/3 I
of the 3x3 strain; its third principal strain is 0 and adds nothing to either part). Plane
stress uses the 2D strain with the plane-stress lam*: K = lam* + mu, dev e = e - tr e/2 I.
The spectral split takes closed-form principal strains: 2x2 in the plane models, 3x3 in 3D
(the trigonometric formula, :func:`principal_strains_3d`).

Both energies are convex, piecewise quadratic and positively homogeneous of degree 2 in e,
so the u-problem is nonlinear but well posed. It is solved by Newton's method with the exact
tangent written out (:meth:`EnergySplit.tangent`: the second derivative of psi+ at the current
u, a linear form in the trial function; NGSolve's symbolic ``Variation`` gives the same matrix
by automatic differentiation but was 6x (Amor) and 27x (Miehe) slower to assemble), a
backtracking line search on the energy, and the residual on the free dofs relative to ``|H u|``
(1e-10) as the stopping test. Homogeneity gives ``D E(u) = H(u) u`` exactly (H the tangent at
u), so the residual is ``H(u) u - rhs`` and the tangent at the
converged u also gives the reaction forces (:mod:`ngfrac.post.reactions`).

Miehe's tangent in 2D, with principal strains e1 >= e2, eigenvectors n1, n2, P1 = n1 n1^T:
``d^2 e1[h, k] = 2 (n1.h.n2)(n1.k.n2)/(e1 - e2)`` and
``(n1.h.n2)(n1.k.n2) = dev h:dev k/2 - ((2 P1 - I):h)((2 P1 - I):k)/4`` (2D deviators).

Miehe's tangent in 3D: with g = f' for f(x) = <x>_+^2 and eigenprojections P_i,
``d^2 sum_i f(e_i)[h, k] = sum_ij theta_ij (P_i h P_j):k``, theta_ii = f''(e_i) and
theta_ij = (g(e_i) - g(e_j))/(e_i - e_j): 2 if both are positive, 0 if neither is,
2 e_i/(e_i - e_j) if e_i > 0 >= e_j. Equal principal strains therefore only meet inside the
positive or the non-positive group, which enter through their projection alone (Q+ and
I - Q+); with m positive principal strains, Q+ the projection on them:

- m = 0: 0; m = 3: ``2 h:k``;
- m = 1: ``2 (P1 h P1):k + (P1 h C):k``, ``C = sum_{j=2,3} 4 e1/(e1 - e_j) P_j
  = 4 e1 ((e1 - e2 - e3) I + e)(I - P1) / ((e1 - e2)(e1 - e3))`` (the linear interpolant
  of x -> 4 e1/(e1 - x) at e2, e3, so e2 = e3 needs no P2, P3);
- m = 2: ``2 (Q+ h Q+):k + (C h P3):k``, ``Q+ = I - P3``,
  ``C = 4 (e1 e2 I - e3 e) Q+ / ((e1 - e3)(e2 - e3))``;

with ``P1 = (e - e2 I)(e - e3 I)/((e1 - e2)(e1 - e3))``, ``P3 = (e - e1 I)(e - e2 I)/((e3 - e1)
(e3 - e2))`` (Sylvester); the denominators are positive where these are used. At a zero
principal strain (a kink of <x>_+: the energy is only C^1 there) IfPos counts 0 as not
positive, so the tangent is the second derivative from one side, the side of the strain as
computed: round-off of ~1e-16 ``|e|`` picks it, and either side gives a valid Newton matrix.
"""
from __future__ import annotations

import logging
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass, field
from typing import Any, Callable, Iterator

import ngsolve as ngs
import numpy as np


log = logging.getLogger(__name__)

SPLITS = ("none", "amor", "miehe")
"""Values of ``material.split``."""

_PAIR_TOLERANCE = 1e-13
"""Two principal strains are equal where ``|r| > 1 -`` this (:func:`principal_strains_3d`)."""


def _positive(x: Any) -> Any:
    return ngs.IfPos(x, x, 0.0)


def _negative(x: Any) -> Any:
    return ngs.IfPos(x, 0.0, x)


def principal_strains_3d(e: Any) -> tuple[Any, Any, Any]:
    """The principal strains e1 >= e2 >= e3 of a symmetric 3x3 CF, in closed form.

    The trigonometric formula: with ``q = tr e/3``, ``p = sqrt(|e - q I|^2/6)`` and
    ``r = det((e - q I)/p)/2`` in [-1, 1], the principal strains are q + p t for the roots t of
    ``t^3 - 3 t - 2 r``. With ``phi = acos(|r|)/3`` and ``a, b, c = 2 cos(phi), 2 cos(pi/3 +
    phi), 2 cos(pi/3 - phi)`` they are ``(a, -b, -c)`` for r >= 0 and ``(c, b, -a)`` for r < 0,
    so that a repeated pair (``|r| = 1``, phi = 0) comes out bitwise equal. Round-off leaves
    ``|r|`` of an exactly repeated pair up to ~1e-15 below 1 and acos would split the pair by
    ~1e-8 p, so ``|r| > 1 - 1e-13`` counts as a pair: the individual values of a pair closer
    than ~5e-7 p move by less than that, their sum and product by ~1e-13 p^2. Where p = 0
    (isotropic strain) all three are q: nothing divides by p there.

    Parameters
    ----------
    e : ngsolve.CoefficientFunction
        A symmetric 3x3 matrix.

    Returns
    -------
    tuple of ngsolve.CoefficientFunction
        e1, e2, e3.
    """
    q = ngs.Trace(e) / 3
    deviator = e - q * ngs.Id(3)
    p2 = ngs.InnerProduct(deviator, deviator)
    p = ngs.sqrt(p2 / 6)
    r = ngs.Det(deviator / ngs.IfPos(p2, p, 1.0)) / 2
    size = ngs.IfPos(r, r, -r)
    size = ngs.IfPos(size - (1 - _PAIR_TOLERANCE), 1.0, size)  # also clips round-off above 1
    phi = ngs.acos(size) / 3
    third = np.pi / 3
    a, b, c = 2 * ngs.cos(phi), 2 * ngs.cos(third + phi), 2 * ngs.cos(third - phi)
    return (q + p * ngs.IfPos(r, a, c), q + p * ngs.IfPos(r, -b, b),
            q - p * ngs.IfPos(r, c, a))


def _spectral_squares_3d(e: Any, h: Any, k: Any) -> Any:
    """The second derivative of ``sum_i <e_i>_+^2`` at the 3x3 strain e, applied to h and k
    (module docstring): ``2 (Q+ h Q+):k + (left h right):k``, the case (how many principal
    strains are positive) selecting the coefficient matrices Q+, left, right, never h or k.

    NGSolve evaluates the compiled integrand, coefficients included, once per pair of trial
    and test gradient components (81 in 3D); build the form in :func:`tangent_integrators`
    (docs/benchmarks.md, "The 3D spectral split", has the cost).
    """
    e1, e2, e3 = principal_strains_3d(e)
    identity = ngs.Id(3)
    zero = ngs.CF((0.0,) * 9, dims=(3, 3))
    # one positive principal strain, e1 > 0 >= e2 >= e3: (e1 - e2)(e1 - e3) >= e1^2 > 0
    gaps1 = (e1 - e2) * (e1 - e3)
    p1 = (e - e2 * identity) * (e - e3 * identity) / gaps1
    c1 = 4 * e1 / gaps1 * ((e1 - e2 - e3) * identity + e) * (identity - p1)
    # two, e1 >= e2 > 0 >= e3: (e1 - e3)(e2 - e3) >= e2^2 > 0
    gaps3 = (e1 - e3) * (e2 - e3)
    p3 = (e - e1 * identity) * (e - e2 * identity) / gaps3
    c3 = 4 / gaps3 * (e1 * e2 * identity - e3 * e) * (identity - p3)

    # IfPos selects: the branches not taken may divide by zero
    def cases(none: Any, one: Any, two: Any, three: Any) -> Any:
        return ngs.IfPos(e3, three, ngs.IfPos(e2, two, ngs.IfPos(e1, one, none)))

    positive = cases(zero, p1, identity - p3, identity)
    left = cases(zero, p1, c3, zero)
    right = cases(zero, c1, p3, zero)
    return (2 * ngs.InnerProduct(positive * h * positive, k)
            + ngs.InnerProduct(left * h * right, k))


class EnergySplit:
    """psi+ and psi- of one split for an elastic model with Lame constants (lam, mu).

    Parameters
    ----------
    kind : str
        ``"amor"`` or ``"miehe"``.
    lam, mu : float
        The Lame constants of the model's stress (plane stress: lam*).
    dim : int
        Components of u (2 or 3).
    bulk_dim : int
        The dimension of the strain whose trace and deviator enter: 3 for plane strain and 3D,
        2 for plane stress.
    """

    def __init__(self, kind: str, lam: float, mu: float, dim: int, bulk_dim: int) -> None:
        if kind not in SPLITS[1:]:
            raise ValueError(f"split {kind!r} is not one of {SPLITS[1:]}")
        self.kind, self.lam, self.mu, self.dim, self.bulk_dim = kind, lam, mu, dim, bulk_dim

    def psi(self, e: Any) -> Any:
        """The undegraded density ``psi = lam/2 (tr e)^2 + mu |e|^2`` (= 1/2 sigma:e)."""
        return 0.5 * self.lam * ngs.Trace(e) ** 2 + self.mu * ngs.InnerProduct(e, e)

    def psi_plus(self, e: Any) -> Any:
        """The degraded part psi+ of the density for the strain e (a dim x dim CF)."""
        tr = ngs.Trace(e)
        if self.kind == "amor":
            bulk = self.lam + 2 * self.mu / self.bulk_dim
            dev2 = ngs.InnerProduct(e, e) - tr * tr / self.bulk_dim
            return 0.5 * bulk * _positive(tr) ** 2 + self.mu * dev2
        if self.dim == 3:
            e1, e2, e3 = principal_strains_3d(e)
            ee = ngs.InnerProduct(e, e)  # = e1^2 + e2^2 + e3^2
            squares = ngs.IfPos(e3, ee, ngs.IfPos(e2, ee - e3 * e3, ngs.IfPos(e1, e1 * e1, 0.0)))
            return 0.5 * self.lam * _positive(tr) ** 2 + self.mu * squares
        # 2x2 principal strains e1 >= e2; the plane-strain e_zz = 0 adds nothing
        half_gap = ngs.sqrt(0.25 * (e[0, 0] - e[1, 1]) ** 2 + e[0, 1] ** 2)
        e1, e2 = 0.5 * tr + half_gap, 0.5 * tr - half_gap
        # both positive: e1^2 + e2^2 = |e|^2, written so that no branch divides by half_gap = 0
        squares = ngs.IfPos(e2, ngs.InnerProduct(e, e), ngs.IfPos(e1, e1 * e1, 0.0))
        return 0.5 * self.lam * _positive(tr) ** 2 + self.mu * squares

    def psi_minus(self, e: Any) -> Any:
        """The undegraded part psi- = psi - psi+."""
        if self.kind == "amor":
            bulk = self.lam + 2 * self.mu / self.bulk_dim
            return 0.5 * bulk * _negative(ngs.Trace(e)) ** 2
        return self.psi(e) - self.psi_plus(e)

    def tangent(self, u_now: Any, u: Any, v: Any, degradation: Any) -> Any:
        """The second derivative of ``g psi+ + psi-`` at ``u_now`` (a GridFunction), applied to
        the trial ``u`` and test ``v``: the Newton matrix's integrand; ``degradation`` is g(z)
        (the crack model's, residual stiffness included)."""
        e = ngs.Sym(ngs.grad(u_now))
        h, k = ngs.Sym(ngs.grad(u)), ngs.Sym(ngs.grad(v))
        tr, trh, trk = ngs.Trace(e), ngs.Trace(h), ngs.Trace(k)
        full = self.lam * trh * trk + 2 * self.mu * ngs.InnerProduct(h, k)  # psi''[h, k]
        tension = ngs.IfPos(tr, 1.0, 0.0)
        if self.kind == "amor":
            bulk = self.lam + 2 * self.mu / self.bulk_dim
            plus = (bulk * tension * trh * trk
                    + 2 * self.mu * (ngs.InnerProduct(h, k) - trh * trk / self.bulk_dim))
        elif self.dim == 3:
            plus = self.lam * tension * trh * trk + self.mu * _spectral_squares_3d(e, h, k)
        else:
            half_gap = ngs.sqrt(0.25 * (e[0, 0] - e[1, 1]) ** 2 + e[0, 1] ** 2)
            e1, e2 = 0.5 * tr + half_gap, 0.5 * tr - half_gap
            gap = ngs.IfPos(e1 - e2, e1 - e2, 1.0)  # only used where e1 > 0 >= e2, so gap > 0
            identity = ngs.Id(2)
            p1 = (e - e2 * identity) / gap
            d1 = 2 * p1 - identity
            dev_hk = ngs.InnerProduct(h, k) - 0.5 * trh * trk
            cross = 0.5 * dev_hk - 0.25 * ngs.InnerProduct(d1, h) * ngs.InnerProduct(d1, k)
            one_positive = (2 * ngs.InnerProduct(p1, h) * ngs.InnerProduct(p1, k)
                            + 4 * e1 / gap * cross)
            # the branches select coefficients, never trial or test functions (cheaper to
            # assemble: docs/benchmarks.md, "Assembling a split's tangent")
            both = ngs.IfPos(e2, 1.0, 0.0)
            mixed = ngs.IfPos(e2, 0.0, ngs.IfPos(e1, 1.0, 0.0))
            squares = both * 2 * ngs.InnerProduct(h, k) + mixed * one_positive
            plus = self.lam * tension * trh * trk + self.mu * squares
        # Compile() shares the coefficient subexpressions between the trial and test
        # derivatives NGSolve takes (docs/benchmarks.md, "Assembling a split's tangent")
        return (degradation * plus + (full - plus)).Compile()

    def drive(self, u: Any) -> Any:
        """2 psi+(e[u]), what drives z (sigma:e without a split)."""
        return (2 * self.psi_plus(ngs.Sym(ngs.grad(u)))).Compile()

    def elastic_density(self, u: Any, degradation: Any) -> Any:
        """``g psi+ + psi-`` at u, the integrand of E_el (``degradation`` is g(z))."""
        e = ngs.Sym(ngs.grad(u))
        return (degradation * self.psi_plus(e) + self.psi_minus(e)).Compile()


@contextmanager
def tangent_integrators(split: EnergySplit | None) -> Iterator[None]:
    """Create the u-form's integrators inside this block.

    For the 3D spectral split they differentiate the integrand symbolically
    (``ngsglobals.symbolic_integrator_uses_diff``, read when an integrator is created): NGSolve
    otherwise evaluates the whole tangent once per pair of gradient components (about 8x
    slower; docs/benchmarks.md, "The 3D spectral split").
    """
    enabled = split is not None and split.kind == "miehe" and split.dim == 3
    previous = ngs.ngsglobals.symbolic_integrator_uses_diff
    if enabled:
        ngs.ngsglobals.symbolic_integrator_uses_diff = True
    try:
        yield
    finally:
        ngs.ngsglobals.symbolic_integrator_uses_diff = previous


def make_split(model: Any, kind: str) -> EnergySplit | None:
    """The split ``kind`` for a model from :mod:`ngfrac.physics.elastic`, None for ``"none"``.

    Raises ValueError for mode III (no volumetric part).
    """
    if kind == "none":
        return None
    if model.n_components == 1:
        raise ValueError(f"material.split = {kind!r} needs a plane or 3D model (model.kind); "
                         "mode III has no tension or compression: use split = 'none'")
    return EnergySplit(kind, model.lam, model.mu, model.n_components, model.bulk_dim)
