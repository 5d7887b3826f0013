"""ngfrac's subpackages stand in layers: a module imports only from its own layer and those
below it (docs/architecture.md, "Layers"). Every import counts: top level, inside functions
and under ``TYPE_CHECKING``. ``estimators/`` never imports ngfrac."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

LAYERS = [
    {"fem"},                 # threads, rank sums, nodes, quadrature, elements, linear, Newton
    {"geometry"},            # domains and CAD shapes with their cracks
    {"physics"},             # elastic models, crack models, splits, initial cracks
    {"scene"},               # the run description, its checks, the objects it describes
    {"mesh"},                # fields of a mesh, size fields, Netgen, adapter, transfer, resolution
    {"post"},                # measurements: energies, reactions, crack set, path, derived fields
    {"solve"},               # the stepper, its sub-problems, the serial/MPI seam
    {"io"},                  # run folder, writers, HDF5, checkpoints, plots
    {"parallel"},            # MPI: the communicator, distributed adaptivity and checkpoints
    {"runner", "studies", "environment", "testing", "cli", "__init__", "__main__"},
]
"""Bottom to top; the names are ngfrac's subpackages and top-level modules."""

LEVEL = {name: level for level, names in enumerate(LAYERS) for name in names}


def unit_of(module: str) -> str | None:
    """The subpackage or top-level module of a dotted ngfrac module name."""
    parts = module.split(".")
    if parts[0] != "ngfrac":
        return None
    return parts[1] if len(parts) > 1 else "__init__"


def imports_of(path: Path, package_root: Path) -> list[tuple[str, int]]:
    """Every module ``path`` imports (absolute names, relative ones resolved), with lines."""
    relative = path.relative_to(package_root.parent).with_suffix("")
    package = ".".join(relative.parts[:-1])  # where a relative import starts (__init__ too)
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module or ""
            found.append((name, node.lineno))
    return found


def upward_imports() -> list[str]:
    package_root = ROOT / "ngfrac"
    problems = []
    for path in sorted(package_root.rglob("*.py")):
        relative = path.relative_to(package_root)
        own = "__init__" if relative.parts == ("__init__.py",) else relative.parts[0].removesuffix(".py")
        if own not in LEVEL:
            problems.append(f"{relative}: {own!r} is in no layer (add it to LAYERS and the docs)")
            continue
        for name, line in imports_of(path, package_root):
            target = unit_of(name)
            if target is None or target == own:
                continue
            if target not in LEVEL:
                problems.append(f"{relative}:{line} imports {name}, which is in no layer")
            elif LEVEL[target] > LEVEL[own]:
                problems.append(f"{relative}:{line} ({own}) imports {name} ({target}, a higher layer)")
    return problems


def test_no_module_imports_from_a_higher_layer():
    problems = upward_imports()
    assert not problems, "\n".join(problems)


def test_the_check_sees_lazy_and_type_checking_imports(tmp_path):
    """The parser finds imports inside functions and under TYPE_CHECKING, relative ones too."""
    package = tmp_path / "ngfrac" / "fem"
    package.mkdir(parents=True)
    source = package / "example.py"
    source.write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                      "    from ..solve.stepper import PhaseFieldStepper\n"
                      "def f():\n    from ngfrac.io import writers\n")
    found = {unit_of(name) for name, _ in imports_of(source, tmp_path / "ngfrac")}
    assert {"solve", "io"} <= found


@pytest.mark.parametrize("path", sorted((ROOT / "estimators").rglob("*.py")), ids=lambda p: p.name)
def test_estimators_know_nothing_of_ngfrac(path):
    names = [name for name, _ in imports_of(path, ROOT / "estimators")]
    assert not [n for n in names if n.split(".")[0] == "ngfrac"]
