"""Write docs/api.md from the docstrings of the public API.

    python docs/make_api.py
"""
from __future__ import annotations

import importlib
import inspect
from pathlib import Path

MODULES = ["ngfrac", "ngfrac.scene", "ngfrac.stepper", "ngfrac.runner", "ngfrac.adaptivity",
           "ngfrac.meshing", "ngfrac.transfer", "ngfrac.models", "ngfrac.reactions",
           "ngfrac.results", "ngfrac.checkpoint", "ngfrac.studies", "ngfrac.crackpath",
           "ngfrac.plotting", "ngfrac.output", "ngfrac.expressions", "ngfrac.cracks",
           "ngfrac.geometry", "ngfrac.nodal", "ngfrac.diagnostics", "ngfrac.profiling",
           "estimators"]
"""The order of the reference; modules of ngfrac not named here follow, alphabetically."""
NOT_API = {"ngfrac.__main__", "ngfrac.cli"}


def all_modules() -> list[str]:
    """MODULES, then every other ngfrac module (so a new module is never left out)."""
    import pkgutil

    import ngfrac

    found = {f"ngfrac.{m.name}" for m in pkgutil.iter_modules(ngfrac.__path__)}
    return MODULES + sorted(found - set(MODULES) - NOT_API)


def public_members(module):
    names = getattr(module, "__all__", None)
    if names is None:
        names = [n for n, obj in vars(module).items()
                 if not n.startswith("_") and (inspect.isfunction(obj) or inspect.isclass(obj))
                 and getattr(obj, "__module__", "") == module.__name__]
    return [(n, getattr(module, n)) for n in names if hasattr(module, n)]


class _Named:
    """Shows a sentinel default by its module-level name."""

    def __init__(self, name: str) -> None:
        self.name = name

    def __repr__(self) -> str:
        return self.name


def signature(obj) -> str:
    """The signature; a sentinel default (an ``object()`` such as ``scene.REQUIRED``, whose repr
    is a memory address) is shown by its module-level name, so the page is the same every run."""
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return ""
    module = inspect.getmodule(obj)
    names = {id(value): name for name, value in vars(module).items()} if module else {}

    def shown(param: inspect.Parameter) -> inspect.Parameter:
        default = param.default
        if default is param.empty or " at 0x" not in repr(default):
            return param
        return param.replace(default=_Named(names.get(id(default), type(default).__name__)))

    return str(sig.replace(parameters=[shown(p) for p in sig.parameters.values()]))


def main() -> None:
    lines = ["# API reference", "",
             "Generated from the docstrings by `python docs/make_api.py`; do not edit by hand.", ""]
    for name in all_modules():
        try:
            module = importlib.import_module(name)
        except ImportError:
            continue
        lines += [f"## `{name}`", "", inspect.cleandoc(module.__doc__ or ""), ""]
        if name == "ngfrac":
            continue  # the package re-exports; documented in its modules
        for member_name, obj in public_members(module):
            if not (inspect.isfunction(obj) or inspect.isclass(obj)):
                continue
            kind = "class" if inspect.isclass(obj) else "def"
            lines += [f"### {kind} `{member_name}{signature(obj)}`", "",
                      inspect.cleandoc(obj.__doc__ or "(no docstring)"), ""]
            if inspect.isclass(obj):
                for method_name, method in vars(obj).items():
                    if method_name.startswith("_") or not callable(method) or not method.__doc__:
                        continue
                    lines += [f"- `{method_name}{signature(method)}`: "
                              + inspect.cleandoc(method.__doc__).splitlines()[0]]
                lines.append("")
    Path(__file__).with_name("api.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
