"""Reading scene files: TOML, ``--set key=value`` overrides, validation into a :class:`Scene`."""
from __future__ import annotations

import copy
import tomllib
from pathlib import Path
from typing import Any

from .coercion import SceneError
from .sections import Scene


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

    A relative ``geometry.file`` is taken relative to the scene file's folder.
    """
    data = apply_overrides(read_scene_data(path), overrides or [])
    geometry = data.get("geometry")
    if isinstance(geometry, dict) and isinstance(geometry.get("file"), str) and geometry["file"]:
        # a CAD file is found next to the scene file
        geometry["file"] = str(Path(path).parent / Path(geometry["file"]).expanduser())
    return Scene.from_dict(data, name=Path(path).stem)
