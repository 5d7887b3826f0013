"""Safe arithmetic expressions in x, y, z and t, for scene files.

A scene writes toughness and loads as strings such as ``"0.5*(1 + 0.2*sin(20*(x+y)))"``
or ``"10*t"``. :class:`Expression` parses such a string once with :mod:`ast`, accepts only
numbers, the variables ``x, y, z, t``, ``pi``, the operators ``+ - * / **`` and a short list
of functions, and can then be turned into an NGSolve ``CoefficientFunction`` or evaluated
on numpy arrays (used to validate a scene before any mesh exists).
"""
from __future__ import annotations

import ast
import math
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np

VARIABLES = ("x", "y", "z", "t")
CONSTANTS = {"pi": math.pi, "e": math.e}
FUNCTIONS = ("sin", "cos", "tan", "exp", "log", "sqrt", "atan", "atan2", "abs",
             "tanh", "sinh", "cosh", "min", "max")

def _power(base: Any, exponent: Any) -> Any:
    """``base ** exponent`` with a whole-number exponent passed as an int: NGSolve's power of
    a CoefficientFunction by a float is exp(b log a), NaN for a negative base when
    integrated (``Integrate((x - 4)**2.0, mesh)`` is nan, ``(x - 4)**2`` is right)."""
    if isinstance(exponent, (float, np.floating)) and float(exponent).is_integer() \
            and abs(exponent) <= 64:
        exponent = int(exponent)
    return base ** exponent


_BINARY = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b,
           ast.Mult: lambda a, b: a * b, ast.Div: lambda a, b: a / b,
           ast.Pow: _power}
_UNARY = {ast.USub: lambda a: -a, ast.UAdd: lambda a: a}


class ExpressionError(ValueError):
    """An expression string that cannot be parsed or uses something not allowed."""


def _numpy_functions() -> dict[str, Callable[..., Any]]:
    return {"sin": np.sin, "cos": np.cos, "tan": np.tan, "exp": np.exp, "log": np.log,
            "sqrt": np.sqrt, "atan": np.arctan, "atan2": np.arctan2, "abs": np.abs,
            "tanh": np.tanh, "sinh": np.sinh, "cosh": np.cosh,
            "min": np.minimum, "max": np.maximum}


def _ngsolve_tanh(a: Any) -> Any:
    """tanh of a CoefficientFunction (NGSolve has none) from exp of a non-positive argument
    only: (exp(2a) - 1)/(exp(2a) + 1) alone is inf/inf = NaN for a > 354, which a steep step
    such as ``tanh((y - 8)/0.005)`` reaches on its domain (numpy's tanh, which validates the
    scene, is 1 there)."""
    import ngsolve as ngs

    negative = ngs.exp(-2 * ngs.IfPos(a, a, -a))
    return ngs.IfPos(a, (1 - negative) / (1 + negative), (negative - 1) / (negative + 1))


def _ngsolve_functions() -> dict[str, Callable[..., Any]]:
    import ngsolve as ngs

    return {"sin": ngs.sin, "cos": ngs.cos, "tan": ngs.tan, "exp": ngs.exp, "log": ngs.log,
            "sqrt": ngs.sqrt, "atan": ngs.atan, "atan2": ngs.atan2, "abs": lambda a: ngs.IfPos(a, a, -a),
            "tanh": _ngsolve_tanh,
            "sinh": ngs.sinh, "cosh": ngs.cosh,
            "min": lambda a, b: ngs.IfPos(a - b, b, a),
            "max": lambda a, b: ngs.IfPos(a - b, a, b)}


