"""The scene sections and the Scene: everything one run needs, as frozen dataclasses.

A scene file has the sections ``[model]``, ``[material]``, ``[phase_field]``,
``[geometry]``, ``[[cracks]]``, ``[[loads]]``, ``[time]``, ``[discretization]``,
``[output]`` and ``[adaptivity]``; docs/user-guide.md lists every key. Each section is a frozen
dataclass that validates its own values; :class:`Scene` checks what spans sections (loads on
existing boundaries, cracks inside the domain, toughness positive everywhere).
Every problem raises :class:`SceneError` with one line that names the key, the value and
what is allowed.
"""
from __future__ import annotations

import dataclasses
import difflib
import functools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Mapping, get_type_hints

import numpy as np

from .checks import check_times, crack_problems, nonfinite_value
from ..physics.crack_models import CRACK_MODELS, PFCZM, SOFTENING_LAWS
from ..physics.elastic import ELASTIC_MODELS
from .expressions import Expression, ExpressionError
from .units import SCENE_UNITS, unit_system

if TYPE_CHECKING:
    from ..geometry.domains import Domain

MODELS = tuple(ELASTIC_MODELS)
"""Model names a scene may choose (``model.kind``)."""

MODELS_3D = tuple(kind for kind, model in ELASTIC_MODELS.items() if model.n_components == 3)
"""Models of a 3D domain (``geometry.kind = "box"``); the others are 2D."""


def _vector_text(name: str, n: int) -> str:
    """``[ux, uy]`` or ``[ux, uy, uz]`` for n = 2, 3 (``name`` = "u" or "f")."""
    return "[" + ", ".join(f"{name}{c}" for c in "xyz"[:n]) + "]"


class SceneError(ValueError):
    """A scene that cannot be run, with a one-line explanation."""


REQUIRED = object()
"""Marker default of a key the scene file must give."""


def _key(section: str, name: str) -> str:
    return f"{section}.{name}" if section else name


def _require(condition: bool, section: str, name: str, value: Any, allowed: str) -> None:
    if not condition:
        raise SceneError(f"{_key(section, name)} = {value!r} is not allowed: {allowed}")


class _Section:
    """Base of the scene sections: required keys first, plain Python values coerced into the
    field types (``Material(gamma=1.0)``, a load value ``"10*t"`` or ``["0", "t"]``), then each
    section's own checks. The sections are frozen, so :func:`dataclasses.replace` makes a
    new, validated one."""

    SECTION: ClassVar[str] = ""

    def __post_init__(self) -> None:
        hints = _hints(type(self))
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            value = getattr(self, f.name)
            if value is REQUIRED:
                raise SceneError(f"missing key {_key(self.SECTION, f.name)!r}; it is required")
            coerced = _coerce(value, hints[f.name], _key(self.SECTION, f.name), f.default)
            if coerced is not value:
                object.__setattr__(self, f.name, coerced)
        self.validate()

    def validate(self) -> None:
        """Check value ranges; overridden by sections that have any."""


FREE = "free"
"""A component of a vector load that is not prescribed (rollers: ``value = ["free", "0"]``)."""


class Components(tuple):
    """One expression per component of a vector, as a scene writes it: ``["0", "10*t"]``.

    Entries are :class:`Expression` or, in loads, the string ``"free"`` (that component
    is not prescribed on the boundary).
    """

    @classmethod
    def of(cls, value: list[Any], key: str) -> "Components":
        """Parse a TOML list; ``key`` names it in error messages."""
        entries: list[Expression | str] = []
        for i, item in enumerate(value):
            if item == FREE:
                entries.append(FREE)
                continue
            try:
                entries.append(Expression.of(item))
            except ExpressionError as err:
                raise SceneError(f"{key}[{i}]: {err}") from None
        return cls(entries)

    @property
    def free(self) -> tuple[bool, ...]:
        """Which components are left free."""
        return tuple(entry == FREE for entry in self)

    @property
    def names(self) -> frozenset[str]:
        """The variables the expressions use."""
        return frozenset().union(*(e.names for e in self if isinstance(e, Expression)))

    @property
    def text(self) -> str:
        return "[" + ", ".join(f'"{e}"' for e in self) + "]"

    def __str__(self) -> str:
        return self.text


