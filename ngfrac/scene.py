"""Scene: everything one run needs, as frozen dataclasses read from TOML.

A scene file has the sections ``[model]``, ``[material]``, ``[phase_field]``,
``[geometry]``, ``[[cracks]]``, ``[[loads]]``, ``[time]``, ``[discretization]``,
``[output]`` and ``[adaptivity]``; docs/scene.md lists every key. Each section is a frozen
dataclass that validates its own values; :class:`Scene` checks what spans sections (loads on
existing boundaries, cracks inside the domain, toughness positive everywhere).
Every problem raises :class:`SceneError` with one line that names the key, the value and
what is allowed.
"""
from __future__ import annotations

import dataclasses
import difflib
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, Mapping, get_type_hints

import numpy as np

from .expressions import Expression, ExpressionError

MODELS = ("mode3",)
"""Model names a scene may choose (``model.kind``)."""


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
    """Base of the scene sections: required keys first, then each section's own checks."""

    SECTION: ClassVar[str] = ""

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            if getattr(self, f.name) is REQUIRED:
                raise SceneError(f"missing key {_key(self.SECTION, f.name)!r}; it is required")
        self.validate()

    def validate(self) -> None:
        """Check value ranges; overridden by sections that have any."""


@dataclass(frozen=True)
class Model(_Section):
    """Which equations to solve."""

    SECTION: ClassVar[str] = "model"
    kind: str = "mode3"

    def validate(self) -> None:
        if self.kind not in MODELS:
            close = difflib.get_close_matches(self.kind, MODELS, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise SceneError(f"model.kind = {self.kind!r} is not a known model{hint}; "
                             f"choose one of {', '.join(MODELS)}")


@dataclass(frozen=True)
class Material(_Section):
    """Elastic moduli and fracture toughness.

    ``mu`` is the shear modulus (mode III uses only it); ``gamma`` is Griffith's G_c, a
    number or an expression in x, y; ``body_force`` is f in ``-div sigma = f``.
    """

    SECTION: ClassVar[str] = "material"
    mu: float = 1.0
    gamma: Expression = Expression("1.0")
    body_force: Expression = Expression("0.0")
    """Body force f (mode III: out of plane), an expression in x, y, t."""

    def validate(self) -> None:
        _require(self.mu > 0, self.SECTION, "mu", self.mu, "the shear modulus must be > 0")
        if "z" in self.body_force.names:
            raise SceneError(f"material.body_force = {self.body_force.text!r} uses z, but the domain is 2D")
        if "t" in self.gamma.names:
            raise SceneError(f"material.gamma = {self.gamma.text!r} may not depend on t")


@dataclass(frozen=True)
class PhaseField(_Section):
    """Parameters of the Ambrosio-Tortorelli gradient flow.

    ``alpha1 du/dt = div((1-z)^2 sigma) + f``, ``alpha2 dz/dt = (...)_+``; the u-stiffness is
    ``(1-z)^2 + residual_stiffness`` so the u-problem stays elliptic where z = 1.
    """

    SECTION: ClassVar[str] = "phase_field"
    epsilon: float = REQUIRED  # type: ignore[assignment]
    alpha2: float = REQUIRED  # type: ignore[assignment]
    alpha1: float = 0.0
    residual_stiffness: float = 1e-6

    def validate(self) -> None:
        s = self.SECTION
        _require(self.epsilon > 0, s, "epsilon", self.epsilon, "the regularization length must be > 0")
        _require(self.alpha2 > 0, s, "alpha2", self.alpha2, "the time constant of z must be > 0")
        _require(self.alpha1 >= 0, s, "alpha1", self.alpha1, "must be >= 0 (0 = quasi-static u)")
        _require(0 < self.residual_stiffness < 1e-1, s, "residual_stiffness",
                 self.residual_stiffness, "must be in (0, 0.1); 1e-6 is typical")


@dataclass(frozen=True)
class Geometry(_Section):
    """The domain: an axis-parallel rectangle with boundaries bottom, right, top, left."""

    SECTION: ClassVar[str] = "geometry"
    BOUNDARIES: ClassVar[tuple[str, ...]] = ("bottom", "right", "top", "left")
    width: float = REQUIRED  # type: ignore[assignment]
    height: float = REQUIRED  # type: ignore[assignment]
    kind: str = "rectangle"
    origin: tuple[float, ...] = (0.0, 0.0)
    mesh_size: float = 0.0
    """Uniform maximal element size; 0 means epsilon/2."""

    def validate(self) -> None:
        s = self.SECTION
        _require(self.kind == "rectangle", s, "kind", self.kind, "only 'rectangle' is available")
        _require(self.width > 0, s, "width", self.width, "must be > 0")
        _require(self.height > 0, s, "height", self.height, "must be > 0")
        _require(len(self.origin) == 2, s, "origin", list(self.origin), "give [x, y]")
        _require(self.mesh_size >= 0, s, "mesh_size", self.mesh_size,
                 "must be > 0 (or 0 for epsilon/2)")

    @property
    def boundary_names(self) -> tuple[str, ...]:
        return self.BOUNDARIES

    def contains(self, point: tuple[float, float], tol: float = 1e-12) -> bool:
        """Whether a point lies in the closed rectangle."""
        x0, y0 = self.origin
        px, py = point
        return (x0 - tol <= px <= x0 + self.width + tol) and (y0 - tol <= py <= y0 + self.height + tol)

    def sample_points(self, n: int = 201) -> tuple[np.ndarray, np.ndarray]:
        """A regular n-by-n grid over the rectangle, for checking expressions."""
        x0, y0 = self.origin
        xs, ys = np.meshgrid(np.linspace(x0, x0 + self.width, n), np.linspace(y0, y0 + self.height, n))
        return xs.ravel(), ys.ravel()


@dataclass(frozen=True)
class Crack(_Section):
    """An initial crack: a polyline; the initial phase field is exp(-dist/epsilon)."""

    SECTION: ClassVar[str] = "cracks"
    points: tuple[tuple[float, ...], ...] = REQUIRED  # type: ignore[assignment]

    def validate(self) -> None:
        _require(len(self.points) >= 2, self.SECTION, "points", self.points,
                 "a crack needs at least two points [[x0, y0], [x1, y1], ...]")
        for point in self.points:
            _require(len(point) == 2, self.SECTION, "points", point, "each point is [x, y]")


@dataclass(frozen=True)
class Load(_Section):
    """A Dirichlet displacement on one named boundary, an expression in x, y, t."""

    SECTION: ClassVar[str] = "loads"
    boundary: str = REQUIRED  # type: ignore[assignment]
    value: Expression = REQUIRED  # type: ignore[assignment]


@dataclass(frozen=True)
class TimeSettings(_Section):
    """Uniform time steps t_k = k dt up to t_end."""

    SECTION: ClassVar[str] = "time"
    dt: float = REQUIRED  # type: ignore[assignment]
    t_end: float = REQUIRED  # type: ignore[assignment]

    def validate(self) -> None:
        _require(self.dt > 0, self.SECTION, "dt", self.dt, "the time step must be > 0")
        _require(self.t_end > 0, self.SECTION, "t_end", self.t_end, "the end time must be > 0")

    @property
    def n_steps(self) -> int:
        """Number of steps: t_end/dt rounded up (a last step may end past t_end by < dt)."""
        return max(1, math.ceil(self.t_end / self.dt - 1e-9))


@dataclass(frozen=True)
class Discretization(_Section):
    """Finite elements and solvers.

    ``order`` is the polynomial order of u; ``order_z`` that of z (1 or 2: the bounds and
    the non-repair condition are enforced at the Lagrange nodes, which is exact for P1/P2).
    ``coupling = "paper"`` solves z with the previous u (the paper's eq. 7);
    ``"staggered"`` uses the u just computed.
    """

    SECTION: ClassVar[str] = "discretization"
    order: int = 2
    order_z: int = 0
    u_solver: str = "sparsecholesky"
    z_solver: str = "cg"
    coupling: str = "paper"

    def validate(self) -> None:
        s = self.SECTION
        _require(1 <= self.order <= 6, s, "order", self.order, "must be an integer in 1..6")
        _require(self.order_z in (0, 1, 2), s, "order_z", self.order_z,
                 "must be 1 or 2 (0 = min(order, 2))")
        _require(self.u_solver in ("sparsecholesky", "umfpack"), s, "u_solver", self.u_solver,
                 "choose 'sparsecholesky' or 'umfpack'")
        _require(self.z_solver in ("cg", "sparsecholesky", "umfpack"), s, "z_solver",
                 self.z_solver, "choose 'cg', 'sparsecholesky' or 'umfpack'")
        _require(self.coupling in ("paper", "staggered"), s, "coupling", self.coupling,
                 "choose 'paper' (z uses the previous u) or 'staggered' (z uses the new u)")

    @property
    def z_order(self) -> int:
        return self.order_z or min(self.order, 2)


@dataclass(frozen=True)
class Output(_Section):
    """What to write and how often (0 = never, except the final step for VTK)."""

    SECTION: ClassVar[str] = "output"
    vtk_every: int = 10
    history_every: int = 1
    vtk_subdivision: int = -1
    """Subdivision of each element in VTK files; -1 means order - 1."""

    def validate(self) -> None:
        s = self.SECTION
        _require(self.vtk_every >= 0, s, "vtk_every", self.vtk_every, "must be >= 0 (0 = never)")
        _require(self.history_every >= 1, s, "history_every", self.history_every, "must be >= 1")
        _require(-1 <= self.vtk_subdivision <= 5, s, "vtk_subdivision", self.vtk_subdivision,
                 "must be in -1..5 (-1 = order - 1)")


SECTIONS: dict[str, type] = {
    "model": Model, "material": Material, "phase_field": PhaseField, "geometry": Geometry,
    "time": TimeSettings, "discretization": Discretization, "output": Output,
}
LISTS: dict[str, type] = {"cracks": Crack, "loads": Load}


@dataclass(frozen=True)
class Scene:
    """A complete, validated run description. Build it with :func:`load_scene` or
    :meth:`Scene.from_dict`."""

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

    def __post_init__(self) -> None:
        names = self.geometry.boundary_names
        if not self.loads:
            raise SceneError("loads: a scene needs at least one [[loads]] entry (a Dirichlet boundary)")
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
            if "z" in load.value.names:
                raise SceneError(f"loads[{i}].value = {load.value.text!r} uses z, but the domain is 2D")
        for i, crack in enumerate(self.cracks):
            for point in crack.points:
                if not self.geometry.contains(point):
                    raise SceneError(f"cracks[{i}].points: point {list(point)} lies outside the "
                                     f"domain {self._domain_text()}")
        self._check_gamma_positive()

    def _domain_text(self) -> str:
        x0, y0 = self.geometry.origin
        return f"[{x0}, {x0 + self.geometry.width}] x [{y0}, {y0 + self.geometry.height}]"

    def _check_gamma_positive(self) -> None:
        gamma = self.material.gamma
        if "z" in gamma.names:
            raise SceneError(f"material.gamma = {gamma.text!r} uses z, but the domain is 2D")
        xs, ys = self.geometry.sample_points()
        values = np.broadcast_to(gamma.evaluate_numpy({"x": xs, "y": ys}), xs.shape)
        if not np.all(np.isfinite(values)):
            raise SceneError(f"material.gamma = {gamma.text!r} is not finite everywhere in the domain")
        worst = int(np.argmin(values))
        if values[worst] <= 0:
            raise SceneError(f"material.gamma = {gamma.text!r} is {values[worst]:.3g} <= 0 at "
                             f"(x, y) = ({xs[worst]:.3g}, {ys[worst]:.3g}); the toughness must be "
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
        allowed = ["name", *SECTIONS, *LISTS]
        for key in data:
            if key not in allowed:
                raise SceneError(_unknown_key_message("", key, allowed))
        kwargs: dict[str, Any] = {"name": str(data.get("name", name))}
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
            return {f.name: plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}

        out: dict[str, Any] = {"name": self.name}
        for name in SECTIONS:
            out[name] = section(getattr(self, name))
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
    except SceneError:
        raise
    except (TypeError, ValueError) as err:
        raise SceneError(f"[{section}]: {err}") from None


def _convert(value: Any, hint: Any, key: str) -> Any:
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SceneError(f"{key} = {value!r} must be a number")
        if not math.isfinite(value):
            raise SceneError(f"{key} = {value!r} must be a finite number")
        return float(value)
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise SceneError(f"{key} = {value!r} must be an integer")
        return value
    if hint is str:
        if not isinstance(value, str):
            raise SceneError(f"{key} = {value!r} must be a string")
        return value
    if hint is Expression:
        try:
            return Expression.of(value)
        except ExpressionError as err:
            raise SceneError(f"{key}: {err}") from None
    if hint == tuple[float, ...]:
        if not isinstance(value, list):
            raise SceneError(f"{key} = {value!r} must be a list of numbers")
        return tuple(_convert(v, float, key) for v in value)
    if hint == tuple[tuple[float, ...], ...]:
        if not isinstance(value, list) or not all(isinstance(v, list) for v in value):
            raise SceneError(f"{key} = {value!r} must be a list of points [[x, y], ...]")
        return tuple(tuple(_convert(c, float, key) for c in v) for v in value)
    raise TypeError(f"no conversion for {hint}")  # a programming error, not user input


def parse_override(text: str) -> tuple[list[str], Any]:
    """Split ``"time.t_end=0.05"`` into (["time", "t_end"], 0.05); values are TOML."""
    if "=" not in text:
        raise SceneError(f"--set {text!r}: write key=value, e.g. time.t_end=0.05")
    key, raw = text.split("=", 1)
    path = [part for part in key.strip().split(".") if part]
    if not path:
        raise SceneError(f"--set {text!r}: the key is empty")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()  # bare words are strings: --set model.kind=mode3
    return path, value


def apply_overrides(data: dict[str, Any], overrides: list[str]) -> dict[str, Any]:
    """Apply ``key=value`` overrides to raw scene data (a copy is returned)."""
    import copy

    result = copy.deepcopy(data)
    for text in overrides:
        path, value = parse_override(text)
        node: Any = result
        for i, part in enumerate(path[:-1]):
            if isinstance(node, list):
                try:
                    node = node[int(part)]
                except (ValueError, IndexError):
                    raise SceneError(f"--set {text!r}: {'.'.join(path[:i + 1])} is not an index "
                                     "of the list") from None
            else:
                node = node.setdefault(part, {})
            if not isinstance(node, (dict, list)):
                raise SceneError(f"--set {text!r}: {'.'.join(path[:i + 1])} is not a section")
        if isinstance(node, list):
            raise SceneError(f"--set {text!r}: give an index into the list, e.g. loads.0.value=...")
        node[path[-1]] = value
    return result


def read_scene_data(path: str | Path) -> dict[str, Any]:
    """Read raw TOML scene data, with one-line errors for missing or malformed files."""
    path = Path(path)
    if not path.is_file():
        raise SceneError(f"scene file {str(path)!r} does not exist")
    try:
        with path.open("rb") as handle:
            return tomllib.load(handle)
    except tomllib.TOMLDecodeError as err:
        raise SceneError(f"scene file {str(path)!r} is not valid TOML: {err}") from None


def load_scene(path: str | Path, overrides: list[str] | None = None) -> Scene:
    """Read, override and validate a scene file.

    Parameters
    ----------
    path : str or Path
        A TOML scene file.
    overrides : list of str, optional
        ``"section.key=value"`` items applied before validation.
    """
    data = apply_overrides(read_scene_data(path), overrides or [])
    return Scene.from_dict(data, name=Path(path).stem)
