"""Small scenes for tests: the slit demo made coarse and short (reads the checkout's demos/)."""
from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

from ngfrac.scene import Scene, apply_overrides, read_scene_data

ROOT = Path(__file__).resolve().parents[2]
DEMOS = ROOT / "demos"
BENCHMARK_SCENES = ROOT / "benchmarks" / "scenes"

QUICK = ["phase_field.epsilon=0.04", "geometry.mesh_size=0.02", "output.vtk_every=0",
         "adaptivity.enabled=false"]


def demo_data(name: str = "mode3_slit") -> dict[str, Any]:
    """Raw TOML data of a demo scene."""
    return read_scene_data(DEMOS / f"{name}.toml")


def benchmark_scene_data(name: str) -> dict[str, Any]:
    """Raw TOML data of a scene in benchmarks/scenes (``sent_band``: SENT with a z0 band)."""
    return read_scene_data(BENCHMARK_SCENES / f"{name}.toml")


def scene_from(data: dict[str, Any], *overrides: str) -> Scene:
    """A scene from raw data (copied) with ``--set`` style overrides applied."""
    return Scene.from_dict(apply_overrides(copy.deepcopy(data), list(overrides)))


def quick_slit(*overrides: str) -> Scene:
    """The slit demo on a coarse mesh (epsilon 0.04, h 0.02)."""
    return scene_from(demo_data(), *QUICK, *overrides)