@dataclass(frozen=True)
class Model(_Section):
    """Which equations to solve.

    ``mode3``: anti-plane shear, u scalar (out of plane). ``plane_strain`` and
    ``plane_stress``: u = (ux, uy) in the plane, ``sigma = 2 mu e + lambda tr(e) I`` with the 3D
    Lame constants (plane strain) or ``lambda* = 2 lambda mu / (lambda + 2 mu)`` (plane stress).
    ``elasticity_3d``: u = (ux, uy, uz) on a 3D domain (``geometry.kind = "box"``).
    """

    SECTION: ClassVar[str] = "model"
    kind: str = "mode3"

    def validate(self) -> None:
        if self.kind not in MODELS:
            close = difflib.get_close_matches(self.kind, MODELS, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise SceneError(f"model.kind = {self.kind!r} is not a known model{hint}; "
                             f"choose one of {', '.join(MODELS)}")

    @property
    def n_components(self) -> int:
        """Components of u: 1 for mode III, 2 for the plane models, 3 in 3D."""
        return ELASTIC_MODELS[self.kind].n_components

    def check(self, material: "Material", loads: tuple["Load", ...]) -> None:
        """What spans sections: loads, body force and moduli must fit the model.

        Mode III takes one expression per load and a scalar body force; the plane models take
        ``[ux, uy]`` (``"free"`` allowed in loads), ``[fx, fy]`` and a pair of moduli.
        """
        kind, n = self.kind, self.n_components
        for i, load in enumerate(loads):
            if load.kind == "pressure":
                if n == 1:
                    raise SceneError(f"loads[{i}].kind = 'pressure' needs a plane or 3D model, but "
                                     "model.kind = 'mode3' has no normal displacement; use "
                                     "kind = 'traction' (the out-of-plane shear stress)")
                continue  # one expression (Load.validate)
            if n == 1 and isinstance(load.value, Components):
                raise SceneError(f"loads[{i}].value = {load.value.text} is a list, but model.kind = "
                                 "'mode3' takes one expression (the out-of-plane displacement)")
            if n > 1 and not isinstance(load.value, Components):
                example = ", ".join(['\"0\"'] * (n - 1) + ['\"10*t\"'])
                raise SceneError(f"loads[{i}].value = {load.value.text!r} is one expression, but "
                                 f"model.kind = {kind!r} needs {_vector_text('u', n)}, e.g. "
                                 f"[{example}] (\"free\" leaves a component unconstrained)")
            if n > 1 and len(load.value) != n:
                raise SceneError(f"loads[{i}].value = {load.value.text} has {len(load.value)} "
                                 f"entries, but model.kind = {kind!r} needs {n}: {_vector_text('u', n)}")
        force = material.body_force
        if n == 1 and isinstance(force, Components):
            raise SceneError(f"material.body_force = {force.text} is a list, but model.kind = "
                             "'mode3' takes one expression (the out-of-plane force)")
        if n > 1 and not isinstance(force, Components) and not (force.is_constant and force.value() == 0):
            raise SceneError(f"material.body_force = {force.text!r} is one expression, but "
                             f"model.kind = {kind!r} needs {_vector_text('f', n)}")
        if n > 1 and isinstance(force, Components) and len(force) != n:
            raise SceneError(f"material.body_force = {force.text} has {len(force)} entries, but "
                             f"model.kind = {kind!r} needs {n}: {_vector_text('f', n)}")
        if n > 1 and material.moduli not in (("mu", "lam"), ("E", "nu")):
            given = ", ".join(material.moduli) or "none"
            raise SceneError(f"material: model.kind = {kind!r} needs the elastic moduli lam and mu, "
                             f"or E and nu (given: {given})")


@dataclass(frozen=True)
class Material(_Section):
    """Elastic moduli and fracture toughness.

    The moduli are one pair, ``lam`` and ``mu`` (3D Lame constants) or ``E`` and ``nu``;
    mode III may give ``mu`` alone (and without any modulus uses mu = 1). Keys not given are
    NaN. ``gamma`` is Griffith's G_c, a number or an expression in x, y; ``body_force`` is f in
    ``-div sigma = f``: one expression for mode III, ``[fx, fy]`` for the plane models.
    """

    SECTION: ClassVar[str] = "material"
    PAIRS: ClassVar[tuple[tuple[str, ...], ...]] = ((), ("mu",), ("mu", "lam"), ("E", "nu"))
    DEFAULT_MU: ClassVar[float] = 1.0
    """Mode III shear modulus when the scene gives no modulus."""
    mu: float = math.nan
    lam: float = math.nan
    E: float = math.nan
    nu: float = math.nan
    gamma: Expression = Expression("1.0")
    body_force: Expression | Components = Expression("0.0")
    """Body force f, expressions in x, y, t (mode III: out of plane)."""
    split: str = "none"
    """Tension/compression split of the elastic energy: "none" (the paper's model), "amor"
    (volumetric-deviatoric) or "miehe" (spectral); see :mod:`ngfrac.physics.splits`."""
    split_mode: str = "full"
    """How the split enters: "full" (psi+ degraded in the u-step, Newton) or "hybrid"
    (Ambati et al. 2015: isotropic u-step, linear; z driven by 2 psi+, not where psi+ < psi-)."""
    strength: float = math.nan
    """The tensile strength f_t of ``phase_field.model = "PF-CZM"`` (mode III: the shear
    strength); NaN = not given."""

    def validate(self) -> None:
        s = self.SECTION
        if self.moduli not in self.PAIRS:
            given = ", ".join(f"{_key(s, k)} = {getattr(self, k)!r}" for k in self.moduli)
            raise SceneError(f"{given} is not allowed: give exactly one pair of elastic moduli, "
                             "lam and mu, or E and nu (mode3 may give mu alone)")
        if "mu" in self.moduli:
            _require(self.mu > 0, s, "mu", self.mu, "the shear modulus must be > 0")
        if "lam" in self.moduli:
            _require(3 * self.lam + 2 * self.mu > 0, s, "lam", self.lam,
                     f"must be > -2 mu/3 = {-2 * self.mu / 3:g} (a Poisson ratio above -1)")
        if "E" in self.moduli:
            _require(self.E > 0, s, "E", self.E, "Young's modulus must be > 0")
            _require(-1 < self.nu < 0.5, s, "nu", self.nu, "Poisson's ratio must be in (-1, 0.5)")
        if isinstance(self.body_force, Components):
            _require(len(self.body_force) > 0 and not any(self.body_force.free), s, "body_force",
                     self.body_force.text, "give one expression per component, none 'free'")
        if "t" in self.gamma.names:
            raise SceneError(f"material.gamma = {self.gamma.text!r} may not depend on t")
        _require(self.split in ("none", "amor", "miehe"), s, "split", self.split,
                 "choose 'none' (the paper's model), 'amor' or 'miehe'")
        _require(self.split_mode in ("full", "hybrid"), s, "split_mode", self.split_mode,
                 "choose 'full' (psi+ degraded, Newton) or 'hybrid' (Ambati et al.)")
        _require(self.split_mode == "full" or self.split != "none", s, "split_mode",
                 self.split_mode, "'hybrid' needs a split: set material.split = 'amor' or 'miehe'")
        _require(math.isnan(self.strength) or (self.strength > 0 and math.isfinite(self.strength)),
                 s, "strength", self.strength, "the tensile strength f_t must be > 0")

    @property
    def moduli(self) -> tuple[str, ...]:
        """The elastic moduli the scene gives, in field order (mu, lam, E, nu)."""
        return tuple(k for k in ("mu", "lam", "E", "nu") if not math.isnan(getattr(self, k)))

    @property
    def lame(self) -> tuple[float, float]:
        """The 3D Lame constants (lambda, mu); from E, nu:
        ``lambda = E nu / ((1 + nu)(1 - 2 nu))``, ``mu = E / (2 (1 + nu))``."""
        if self.moduli == ("E", "nu"):
            E, nu = self.E, self.nu
            return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
        if self.moduli == ("mu", "lam"):
            return self.lam, self.mu
        raise ValueError(f"material gives {self.moduli or 'no moduli'}, not lam and mu or E and nu")

    @property
    def young(self) -> float:
        """Young's modulus E: given, or ``mu (3 lam + 2 mu)/(lam + mu)``; with mu alone (mode
        III) mu itself, the modulus of the shear onset (PF-CZM's l_ch = mu G_f/f_t^2)."""
        if self.moduli == ("E", "nu"):
            return self.E
        if self.moduli == ("mu", "lam"):
            return self.mu * (3 * self.lam + 2 * self.mu) / (self.lam + self.mu)
        return self.shear_modulus

    @property
    def shear_modulus(self) -> float:
        """mu, from whichever moduli are given (1 when none is)."""
        if self.moduli == ("E", "nu"):
            return self.lame[1]
        return self.DEFAULT_MU if math.isnan(self.mu) else self.mu


@dataclass(frozen=True)
class PhaseField(_Section):
    """Parameters of the Ambrosio-Tortorelli gradient flow.

    ``alpha1 du/dt = div((1-z)^2 sigma) + f``, ``alpha2 dz/dt = (...)_+``; the u-stiffness is
    ``(1-z)^2 + residual_stiffness`` so the u-problem stays elliptic where z = 1. ``model``
    is the crack model, the surface term (:mod:`ngfrac.physics.crack_models`): ``"AT2"`` (the paper's),
    ``"AT1"`` (an elastic threshold) or ``"PF-CZM"`` (Wu's cohesive model: needs
    ``material.strength``; ``softening`` its law). ``drive`` is what drives z: ``"energy"``
    (sigma:e, or 2 psi+ with a split) or ``"rankine"`` (PF-CZM: ``<sigma_1>^2/E``).
    """

    SECTION: ClassVar[str] = "phase_field"
    epsilon: float = REQUIRED  # type: ignore[assignment]
    alpha2: float = REQUIRED  # type: ignore[assignment]
    alpha1: float = 0.0
    residual_stiffness: float = 1e-6
    model: str = "AT2"
    crack_pressure: Expression = Expression("0.0")
    """p(t) inside the crack (the pressurized-crack work term ``int p u.grad z``); 0 = none."""
    softening: str = "linear"
    """PF-CZM's softening law: "linear", "exponential" or "cornelissen"."""
    drive: str = "energy"
    """W of the z-equation: "energy" (sigma:e; 2 psi+ with a split) or "rankine" (PF-CZM)."""

    def validate(self) -> None:
        s = self.SECTION
        _require(self.crack_pressure.names <= {"t"}, s, "crack_pressure", self.crack_pressure.text,
                 "an expression in t only (a pressure uniform in the crack)")
        _require(self.epsilon > 0, s, "epsilon", self.epsilon, "the regularization length must be > 0")
        _require(self.alpha2 > 0, s, "alpha2", self.alpha2, "the time constant of z must be > 0")
        _require(self.alpha1 >= 0, s, "alpha1", self.alpha1, "must be >= 0 (0 = quasi-static u)")
        _require(0 < self.residual_stiffness < 1e-1, s, "residual_stiffness",
                 self.residual_stiffness, "must be in (0, 0.1); 1e-6 is typical")
        _require(self.model in CRACK_MODELS, s, "model", self.model,
                 f"choose {' or '.join(repr(m) for m in CRACK_MODELS)}")
        _require(self.softening in SOFTENING_LAWS, s, "softening", self.softening,
                 f"choose {' or '.join(repr(m) for m in SOFTENING_LAWS)}")
        _require(self.drive in ("energy", "rankine"), s, "drive", self.drive,
                 "choose 'energy' (sigma:e) or 'rankine' (<sigma_1>^2/E, PF-CZM)")
        _require(self.drive == "energy" or self.model == "PF-CZM", s, "drive", self.drive,
                 "'rankine' is PF-CZM's drive: set phase_field.model = 'PF-CZM'")

    @property
    def pressurized(self) -> bool:
        """Whether a crack pressure is set (``crack_pressure`` not the constant 0)."""
        p = self.crack_pressure
        return not (p.is_constant and p.value() == 0)


SHAPE_TYPES_2D = ("rectangle", "circle", "ellipse", "polygon")
"""``[[geometry.shapes]]`` types of a 2D OCC domain."""

SHAPE_TYPES_3D = ("box", "cylinder", "sphere")
"""``[[geometry.shapes]]`` types of a 3D OCC domain."""


@dataclass(frozen=True)
class Shape(_Section):
    """One ``[[geometry.shapes]]`` entry of an OCC domain, combined with those before it.

    ``rectangle``: ``corner = [x, y]``, ``size = [w, h]``. ``circle``: ``center``, ``radius``.
    ``ellipse``: ``center``, ``radii = [rx, ry]``. ``polygon``: ``points = [[x, y], ...]``.
    ``box``: ``corner = [x, y, z]``, ``size = [w, h, d]``. ``cylinder``: ``center`` (of the
    base), ``axis``, ``radius``, ``height``. ``sphere``: ``center``, ``radius``. ``op``:
    ``"add"`` (union), ``"cut"`` (difference: holes, notches) or ``"intersect"``.
    """

    SECTION: ClassVar[str] = "geometry.shapes"
    KEYS: ClassVar[dict[str, tuple[str, ...]]] = {
        "rectangle": ("corner", "size"), "circle": ("center", "radius"),
        "ellipse": ("center", "radii"), "polygon": ("points",), "box": ("corner", "size"),
        "cylinder": ("center", "axis", "radius", "height"), "sphere": ("center", "radius")}
    type: str = REQUIRED  # type: ignore[assignment]
    op: str = "add"
    corner: tuple[float, ...] = ()
    size: tuple[float, ...] = ()
    center: tuple[float, ...] = ()
    radius: float = 0.0
    radii: tuple[float, ...] = ()
    points: tuple[tuple[float, ...], ...] = ()
    axis: tuple[float, ...] = ()
    height: float = 0.0

    def validate(self) -> None:
        s = self.SECTION
        _require(self.type in self.KEYS, s, "type", self.type,
                 f"choose one of {', '.join(self.KEYS)}")
        _require(self.op in ("add", "cut", "intersect"), s, "op", self.op,
                 "choose 'add' (union), 'cut' (difference) or 'intersect'")
        needed = self.KEYS[self.type]
        for f in dataclasses.fields(self):
            if f.name in ("type", "op"):
                continue
            given = getattr(self, f.name) != f.default
            _require(given == (f.name in needed), s, f.name, getattr(self, f.name),
                     f"a {self.type} takes {', '.join(needed)}" if given
                     else f"a {self.type} needs {f.name}")
        n = self.dim
        for key in ("corner", "center", "axis"):
            if key in needed:
                _require(len(getattr(self, key)) == n, s, key, list(getattr(self, key)),
                         f"give {n} coordinates")
        for key in ("size", "radii"):
            if key in needed:
                _require(len(getattr(self, key)) == (2 if key == "radii" else n)
                         and min(getattr(self, key)) > 0, s, key, list(getattr(self, key)),
                         "give positive lengths, one per axis")
        for key in ("radius", "height"):
            if key in needed:
                _require(getattr(self, key) > 0, s, key, getattr(self, key), "must be > 0")
        if self.type == "polygon":
            _require(len(self.points) >= 3 and all(len(p) == 2 for p in self.points), s,
                     "points", [list(p) for p in self.points],
                     "a polygon needs at least three corners [[x, y], ...]")
        if self.type == "cylinder":
            _require(any(self.axis), s, "axis", list(self.axis), "the axis must not be zero")

    @property
    def dim(self) -> int:
        """2 for the plane shapes, 3 for the solids."""
        return 3 if self.type in SHAPE_TYPES_3D else 2


@dataclass(frozen=True)
class BoundarySelector(_Section):
    """One ``[[geometry.boundaries]]`` entry: ``name`` for the edges (2D) or faces (3D) that
    one selector picks: ``named`` (their name in the CAD file), ``box = [[x0, y0], [x1, y1]]``
    (those inside the box), ``point = [x, y]`` (those through the point, within ``tol``) or
    ``normal = [nx, ny]`` (straight edges, planar faces, with this outward normal)."""

    SECTION: ClassVar[str] = "geometry.boundaries"
    SELECTORS: ClassVar[tuple[str, ...]] = ("named", "box", "point", "normal")
    name: str = REQUIRED  # type: ignore[assignment]
    named: str = ""
    box: tuple[tuple[float, ...], ...] = ()
    point: tuple[float, ...] = ()
    normal: tuple[float, ...] = ()
    tol: float = 0.0
    """Distance tolerance of ``box`` and ``point``; 0: 1e-6 times the domain's diameter."""

    def validate(self) -> None:
        s = self.SECTION
        _require(bool(self.name) and self.name != "crack", s, "name", self.name,
                 "give a name other than '' and 'crack' (the initial cracks' edges)")
        given = [k for k in self.SELECTORS if getattr(self, k)]
        _require(len(given) == 1, s, "name", self.name,
                 f"give exactly one of {', '.join(self.SELECTORS)} (given: {', '.join(given) or 'none'})")
        if self.box:
            _require(len(self.box) == 2 and len(self.box[0]) == len(self.box[1]) in (2, 3), s,
                     "box", [list(p) for p in self.box], "give [[x0, y0], [x1, y1]] (3D: [x, y, z])")
        if self.normal:
            _require(any(self.normal), s, "normal", list(self.normal), "must not be zero")
        _require(self.tol >= 0, s, "tol", self.tol, "must be >= 0 (0: 1e-6 of the diameter)")

    def describe(self) -> str:
        """The selector as the scene writes it, for messages."""
        key = next(k for k in self.SELECTORS if getattr(self, k))
        value = getattr(self, key)
        text = repr(value) if isinstance(value, str) else str(_plain(value))
        return f"name = {self.name!r}, {key} = {text}"


@dataclass(frozen=True)
class Geometry(_Section):
    """The domain: an axis-parallel rectangle (2D) or box (3D), or a CAD shape (``occ``).

    ``rectangle``: [x0, x0 + width] x [y0, y0 + height], boundaries bottom (y = y0), right,
    top, left. ``box``: [x0, x0 + width] x [y0, y0 + height] x [z0, z0 + depth], faces left
    (x = x0), right (x = x0 + width), bottom (y = y0), top (y = y0 + height), back (z = z0),
    front (z = z0 + depth). ``occ``: ``[[geometry.shapes]]`` (:class:`Shape`) or a CAD
    ``file`` (STEP, BREP, IGES; times ``scale``), boundaries named by ``[[geometry.boundaries]]``
    (:class:`BoundarySelector`) and the file; the rest is ``default_boundary``
    (:mod:`ngfrac.geometry.cad`). ``split_points`` split boundary edges (2D) before they are named.
    """

    SECTION: ClassVar[str] = "geometry"
    KINDS: ClassVar[tuple[str, ...]] = ("rectangle", "box", "occ")
    OCC_KEYS: ClassVar[tuple[str, ...]] = ("shapes", "boundaries", "file", "scale",
                                           "default_boundary", "split_points")
    BOUNDARIES: ClassVar[tuple[str, ...]] = ("bottom", "right", "top", "left")
    BOUNDARIES_3D: ClassVar[tuple[str, ...]] = ("left", "right", "bottom", "top", "back", "front")
    width: float = math.nan
    """Required for a rectangle or a box."""
    height: float = math.nan
    kind: str = "rectangle"
    origin: tuple[float, ...] = (0.0, 0.0)
    depth: float = 0.0
    """Extent in z of a box; 0 (not given) for a rectangle."""
    mesh_size: float = 0.0
    """Uniform maximal element size; 0 means epsilon/2."""
    shapes: tuple[Shape, ...] = ()
    boundaries: tuple[BoundarySelector, ...] = ()
    file: str = ""
    scale: float = 1.0
    default_boundary: str = "free"
    split_points: tuple[tuple[float, ...], ...] = ()
    """Points on boundary edges of a 2D occ domain where an edge is split in two (e.g. a
    hole's circle into two arcs, so that selectors can name each)."""

    def validate(self) -> None:
        s = self.SECTION
        if self.kind in ("rectangle", "box"):
            for key in ("width", "height"):
                if math.isnan(getattr(self, key)):
                    raise SceneError(f"missing key {_key(s, key)!r}; it is required")
        _require(self.kind in self.KINDS, s, "kind", self.kind,
                 "choose 'rectangle' (2D), 'box' (3D) or 'occ' (CAD shapes or a file)")
        _require(self.mesh_size >= 0, s, "mesh_size", self.mesh_size,
                 "must be > 0 (or 0 for epsilon/2)")
        if self.kind == "occ":
            self._validate_occ()
            return
        for key in self.OCC_KEYS:
            value = getattr(self, key)
            _require(value == Geometry.__dataclass_fields__[key].default, s, key, _plain(value),
                     "only geometry.kind = 'occ' takes it")
        _require(self.width > 0, s, "width", self.width, "must be > 0")
        _require(self.height > 0, s, "height", self.height, "must be > 0")
        if self.kind == "box":
            if self.origin is Geometry.__dataclass_fields__["origin"].default:
                object.__setattr__(self, "origin", (0.0, 0.0, 0.0))  # not given: the 3D zero
            _require(len(self.origin) == 3, s, "origin", list(self.origin),
                     "a box needs [x, y, z]")
            _require(self.depth > 0, s, "depth", self.depth, "a box needs depth > 0")
        else:
            _require(len(self.origin) == 2, s, "origin", list(self.origin), "give [x, y]")
            _require(self.depth == 0, s, "depth", self.depth,
                     "only a box has a depth; set geometry.kind = 'box' or remove depth")

    def _validate_occ(self) -> None:
        """Shapes or a file, no rectangle keys; building the domain checks the selectors."""
        s = self.SECTION
        for key in ("width", "height", "depth"):
            value = getattr(self, key)
            _require(math.isnan(value) or value == 0, s, key, value,
                     "an occ domain takes its extent from its shapes or file; remove it")
        _require(self.origin == (0.0, 0.0), s, "origin", list(self.origin),
                 "an occ domain has no origin; move its shapes")
        _require(bool(self.shapes) != bool(self.file), s, "shapes",
                 [f"{shape.type}" for shape in self.shapes],
                 "give [[geometry.shapes]] or geometry.file, not both (nor neither)")
        _require(self.scale > 0, s, "scale", self.scale, "must be > 0")
        for point in self.split_points:
            _require(len(point) == 2, s, "split_points", [list(p) for p in self.split_points],
                     "give points [x, y] on the edges of a 2D domain")
        _require(bool(self.default_boundary) and self.default_boundary != "crack", s,
                 "default_boundary", self.default_boundary, "give a name other than '' and 'crack'")
        if self.shapes:
            _require(self.shapes[0].op == "add", s, "shapes[0].op", self.shapes[0].op,
                     "the first shape starts the domain: use op = 'add'")
            dims = {shape.dim for shape in self.shapes}
            _require(len(dims) == 1, s, "shapes", [shape.type for shape in self.shapes],
                     f"mix no plane shapes ({', '.join(SHAPE_TYPES_2D)}) with solids "
                     f"({', '.join(SHAPE_TYPES_3D)})")
        self.domain()  # raises SceneError for a selector that matches nothing or a conflict

    @property
    def dim(self) -> int:
        """2 for a rectangle, 3 for a box; an occ domain's own."""
        if self.kind == "occ":
            return self.domain().dim
        return 3 if self.kind == "box" else 2

    @property
    def extent(self) -> tuple[float, ...]:
        """(width, height) or (width, height, depth); an occ domain's bounding box."""
        if self.kind == "occ":
            return self.domain().extent
        return (self.width, self.height, self.depth)[: self.dim]

    @property
    def shortest_side(self) -> float:
        return min(self.extent)

    @property
    def boundary_names(self) -> tuple[str, ...]:
        if self.kind == "occ":
            return self.domain().boundary_names
        return self.BOUNDARIES_3D if self.dim == 3 else self.BOUNDARIES

    def domain(self) -> "Domain":
        """The domain this section describes: its
        boundary and containment tests, measure and sample points live there. An occ domain
        is built once per section (OCC work) and kept."""
        from ..geometry.domains import Box, Rectangle

        if self.kind == "box":
            return Box(self.width, self.height, self.depth, tuple(self.origin))
        if self.kind == "rectangle":
            return Rectangle(self.width, self.height, tuple(self.origin))
        built = self.__dict__.get("_domain")
        if built is None:
            built = occ_domain_of(self)
            object.__setattr__(self, "_domain", built)
        return built

    def __getstate__(self) -> dict[str, Any]:
        """Copies and pickles leave out the built occ domain (OCC shapes do not pickle);
        they build it again from ``shapes`` or ``file``."""
        return {k: v for k, v in self.__dict__.items() if k != "_domain"}

    IN_CODE: ClassVar[str] = "<shape in code>"
    """The ``file`` of a geometry made by :meth:`of_domain`."""

    @classmethod
    def of_domain(cls, domain: "Domain", mesh_size: float = 0.0) -> "Geometry":
        """An occ geometry section for a domain built in code (an
        :class:`~ngfrac.geometry.cad.OccDomain` of any netgen.occ shape), for a :class:`Scene`.

        Its ``file`` is :attr:`IN_CODE`: such a scene cannot be written to and read from TOML,
        and ``dataclasses.replace``, copies and pickles of this section lose the domain
        (``dataclasses.replace`` of the scene keeps the section and so the domain).
        """
        geometry = cls.__new__(cls)
        object.__setattr__(geometry, "_domain", domain)
        cls.__init__(geometry, kind="occ", file=cls.IN_CODE, mesh_size=mesh_size)
        return geometry

    def to_dict(self) -> dict[str, Any]:
        """The keys as a scene file writes them: no occ keys for a rectangle or box, none of
        a shape's or selector's keys at their defaults."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, float) and math.isnan(value):
                continue
            if f.name in self.OCC_KEYS and self.kind != "occ":
                continue
            if f.name in ("shapes", "boundaries"):
                value = [{g.name: _plain(getattr(item, g.name)) for g in dataclasses.fields(item)
                          if getattr(item, g.name) != g.default} for item in value]
            out[f.name] = _plain(value)
        return out


@dataclass(frozen=True)
class Crack(_Section):
    """An initial crack; the initial phase field is exp(-dist/epsilon).

    2D: a polyline ``[[x, y], ...]`` (at least two points, from the mouth to the tip).
    3D: a planar polygon ``[[x, y, z], ...]`` (at least three corners, in order around it);
    the crack is the filled polygon and dist the distance to it.
    """

    SECTION: ClassVar[str] = "cracks"
    PLANAR_TOL: ClassVar[float] = 1e-9
    points: tuple[tuple[float, ...], ...] = REQUIRED  # type: ignore[assignment]

    def validate(self) -> None:
        s = self.SECTION
        _require(len(self.points) >= 2, s, "points", self.points,
                 "a crack needs at least two points [[x0, y0], [x1, y1], ...]")
        dim = len(self.points[0])
        for point in self.points:
            _require(len(point) in (2, 3) and len(point) == dim, s, "points", list(point),
                     "each point is [x, y] (2D) or [x, y, z] (3D), all of the same length")
        if dim == 3:
            _require(len(self.points) >= 3, s, "points", [list(p) for p in self.points],
                     "a 3D crack is a planar polygon with at least three corners [[x, y, z], ...]")
            corners = np.asarray(self.points, dtype=float)
            normal = self.normal
            size = float(np.ptp(corners, axis=0).max())
            _require(float(np.linalg.norm(normal)) > 0, s, "points",
                     [list(p) for p in self.points],
                     "the polygon has no area; give corners that span a plane")
            offsets = np.abs((corners - corners[0]) @ normal)
            _require(offsets.max() <= self.PLANAR_TOL * size, s, "points",
                     [list(p) for p in self.points],
                     f"a 3D crack must be planar (a corner is {offsets.max():.3g} off the plane "
                     "of the others)")

    @property
    def dim(self) -> int:
        return len(self.points[0])

    @property
    def normal(self) -> np.ndarray:
        """Unit normal of a 3D polygon (Newell's method); zeros if it has no area."""
        corners = np.asarray(self.points, dtype=float)
        nxt = np.roll(corners, -1, axis=0)
        normal = 0.5 * np.cross(corners, nxt).sum(axis=0)
        length = float(np.linalg.norm(normal))
        scale = float(np.ptp(corners, axis=0).max()) ** 2
        return normal / length if length > 1e-12 * scale else np.zeros(3)


LOAD_KINDS = ("displacement", "traction", "pressure")
"""What a load prescribes on its boundary (``loads[i].kind``)."""


@dataclass(frozen=True)
class Load(_Section):
    """A load on one named boundary, expressions in x, y, t (3D also z).

    ``kind = "displacement"`` (the default): a Dirichlet displacement. Mode III: one
    expression, ``value = "10*t"``. Plane models: one per component, ``value = ["0", "10*t"]``;
    ``"free"`` leaves a component unconstrained (rollers: ``value = ["free", "0"]``).
    ``kind = "traction"``: a Neumann traction sigma n = value, of the same shape as a
    displacement (no ``"free"``). ``kind = "pressure"``: one expression p, the traction
    -p n (plane and 3D models).
    """

    SECTION: ClassVar[str] = "loads"
    boundary: str = REQUIRED  # type: ignore[assignment]
    value: Expression | Components = REQUIRED  # type: ignore[assignment]
    kind: str = "displacement"

    def validate(self) -> None:
        s = self.SECTION
        _require(self.kind in LOAD_KINDS, s, "kind", self.kind,
                 f"choose {', '.join(repr(k) for k in LOAD_KINDS)}")
        if self.kind == "pressure":
            _require(not isinstance(self.value, Components), s, "value", _plain_value(self.value),
                     "a pressure is one expression p(x, y, t) (it acts as -p n), not a list")
        if isinstance(self.value, Components):
            _require(len(self.value) > 0, s, "value", [], "give [ux, uy]")
            if self.kind == "traction":
                _require(not any(self.value.free), s, "value", self.value.text,
                         "a traction gives every component (use \"0\", not \"free\")")
            _require(not all(self.value.free), s, "value", self.value.text,
                     "every component is free, so the load constrains nothing; remove it")

    @property
    def is_dirichlet(self) -> bool:
        """Whether the load prescribes u (``kind = "displacement"``)."""
        return self.kind == "displacement"

    @property
    def free(self) -> tuple[bool, ...]:
        """Which components are left free (mode III: never; a traction or pressure prescribes
        no component of u, so all are free)."""
        if not self.is_dirichlet:
            n = len(self.value) if isinstance(self.value, Components) else 1
            return (True,) * n
        return self.value.free if isinstance(self.value, Components) else (False,)


def _plain_value(value: Expression | Components) -> Any:
    return [str(e) for e in value] if isinstance(value, Components) else value.text


@dataclass(frozen=True)
class TimeSettings(_Section):
    """Time steps on the grid t = n dt (n an integer), up to t_end.

    Fixed: every step is dt. ``adaptive = true``: a step is dt 2^j with 0 <= j <=
    ``max_doublings``; it doubles while the largest change of z at a node stays below
    ``dz_target``/4 and halves (the step is redone) when it exceeds ``dz_target``. Steps of
    2^j dt start at multiples of 2^j dt, so every multiple of dt_max = dt 2^max_doublings (the
    output times) is hit exactly and times stay exact products.
    """

    SECTION: ClassVar[str] = "time"
    dt: float = REQUIRED  # type: ignore[assignment]
    t_end: float = REQUIRED  # type: ignore[assignment]
    adaptive: bool = False
    max_doublings: int = 4
    dz_target: float = 0.01

    def validate(self) -> None:
        s = self.SECTION
        _require(self.dt > 0, s, "dt", self.dt, "the time step must be > 0")
        _require(self.t_end > 0, s, "t_end", self.t_end, "the end time must be > 0")
        _require(0 <= self.max_doublings <= 12, s, "max_doublings", self.max_doublings,
                 "must be in 0..12 (the largest step is dt * 2**max_doublings)")
        _require(0 < self.dz_target <= 1, s, "dz_target", self.dz_target, "must be in (0, 1]")

    @property
    def n_ticks(self) -> int:
        """End of the run on the grid t = n dt: t_end/dt rounded up."""
        return max(1, math.ceil(self.t_end / self.dt - 1e-9))

    @property
    def n_steps(self) -> int:
        """Number of steps of a fixed-step run (an upper bound for an adaptive one)."""
        return self.n_ticks

    @property
    def output_ticks(self) -> int:
        """Grid points between two output times of an adaptive run (1 for fixed steps)."""
        return 2 ** self.max_doublings if self.adaptive else 1


Z_UPDATES = ("auto", "projection", "descent", "obstacle")
"""The values of ``discretization.z_update``."""


@dataclass(frozen=True)
class Discretization(_Section):
    """Finite elements and solvers.

    ``order`` is the polynomial order of u; ``order_z`` that of z (1 or 2: the bounds and
    the non-repair condition are enforced at the Lagrange nodes, which is exact for P1/P2).
    ``coupling = "paper"`` solves z with the previous u (the paper's eq. 7);
    ``"staggered"`` uses the u just computed. ``z_update = "projection"`` is the paper's
    ``z = min(1, max(z_trial, z_old))`` at the nodes; ``"descent"`` moves from z_old towards
    that projection only as far as the z-step's quadratic energy keeps decreasing (exact line
    search, never worse than z_old), which with ``coupling = "staggered"`` makes every step
    an energy descent; ``"obstacle"`` minimizes the z-step's energy under ``z >= z_old``
    (an active-set method); ``"auto"`` (the default) is the crack model's choice:
    ``"projection"`` for AT2 and ``"obstacle"`` for AT1. ``threaded_solves = false`` (the
    default) runs factorizations and solves outside NGSolve's TaskManager so that a run is
    bitwise reproducible with any thread count (:mod:`ngfrac.fem.threads`); ``true``
    threads them too. ``concurrent_substeps = true`` runs the u- and the z-sub-step of a step
    at the same time, each on one core with one NGSolve thread (with ``coupling = "paper"``
    they are independent: z uses the previous u); bitwise the same results as one thread,
    for two cores (docs/benchmarks.md, section 13). Serial on a distributed (MPI) mesh and
    with a tension/compression split.
    """

    SECTION: ClassVar[str] = "discretization"
    order: int = 2
    order_z: int = 0
    u_solver: str = "sparsecholesky"
    z_solver: str = "sparsecholesky"
    coupling: str = "paper"
    z_update: str = "auto"
    threaded_solves: bool = False
    concurrent_substeps: bool = False

    def validate(self) -> None:
        s = self.SECTION
        _require(not self.concurrent_substeps or self.coupling == "paper", s,
                 "concurrent_substeps", True, "it needs coupling = 'paper' (with 'staggered' "
                 "the z-sub-step waits for the new u)")
        _require(not (self.concurrent_substeps and self.threaded_solves), s,
                 "concurrent_substeps", True, "threaded_solves = true excludes it (the two "
                 "sub-steps on one NGSolve thread each, or one after the other on all)")
        _require(1 <= self.order <= 6, s, "order", self.order, "must be an integer in 1..6")
        _require(self.order_z in (0, 1, 2), s, "order_z", self.order_z,
                 "must be 1 or 2 (0 = min(order, 2))")
        _require(self.u_solver in ("sparsecholesky", "umfpack", "cg"), s, "u_solver",
                 self.u_solver, "choose 'sparsecholesky', 'umfpack' or 'cg' (with BDDC)")
        _require(self.z_solver in ("cg", "sparsecholesky", "umfpack"), s, "z_solver",
                 self.z_solver, "choose 'cg', 'sparsecholesky' or 'umfpack'")
        _require(self.coupling in ("paper", "staggered"), s, "coupling", self.coupling,
                 "choose 'paper' (z uses the previous u) or 'staggered' (z uses the new u)")
        _require(self.z_update in Z_UPDATES, s, "z_update", self.z_update,
                 "choose 'auto', 'projection' (the paper's min(1, max(z_trial, z_old))), "
                 "'descent' (the projection, shortened where it would raise the z-step's "
                 "energy) or 'obstacle' (the z-step minimized under z >= z_old)")

    @property
    def z_order(self) -> int:
        return self.order_z or min(self.order, 2)


VTK_FORMATS = ("auto", "subdivided", "vertices")
"""Values of ``output.vtk_format``."""


@dataclass(frozen=True)
class Output(_Section):
    """What to write and how often (0 = never; for VTK: only the last step)."""

    SECTION: ClassVar[str] = "output"
    vtk_every: int = 10
    history_every: int = 1
    vtk_subdivision: int = -1
    """Subdivision of each element in VTK files; -1 means order - 1."""
    vtk_format: str = "auto"
    """``"subdivided"``: NGSolve's ASCII output, each element refined ``vtk_subdivision``
    times (P2 fields faithfully); ``"vertices"``: compressed binary, one point per vertex,
    other fields at the element centroids (fast, small); ``"auto"``: vertices in 3D, subdivided in
    2D."""
    checkpoint_every: int = 50
    """A checkpoint (checkpoint.h5, written atomically) every N steps; 0 = never."""
    results: bool = True
    """Write results.h5 (history and field snapshots with their meshes, at the VTK steps)."""

    def validate(self) -> None:
        s = self.SECTION
        _require(self.vtk_every >= 0, s, "vtk_every", self.vtk_every,
                 "must be >= 0 (0: only the last step)")
        _require(self.history_every >= 1, s, "history_every", self.history_every, "must be >= 1")
        _require(-1 <= self.vtk_subdivision <= 5, s, "vtk_subdivision", self.vtk_subdivision,
                 "must be in -1..5 (-1 = order - 1)")
        _require(self.checkpoint_every >= 0, s, "checkpoint_every", self.checkpoint_every,
                 "must be >= 0 (0 = never)")
        _require(self.vtk_format in VTK_FORMATS, s, "vtk_format", self.vtk_format,
                 f"choose one of {', '.join(repr(f) for f in VTK_FORMATS)}")


SIZE_FIELDS = ("bands", "equidistributed")
"""Values of ``adaptivity.size_field``."""


@dataclass(frozen=True)
class Adaptivity(_Section):
    """Mesh adaptation driven by an a-posteriori estimator on z (refinement and coarsening).

    Sizes are 0 for "derived from epsilon": ``h_crack`` (where z >= 0.9, the crack core)
    defaults to max(hmin, epsilon/10), ``h_band`` (where z >= 0.1) to epsilon/4, ``h_tip``
    (within ``tip_margin`` of the tip) to h_band, ``hmax`` to a tenth of the shorter side,
    ``tip_margin`` to 4 epsilon. ``tip_lane`` (2D) also asks for h_crack in a wedge of length
    ``tip_margin`` ahead of the tip along the crack, so the core runs in fine elements.
    ``relax_core`` (off by default; on in the SENT/SENS demos): after a transfer, one
    z-sub-step at the transferred u restores the open crack (kept where z >= 1/2 and the
    sub-step gives z >= 0.95, outside the tip disc), which interpolation at the new nodes
    lowers where they miss its ridge, so force curves do not jump after a mesh change.

    ``size_field`` says where the sizes come from: ``"bands"`` (the default) equidistributes
    the estimator and then asks for h_crack in the core, h_band in the band and the tip lane,
    and under the cap coarsens the coarsest parts first; ``"equidistributed"`` keeps only the
    estimator's equidistribution (on size levels) and the tip disc, and under the cap scales
    every size alike (the Fig. 2 demo's setting; docs/benchmarks.md, section 11, compares them).
    """

    SECTION: ClassVar[str] = "adaptivity"
    enabled: bool = False
    estimator: str = "zz"
    every: int = 1
    max_vertices: int = 5000
    hmin: float = 2e-3
    hmax: float = 0.0
    h_crack: float = 0.0
    h_band: float = 0.0
    h_tip: float = 0.0
    tip_margin: float = 0.0
    tip_lane: bool = True
    relax_core: bool = False
    size_field: str = "bands"

    def validate(self) -> None:
        s = self.SECTION
        _require(self.estimator in ("zz", "residual"), s, "estimator", self.estimator,
                 "choose 'zz' or 'residual'")
        _require(self.size_field in SIZE_FIELDS, s, "size_field", self.size_field,
                 "choose 'bands' or 'equidistributed'")
        _require(self.every >= 1, s, "every", self.every, "must be >= 1 (steps between checks)")
        _require(self.max_vertices >= 100, s, "max_vertices", self.max_vertices, "must be >= 100")
        _require(self.hmin > 0, s, "hmin", self.hmin, "must be > 0")
        for name in ("hmax", "h_crack", "h_band", "h_tip", "tip_margin"):
            value = getattr(self, name)
            _require(value >= 0, s, name, value, "must be >= 0 (0 = derived from epsilon)")
        _require(self.hmax == 0 or self.hmax >= self.hmin, s, "hmax", self.hmax, "must be >= hmin")


SECTIONS: dict[str, type] = {
    "model": Model, "material": Material, "phase_field": PhaseField, "geometry": Geometry,
    "time": TimeSettings, "discretization": Discretization, "output": Output,
    "adaptivity": Adaptivity,
}
LISTS: dict[str, type] = {"cracks": Crack, "loads": Load}


@dataclass(frozen=True)
class Scene:
    """A complete, validated run description. Build it with :func:`load_scene`,
    :meth:`Scene.from_dict` or in code: sections may be given as dicts of their keys, loads and
    cracks as lists, and every section coerces plain numbers, strings and lists. Validation
    also refuses crack geometry Netgen cannot mesh (:func:`ngfrac.scene.checks.crack_problems`) and
    expressions that are NaN or infinite on their boundary or domain for 0 <= t <= t_end.
    ``dataclasses.replace`` returns a new scene, validated again."""

    name: str
    geometry: Geometry
    phase_field: PhaseField
    time: TimeSettings
    loads: tuple[Load, ...]
    cracks: tuple[Crack, ...] = ()
    model: Model = field(default_factory=Model)
    material: Material = field(default_factory=Material)
    discretization: Discretization = field(default_factory=Discretization)
    output: Output = field(default_factory=Output)
    adaptivity: Adaptivity = field(default_factory=Adaptivity)
    units: str = SCENE_UNITS
    """The unit system of the scene's numbers (:data:`ngfrac.scene.units.UNIT_SYSTEMS`): labels
    and units attributes only, the computation is the same."""

    def __post_init__(self) -> None:
        self._coerce_sections()
        try:
            unit_system(self.units)
        except ValueError as err:
            raise SceneError(str(err)) from None
        names = self.geometry.boundary_names
        self._check_dimension()
        if not any(load.is_dirichlet for load in self.loads):
            raise SceneError("loads: a scene needs at least one [[loads]] entry with kind = "
                             "'displacement' (a Dirichlet boundary); tractions alone leave u "
                             "undetermined up to a rigid motion")
        seen = set()
        for i, load in enumerate(self.loads):
            if load.boundary not in names:
                close = difflib.get_close_matches(load.boundary, names, n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else ""
                raise SceneError(f"loads[{i}].boundary = {load.boundary!r} is not a boundary of the "
                                 f"geometry{hint}; boundaries are {', '.join(names)}")
            if load.boundary in seen:
                raise SceneError(f"loads[{i}].boundary = {load.boundary!r} is loaded twice")
            seen.add(load.boundary)
            if "z" in load.value.names and self.geometry.dim == 2:
                raise SceneError(f"loads[{i}].value = {load.value.text!r} uses z, but the domain is 2D")
        if "z" in self.material.body_force.names and self.geometry.dim == 2:
            raise SceneError(f"material.body_force = {self.material.body_force.text!r} uses z, "
                             "but the domain is 2D")
        self.model.check(self.material, self.loads)
        self._check_constrained()
        self._check_split()
        for i, crack in enumerate(self.cracks):
            if crack.dim != self.geometry.dim:
                example = "[[x, y, z], ...] (a planar polygon)" if self.geometry.dim == 3 else "[[x, y], ...]"
                raise SceneError(f"cracks[{i}].points = {[list(p) for p in crack.points]} has "
                                 f"{crack.dim}D points, but geometry.kind = {self.geometry.kind!r} "
                                 f"is {self.geometry.dim}D: give {example}")
            domain = self.geometry.domain()
            for point in crack.points:
                if not domain.contains(point, tol=1e-12):
                    raise SceneError(f"cracks[{i}].points: point {list(point)} lies outside the "
                                     f"domain {self._domain_text()}")
        normals = [c.normal for c in self.cracks] if self.geometry.dim == 3 else []
        for problem in crack_problems(self.geometry, [c.points for c in self.cracks], normals):
            raise SceneError(problem)
        self._check_gamma_positive()
        self._check_crack_model()
        self._check_finite_expressions()

    def _coerce_sections(self) -> None:
        """Sections given as tables (dicts) are built; lists of loads and cracks become tuples."""
        if not isinstance(self.name, str):
            raise SceneError(f"name = {self.name!r} must be a string")
        for section, cls in SECTIONS.items():
            value = getattr(self, section)
            if isinstance(value, Mapping):
                object.__setattr__(self, section, _build(cls, value, section))
            elif not isinstance(value, cls):
                raise SceneError(f"{section} = {value!r} must be a {cls.__name__} (or a table of "
                                 "its keys)")
        for section, cls in LISTS.items():
            items = getattr(self, section)
            if isinstance(items, (cls, Mapping, str)) or not isinstance(items, (list, tuple)):
                raise SceneError(f"{section} = {items!r} must be a list of {cls.__name__}")
            built = []
            for i, item in enumerate(items):
                if isinstance(item, Mapping):
                    item = _build(cls, item, f"{section}[{i}]")
                elif not isinstance(item, cls):
                    raise SceneError(f"{section}[{i}] = {item!r} must be a {cls.__name__} (or a "
                                     "table of its keys)")
                built.append(item)
            if not isinstance(items, tuple) or any(a is not b for a, b in zip(built, items)):
                object.__setattr__(self, section, tuple(built))

    def _check_finite_expressions(self) -> None:
        """Loads on their boundary, the body force in the domain, at a few times in [0, t_end]."""
        times = check_times(self.time.n_ticks * self.time.dt)
        checks = []
        for i, load in enumerate(self.loads):
            where = self.geometry.domain().boundary_points(load.boundary)
            checks.append((f"loads[{i}].value", load.value, where, f"on boundary {load.boundary!r}"))
        checks.append(("material.body_force", self.material.body_force,
                       self.geometry.domain().sample_points(), "in the domain"))
        for key, value, where, place in checks:
            parts = value if isinstance(value, Components) else (value,)
            for k, part in enumerate(parts):
                if not isinstance(part, Expression):
                    continue  # "free"
                bad = nonfinite_value(part, where, times)
                if bad:
                    name = f"{key}[{k}]" if isinstance(value, Components) else key
                    raise SceneError(f"{name} = {part.text!r} is {bad} {place}: an expression must "
                                     f"be finite for 0 <= t <= t_end")

    def _check_dimension(self) -> None:
        """A 3D model needs a box (a solid), a box (a solid) needs a 3D model."""
        kind, geometry = self.model.kind, self.geometry.kind
        if geometry == "occ":
            self._check_occ_dimension()
            return
        if kind in MODELS_3D and self.geometry.dim != 3:
            raise SceneError(f"model.kind = {kind!r} is 3D but geometry.kind = {geometry!r} is 2D; "
                             "set geometry.kind = 'box' (with depth)")
        if kind not in MODELS_3D and self.geometry.dim == 3:
            raise SceneError(f"geometry.kind = {geometry!r} is 3D but model.kind = {kind!r} is 2D; "
                             f"set model.kind = {MODELS_3D[0]!r}")

    def _check_occ_dimension(self) -> None:
        """A CAD file or shapes of the other dimension than the model's."""
        kind, dim = self.model.kind, self.geometry.dim
        source = f"geometry.file = {self.geometry.file!r}" if self.geometry.file else "geometry.shapes"
        models_2d = ", ".join(repr(k) for k in MODELS if k not in MODELS_3D)
        if kind in MODELS_3D and dim != 3:
            raise SceneError(f"{source} is 2D (faces, no solid) but model.kind = {kind!r} is 3D; "
                             f"give a solid or a 2D model.kind ({models_2d})")
        if kind not in MODELS_3D and dim == 3:
            raise SceneError(f"{source} is 3D (a solid) but model.kind = {kind!r} is 2D; set "
                             f"model.kind = {MODELS_3D[0]!r} or give a planar face in z = 0")

    def _check_constrained(self) -> None:
        """Quasi-static u (alpha1 = 0) needs every component of u prescribed on some boundary;
        otherwise a rigid translation solves the homogeneous problem (a singular matrix)."""
        if self.phase_field.alpha1 > 0:
            return  # the alpha1/dt mass term makes the u-problem definite
        dirichlet = [load for load in self.loads if load.is_dirichlet]
        names = ("z",) if self.model.n_components == 1 else "xyz"[: self.model.n_components]
        for i, c in enumerate(names):
            if all(load.free[i] for load in dirichlet):
                raise SceneError(f"loads: u{c} is prescribed on no boundary (every displacement "
                                 f"load leaves it 'free'), so with phase_field.alpha1 = 0 the "
                                 "u-problem is singular; prescribe it on one boundary")

    def _check_split(self) -> None:
        """A split (ngfrac.physics.splits) and a crack pressure need a vector model."""
        split, kind = self.material.split, self.model.kind
        if self.phase_field.pressurized and kind == "mode3":
            raise SceneError(f"phase_field.crack_pressure = {self.phase_field.crack_pressure.text!r} "
                             "needs a plane or 3D model: mode III has no opening")
        if split != "none" and kind == "mode3":
            raise SceneError(f"material.split = {split!r} needs a plane or 3D model, but "
                             "model.kind = 'mode3' has no tension or compression: set split = 'none'")

    def _check_crack_model(self) -> None:
        """PF-CZM needs a strength, a constant toughness and eps below its limit; the Rankine
        drive an isotropic u-step."""
        pf, material = self.phase_field, self.material
        if pf.drive == "rankine" and material.split != "none" and material.split_mode == "full":
            raise SceneError(f"phase_field.drive = 'rankine' takes the isotropic u-step, but "
                             f"material.split = {material.split!r} degrades psi+ only: set "
                             "material.split = 'none' or material.split_mode = 'hybrid'")
        if pf.model != "PF-CZM":
            return
        if math.isnan(material.strength):
            raise SceneError("material.strength is missing: phase_field.model = 'PF-CZM' needs "
                             "the tensile strength f_t > 0")
        if not material.gamma.is_constant:
            raise SceneError(f"material.gamma = {material.gamma.text!r} is not allowed with "
                             "phase_field.model = 'PF-CZM': its a1 = 4 E G_f/(pi eps f_t^2) "
                             "needs one G_f; give a number")
        try:
            PFCZM(material.young, material.gamma.value(), material.strength, pf.epsilon,
                  pf.softening)
        except ValueError:
            limit = PFCZM(material.young, material.gamma.value(), material.strength,
                          1e-300, pf.softening).epsilon_limit()
            raise SceneError(f"phase_field.epsilon = {pf.epsilon!r} is not allowed: PF-CZM with "
                             f"the {pf.softening} law needs epsilon <= {limit:.4g} (g convex; "
                             "4 l_ch/(pi a1_min), l_ch = E G_f/f_t^2): lower it") from None

    def _domain_text(self) -> str:
        if self.geometry.kind == "occ":
            return "(the occ shape)"
        return " x ".join(f"[{o}, {o + e}]" for o, e in zip(self.geometry.origin, self.geometry.extent))

    def _check_gamma_positive(self) -> None:
        gamma = self.material.gamma
        dim = self.geometry.dim
        if "z" in gamma.names and dim == 2:
            raise SceneError(f"material.gamma = {gamma.text!r} uses z, but the domain is 2D")
        coordinates = self.geometry.domain().sample_points()
        names = "xyz"[:dim]
        values = np.broadcast_to(gamma.evaluate_numpy(dict(zip(names, coordinates))),
                                 coordinates[0].shape)
        bad = nonfinite_value(gamma, coordinates)
        if bad:
            raise SceneError(f"material.gamma = {gamma.text!r} is {bad} in the domain: the "
                             "toughness must be finite and > 0 everywhere")
        worst = int(np.argmin(values))
        if values[worst] <= 0:
            where = ", ".join(f"{c[worst]:.3g}" for c in coordinates)
            raise SceneError(f"material.gamma = {gamma.text!r} is {values[worst]:.3g} <= 0 at "
                             f"({', '.join(names)}) = ({where}); the toughness must be "
                             "> 0 everywhere")

    @property
    def mesh_size(self) -> float:
        """Maximal element size of the uniform mesh."""
        return self.geometry.mesh_size or self.phase_field.epsilon / 2

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], name: str = "scene") -> "Scene":
        """Validate a nested mapping (as read from TOML) into a Scene."""
        if not isinstance(data, Mapping):
            raise SceneError("a scene must be a table of sections")
        allowed = ["name", "units", *SECTIONS, *LISTS]
        for key in data:
            if key not in allowed:
                raise SceneError(_unknown_key_message("", key, allowed))
        kwargs: dict[str, Any] = {"name": str(data.get("name", name)),
                                  "units": data.get("units", SCENE_UNITS)}
        for section, section_cls in SECTIONS.items():
            value = data.get(section, {})
            if section_cls in (Geometry, PhaseField, TimeSettings) and section not in data:
                raise SceneError(f"missing section [{section}]; it is required")
            kwargs[section] = _build(section_cls, value, section)
        for section, item_cls in LISTS.items():
            items = data.get(section, [])
            if isinstance(items, Mapping):
                items = [items]
            if not isinstance(items, list):
                raise SceneError(f"{section} must be an array of tables ([[{section}]])")
            kwargs[section] = tuple(_build(item_cls, item, f"{section}[{i}]")
                                    for i, item in enumerate(items))
        return cls(**kwargs)

    def to_dict(self) -> dict[str, Any]:
        """The resolved scene as plain TOML-able data (defaults filled in)."""
        def plain(value: Any) -> Any:
            if isinstance(value, Expression):
                return value.text
            if isinstance(value, tuple):
                return [plain(v) for v in value]
            return value

        def section(obj: Any) -> dict[str, Any]:
            values = {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}
            # NaN marks an optional number the scene did not give (material moduli)
            return {k: plain(v) for k, v in values.items()
                    if not (isinstance(v, float) and math.isnan(v))}

        out: dict[str, Any] = {"name": self.name, "units": self.units}
        for name in SECTIONS:
            out[name] = section(getattr(self, name))
        out["geometry"] = self.geometry.to_dict()
        for name in LISTS:
            out[name] = [section(item) for item in getattr(self, name)]
        return out


def _unknown_key_message(section: str, key: str, allowed: list[str]) -> str:
    close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.5)
    hint = f"; did you mean {_key(section, close[0])!r}?" if close else ""
    return f"unknown key {_key(section, key)!r}{hint} (valid keys: {', '.join(allowed)})"


