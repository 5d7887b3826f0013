"""The demo scripts as modules for the demo tests (they live in demos/, outside the package)."""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[2]
DEMOS = ROOT / "demos"


def load_demo(name: str) -> ModuleType:
    """Import ``demos/NAME.py`` (its folder on sys.path: the scripts share _common.py)."""
    if str(DEMOS) not in sys.path:
        sys.path.insert(0, str(DEMOS))
    spec = importlib.util.spec_from_file_location(f"demo_{name}", DEMOS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