@dataclass(frozen=True)
class Expression:
    """A parsed, validated scalar expression.

    Parameters
    ----------
    text : str
        The source, e.g. ``"10*t"`` or ``"0.5*(1 + 0.2*sin(20*(x+y)))"``.
    """

    text: str
    _tree: ast.Expression = field(init=False, repr=False, compare=False)
    names: frozenset[str] = field(init=False, compare=False)

    def __post_init__(self) -> None:
        try:
            tree = ast.parse(self.text.strip(), mode="eval")
        except SyntaxError as err:
            raise ExpressionError(f"cannot parse expression {self.text!r}: {err.msg}") from None
        names = _check(tree.body, self.text)
        object.__setattr__(self, "_tree", tree)
        object.__setattr__(self, "names", frozenset(names))

    @classmethod
    def of(cls, value: "Expression | str | float | int") -> "Expression":
        """Accept an Expression, a string or a number."""
        if isinstance(value, Expression):
            return value
        if isinstance(value, bool) or not isinstance(value, (str, int, float)):
            raise ExpressionError(f"expected a number or an expression string, got {value!r}")
        return cls(repr(float(value)) if not isinstance(value, str) else value)

    @property
    def is_constant(self) -> bool:
        """True when the expression uses none of x, y, z, t."""
        return not (self.names & set(VARIABLES))

    @property
    def depends_on_time(self) -> bool:
        return "t" in self.names

    def value(self) -> float:
        """The value of a constant expression."""
        if not self.is_constant:
            raise ExpressionError(f"expression {self.text!r} is not constant")
        return float(self.evaluate_numpy({}))

    def evaluate_numpy(self, variables: Mapping[str, Any]) -> Any:
        """Evaluate with numpy arrays (or floats) for the variables it uses."""
        env: dict[str, Any] = {k: np.float64(v) for k, v in CONSTANTS.items()}
        env.update(_numpy_functions())
        env.update(variables)
        missing = (self.names & set(VARIABLES)) - set(variables)
        if missing:
            raise ExpressionError(f"expression {self.text!r} needs {sorted(missing)}")
        with np.errstate(all="ignore"):  # numpy floats: 1/0 is inf and 10**400 inf, not errors
            return _evaluate(self._tree.body, env, literal=np.float64)

    def to_coefficient(self, t: Any = None) -> Any:
        """Build an NGSolve CoefficientFunction.

        Parameters
        ----------
        t : ngsolve.Parameter or float, optional
            What the symbol ``t`` stands for; required when the expression uses ``t``.
        """
        import ngsolve as ngs

        if self.is_constant:
            return ngs.CoefficientFunction(self.value())
        env: dict[str, Any] = dict(CONSTANTS)
        env.update(_ngsolve_functions())
        env.update({"x": ngs.x, "y": ngs.y, "z": ngs.z})
        if self.depends_on_time:
            if t is None:
                raise ExpressionError(f"expression {self.text!r} uses t but no time was given")
            env["t"] = t
        return ngs.CoefficientFunction(_evaluate(self._tree.body, env))

    def __str__(self) -> str:
        return self.text


def _check(node: ast.AST, text: str) -> set[str]:
    """Walk the tree, reject anything outside the allowed grammar, return the names used."""
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise ExpressionError(f"expression {text!r}: only numbers are allowed as literals")
        return set()
    if isinstance(node, ast.Name):
        if node.id in VARIABLES or node.id in CONSTANTS:
            return {node.id}
        allowed = ", ".join(VARIABLES + tuple(CONSTANTS))
        raise ExpressionError(f"expression {text!r}: unknown name {node.id!r} (allowed: {allowed})")
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        return _check(node.left, text) | _check(node.right, text)
    if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
        return _check(node.operand, text)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and not node.keywords:
        if node.func.id not in FUNCTIONS:
            raise ExpressionError(f"expression {text!r}: unknown function {node.func.id!r} "
                                  f"(allowed: {', '.join(FUNCTIONS)})")
        arity = 2 if node.func.id in ("atan2", "min", "max") else 1
        if len(node.args) != arity:
            raise ExpressionError(f"expression {text!r}: {node.func.id} takes {arity} argument(s)")
        names: set[str] = set()
        for arg in node.args:
            names |= _check(arg, text)
        return names
    raise ExpressionError(f"expression {text!r}: {type(node).__name__} is not allowed "
                          "(use numbers, x, y, z, t, pi, + - * / ** and functions)")


def _evaluate(node: ast.AST, env: Mapping[str, Any], literal: Callable[[Any], Any] = float) -> Any:
    if isinstance(node, ast.Constant):
        return literal(node.value)
    if isinstance(node, ast.Name):
        return env[node.id]
    if isinstance(node, ast.BinOp):
        return _BINARY[type(node.op)](_evaluate(node.left, env, literal),
                                      _evaluate(node.right, env, literal))
    if isinstance(node, ast.UnaryOp):
        return _UNARY[type(node.op)](_evaluate(node.operand, env, literal))
    if isinstance(node, ast.Call):
        func = env[node.func.id]  # type: ignore[attr-defined]
        return func(*(_evaluate(arg, env, literal) for arg in node.args))
    raise ExpressionError(f"cannot evaluate {ast.dump(node)}")  # unreachable after _check