def _build(cls: type, data: Any, section: str) -> Any:
    """Check keys and types of one table, then construct (which checks ranges)."""
    if not isinstance(data, Mapping):
        raise SceneError(f"[{section}] must be a table, got {data!r}")
    hints = get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    for key in data:
        if key not in fields:
            raise SceneError(_unknown_key_message(section, key, list(fields)))
    kwargs = {}
    for name, f in fields.items():
        if name in data:
            kwargs[name] = _convert(data[name], hints[name], _key(section, name))
        elif f.default is REQUIRED:
            raise SceneError(f"missing key {_key(section, name)!r}; it is required")
    try:
        return cls(**kwargs)
    except SceneError as err:
        prefix = getattr(cls, "SECTION", "") + "."
        message = str(err)
        if section + "." != prefix and message.startswith(prefix):  # name the list entry
            raise SceneError(section + "." + message[len(prefix):]) from None
        raise
    except (TypeError, ValueError) as err:
        raise SceneError(f"[{section}]: {err}") from None


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return get_type_hints(cls)


def _has_type(value: Any, hint: Any, default: Any) -> bool:
    """Whether a field value is already of its field's type (then it is kept as it is)."""
    def number(v: Any) -> bool:
        return isinstance(v, float) and math.isfinite(v)

    if hint is float:
        return number(value) or (isinstance(default, float) and math.isnan(default)
                                 and isinstance(value, float) and math.isnan(value))
    if hint in (int, bool, str):
        return type(value) is hint
    if hint is Expression:
        return isinstance(value, Expression)
    if hint == Expression | Components:
        return isinstance(value, (Expression, Components))
    if hint == tuple[float, ...]:
        return isinstance(value, tuple) and all(number(v) for v in value)
    if _table_class(hint) is not None:
        return isinstance(value, tuple) and all(isinstance(v, _table_class(hint)) for v in value)
    if hint == tuple[tuple[float, ...], ...]:
        return isinstance(value, tuple) and all(
            isinstance(p, tuple) and all(number(v) for v in p) for p in value)
    return False


