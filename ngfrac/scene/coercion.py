"""The generic part of reading a scene: plain Python values (as TOML gives them, or as code
writes them) checked and coerced into the field types of the scene's frozen dataclasses.

:class:`Section` is the base of every section: required keys first, then each value coerced
into its field's type (:func:`coerce`), then the section's own ``validate``.
:func:`build_section` makes a section from one TOML table, refusing unknown keys with a hint.
Every problem is a :class:`SceneError` with one line that names the key, the value and what
is allowed; :func:`require` writes that line.
"""
from __future__ import annotations

import dataclasses
import difflib
import functools
import math
from typing import Any, ClassVar, Mapping, get_type_hints

import numpy as np

from .expressions import Expression, ExpressionError

__all__ = ["FREE", "REQUIRED", "Components", "SceneError", "Section", "build_section",
           "coerce", "convert", "dotted_key", "field_hints", "plain", "require",
           "unknown_key_message"]


class SceneError(ValueError):
    """A scene that cannot be run, with a one-line explanation."""


REQUIRED = object()
"""Marker default of a key the scene file must give."""


def dotted_key(section: str, name: str) -> str:
    """``section.name`` as a scene file writes the key (``name`` alone at the top level)."""
    return f"{section}.{name}" if section else name


def require(condition: bool, section: str, name: str, value: Any, allowed: str) -> None:
    """Raise ``SceneError("section.name = value is not allowed: allowed")`` unless
    ``condition``."""
    if not condition:
        raise SceneError(f"{dotted_key(section, name)} = {value!r} is not allowed: {allowed}")


class Section:
    """Base of the scene sections: required keys first, plain Python values coerced into the
    field types (``Material(gamma=1.0)``, a load value ``"10*t"`` or ``["0", "t"]``), then each
    section's own checks. The sections are frozen, so :func:`dataclasses.replace` makes a
    new, validated one."""

    SECTION: ClassVar[str] = ""

    def __post_init__(self) -> None:
        hints = field_hints(type(self))
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            value = getattr(self, f.name)
            if value is REQUIRED:
                raise SceneError(f"missing key {dotted_key(self.SECTION, f.name)!r}; it is required")
            coerced = coerce(value, hints[f.name], dotted_key(self.SECTION, f.name), f.default)
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


def unknown_key_message(section: str, key: str, allowed: list[str]) -> str:
    """The one line for a key the section does not have, with the nearest valid one."""
    close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.5)
    hint = f"; did you mean {dotted_key(section, close[0])!r}?" if close else ""
    return f"unknown key {dotted_key(section, key)!r}{hint} (valid keys: {', '.join(allowed)})"


def build_section(cls: type, data: Any, section: str) -> Any:
    """Check keys and types of one table, then construct (which checks ranges)."""
    if not isinstance(data, Mapping):
        raise SceneError(f"[{section}] must be a table, got {data!r}")
    hints = get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    for key in data:
        if key not in fields:
            raise SceneError(unknown_key_message(section, key, list(fields)))
    kwargs = {}
    for name, f in fields.items():
        if name in data:
            kwargs[name] = convert(data[name], hints[name], dotted_key(section, name))
        elif f.default is REQUIRED:
            raise SceneError(f"missing key {dotted_key(section, name)!r}; it is required")
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
def field_hints(cls: type) -> dict[str, Any]:
    """The resolved type hints of a section class (cached: a scene builds many sections)."""
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
    if hint == tuple[str, ...]:
        return isinstance(value, tuple) and all(isinstance(v, str) for v in value)
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
            and isinstance(args[0], type) and issubclass(args[0], Section):
        return args[0]
    return None


def plain(value: Any) -> Any:
    """Tuples and numpy values as the lists and Python scalars TOML gives."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple):
        return [plain(v) for v in value]
    return value


def coerce(value: Any, hint: Any, key: str, default: Any) -> Any:
    """A field value given in code (a number, a string, a list) as its field's type."""
    if _has_type(value, hint, default):
        return value
    return convert(plain(value), hint, key)


def convert(value: Any, hint: Any, key: str) -> Any:
    """A plain value (as TOML gives it) as the type ``hint``; ``key`` names it in errors."""
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
        return Components.of(value, key) if isinstance(value, list) else convert(value, Expression, key)
    if hint is Expression:
        try:
            return Expression.of(value)
        except ExpressionError as err:
            raise SceneError(f"{key}: {err}") from None
    if hint == tuple[float, ...]:
        if not isinstance(value, list):
            raise SceneError(f"{key} = {value!r} must be a list of numbers")
        return tuple(convert(v, float, key) for v in value)
    if hint == tuple[str, ...]:
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise SceneError(f"{key} = {value!r} must be a list of names, e.g. [\"left\"]")
        return tuple(value)
    table = _table_class(hint)
    if table is not None:
        if isinstance(value, Mapping):
            value = [value]
        if not isinstance(value, list):
            raise SceneError(f"{key} must be an array of tables ([[{key}]])")
        return tuple(item if isinstance(item, table) else build_section(table, item, f"{key}[{i}]")
                     for i, item in enumerate(value))
    if hint == tuple[tuple[float, ...], ...]:
        if not isinstance(value, list) or not all(isinstance(v, list) for v in value):
            raise SceneError(f"{key} = {value!r} must be a list of points [[x, y], ...] "
                             "(3D: [[x, y, z], ...])")
        return tuple(tuple(convert(c, float, key) for c in v) for v in value)
    raise TypeError(f"no conversion for {hint}")  # a programming error, not user input