def _table_class(hint: Any) -> type | None:
    """The section class of a field that is a list of tables (``tuple[Shape, ...]``)."""
    args = getattr(hint, "__args__", ())
    if getattr(hint, "__origin__", None) is tuple and len(args) == 2 and args[1] is Ellipsis \
            and isinstance(args[0], type) and issubclass(args[0], _Section):
        return args[0]
    return None


def _plain(value: Any) -> Any:
    """Tuples and numpy values as the lists and Python scalars TOML gives."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def _coerce(value: Any, hint: Any, key: str, default: Any) -> Any:
    """A field value given in code (a number, a string, a list) as its field's type."""
    if _has_type(value, hint, default):
        return value
    return _convert(_plain(value), hint, key)


def _convert(value: Any, hint: Any, key: str) -> Any:
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SceneError(f"{key} = {value!r} must be a number")
        if not math.isfinite(value):
            raise SceneError(f"{key} = {value!r} must be a finite number")
        return float(value)
    if hint is bool:
        if not isinstance(value, bool):
            raise SceneError(f"{key} = {value!r} must be true or false")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise SceneError(f"{key} = {value!r} must be an integer")
        return value
    if hint is str:
        if not isinstance(value, str):
            raise SceneError(f"{key} = {value!r} must be a string")
        return value
    if hint == Expression | Components:
        return Components.of(value, key) if isinstance(value, list) else _convert(value, Expression, key)
    if hint is Expression:
        try:
            return Expression.of(value)
        except ExpressionError as err:
            raise SceneError(f"{key}: {err}") from None
    if hint == tuple[float, ...]:
        if not isinstance(value, list):
            raise SceneError(f"{key} = {value!r} must be a list of numbers")
        return tuple(_convert(v, float, key) for v in value)
    table = _table_class(hint)
    if table is not None:
        if isinstance(value, Mapping):
            value = [value]
        if not isinstance(value, list):
            raise SceneError(f"{key} must be an array of tables ([[{key}]])")
        return tuple(item if isinstance(item, table) else _build(table, item, f"{key}[{i}]")
                     for i, item in enumerate(value))
    if hint == tuple[tuple[float, ...], ...]:
        if not isinstance(value, list) or not all(isinstance(v, list) for v in value):
            raise SceneError(f"{key} = {value!r} must be a list of points [[x, y], ...] "
                             "(3D: [[x, y, z], ...])")
        return tuple(tuple(_convert(c, float, key) for c in v) for v in value)
    raise TypeError(f"no conversion for {hint}")  # a programming error, not user input


def occ_domain_of(geometry: "Geometry") -> "Domain":
    """The :class:`~ngfrac.geometry.cad.OccDomain` of a ``geometry.kind = "occ"`` section: its
    shapes or file, with the boundaries named by its selectors.

    Raises
    ------
    SceneError
        A selector matches nothing, two names claim one part, the file is missing or cannot
        be read, or the shapes (the file) leave no face or solid or several separate pieces.
    """
    from ..geometry.cad import (BoundaryConflict, EmptyShape, UnreadableFile, connected_pieces,
                      name_boundaries, read_shape, shape_from_specs, split_edges)

    try:
        shape = (read_shape(geometry.file, geometry.scale) if geometry.file
                 else shape_from_specs(geometry.shapes))
    except (FileNotFoundError, UnreadableFile) as err:
        raise SceneError(f"geometry.file = {geometry.file!r}: {err}") from None
    except EmptyShape as err:
        prefix = f"geometry.file = {geometry.file!r}: " if geometry.file else "geometry."
        raise SceneError(f"{prefix}{err}") from None
    except Exception as err:  # OCC raises plain Exceptions for bad shapes or files
        what = f"file = {geometry.file!r}" if geometry.file else "shapes"
        text = " ".join(str(err).split())  # one line: OCC's messages span several
        raise SceneError(f"geometry.{what}: OCC could not build the shape ({text})") from None
    pieces = connected_pieces(shape)
    if pieces > 1:  # each piece would need its own supports: a singular u-problem otherwise
        source = f"geometry.file = {geometry.file!r} holds" if geometry.file else "geometry.shapes make"
        raise SceneError(f"{source} {pieces} separate pieces (a cut through the domain, or a "
                         "shape that touches no other); ngfrac meshes one connected part: "
                         "join or remove the pieces")
    try:
        if geometry.split_points:
            shape = split_edges(shape, geometry.split_points)
        return name_boundaries(shape, geometry.boundaries, geometry.default_boundary)
    except BoundaryConflict as err:
        raise SceneError(str(err)) from None
