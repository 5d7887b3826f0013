"""The runs of a study: ``--vary``, ``--zip`` and ``--refine`` turned into named, validated scenes.

``--vary KEY=V1,V2,...`` (repeatable) runs the product of the values; ``--zip KEY=V1,V2,...``
(repeatable, lists of one length) pairs its lists into one more axis of that product;
``--refine KEY --ratio R --levels N`` adds an axis of N refinement levels of a discretization
setting (:func:`refinement_values`). Values are TOML literals as for ``--set`` (bare words are
strings); a comma inside brackets or quotes does not split (``--vary 'loads.1.value=["0","t"],
["0","2*t"]'``).

Every combination is validated (:meth:`ngfrac.scene.Scene.from_dict`, and
``output.checkpoint_every`` > 0: a study resumes by checkpoints) before anything runs:
:func:`plan_study` raises :class:`~ngfrac.scene.SceneError` with one line naming the run and
the problem.
"""
from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

from ..scene import Scene, SceneError, apply_overrides, parse_override, read_scene_data

__all__ = ["Axis", "PlannedRun", "StudyPlan", "parse_values", "plan_study", "refinement_values"]


@dataclass(frozen=True)
class Axis:
    """One axis of the product: the keys it sets and, per point, their override texts.

    A ``--vary`` axis has one key; a ``--zip`` axis several, paired value by value; the
    ``--refine`` axis its keys scaled together, level 0 the coarsest.
    """

    keys: tuple[str, ...]
    point_texts: tuple[tuple[str, ...], ...]
    """``point_texts[i][j]``: the TOML text of ``keys[j]`` at point ``i``."""
    refinement: bool = False


@dataclass(frozen=True)
class PlannedRun:
    """One run of a study: its folder name, its overrides and its validated scene data."""

    name: str
    values: dict[str, Any]
    """The varied keys (dotted) and their values, as read back from TOML."""
    overrides: tuple[str, ...]
    data: dict[str, Any]
    """The scene as :meth:`Scene.to_dict` gives it (plain data: what a Dask worker receives)."""
    scene_name: str
    level: int | None = None
    """The refinement level (0 the coarsest) when the study has a ``--refine`` axis."""

    def scene(self) -> Scene:
        """The run's scene (built again from :attr:`data`)."""
        return Scene.from_dict(self.data, name=self.scene_name)


@dataclass(frozen=True)
class StudyPlan:
    """The validated runs of a study, in the order of the product (the last axis fastest)."""

    scene_path: Path
    axes: tuple[Axis, ...]
    runs: tuple[PlannedRun, ...]
    base_overrides: tuple[str, ...] = ()
    refine_keys: tuple[str, ...] = ()
    ratio: float | None = None
    levels: int = 0

    @property
    def keys(self) -> list[str]:
        """Every varied key, axis by axis (the columns that come first in study.csv)."""
        return [key for axis in self.axes for key in axis.keys]

    @property
    def grouping_keys(self) -> list[str]:
        """The varied keys outside the refinement axis: one Richardson estimate per value."""
        return [key for axis in self.axes if not axis.refinement for key in axis.keys]


def split_values(text: str) -> list[str]:
    """``"0.1,[1, 2],'a,b'"`` -> ``["0.1", "[1, 2]", "'a,b'"]``: commas at depth 0 split."""
    parts, depth, quote, start = [], 0, "", 0
    for i, char in enumerate(text):
        if quote:
            if char == quote:
                quote = ""
        elif char in "\"'":
            quote = char
        elif char in "[{":
            depth += 1
        elif char in "]}":
            depth -= 1
        elif char == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    parts.append(text[start:])
    return [part.strip() for part in parts]


def parse_values(option: str, text: str) -> tuple[str, list[str]]:
    """``"phase_field.epsilon=0.1,0.05"`` -> ``("phase_field.epsilon", ["0.1", "0.05"])``.

    Raises
    ------
    SceneError
        No ``=``, an empty key, an empty value or fewer values than the option needs.
    """
    if "=" not in text:
        raise SceneError(f"{option} {text!r}: write KEY=V1,V2,..., e.g. {option} "
                         "phase_field.epsilon=0.1,0.05")
    key, raw = (part.strip() for part in text.split("=", 1))
    if not key or any(not part for part in key.split(".")):
        raise SceneError(f"{option} {text!r}: the key is empty or has an empty part")
    values = split_values(raw)
    if any(not value for value in values):
        raise SceneError(f"{option} {text!r}: an empty value (two commas, or one at the end); "
                         "give V1,V2,...")
    if len(set(values)) != len(values):
        raise SceneError(f"{option} {text!r}: a value is given twice")
    return key, values


def refinement_values(key: str, base: Any, ratio: float, levels: int, dim: int) -> list[str]:
    """The TOML texts of ``key`` on ``levels`` refinement levels, the coarsest first.

    A length or a time step (a float: ``geometry.mesh_size``, ``adaptivity.hmin``,
    ``time.dt``, ``phase_field.epsilon``) is divided by ``ratio`` per level; a vertex cap (an
    integer key, ``adaptivity.max_vertices``) is multiplied by ``ratio**dim`` (rounded), so
    that the mesh size again shrinks by ``ratio``: the grid refinement ratio of Richardson's
    extrapolation is ``ratio`` either way.
    """
    if isinstance(base, bool) or not isinstance(base, (int, float)) or not base > 0:
        raise SceneError(f"--refine {key}: the scene's value {base!r} is not a positive number "
                         "(refine a mesh size, a vertex cap, a time step or epsilon)")
    if isinstance(base, int):
        return [str(int(round(base * ratio ** (dim * level)))) for level in range(levels)]
    # 12 digits: 0.00075, not 0.0007499999999999998 (a change of 1e-16 relative)
    return [repr(float(f"{float(base) / ratio ** level:.12g}")) for level in range(levels)]


def _lookup(data: dict[str, Any], key: str) -> Any:
    node: Any = data
    for part in key.split("."):
        if isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        elif isinstance(node, dict) and part in node:
            node = node[part]
        else:
            return None
    return node


def _scene_value(data: dict[str, Any], scene: Scene, key: str) -> Any:
    """The value of ``key`` in the scene file, else in the validated scene (its default)."""
    value = _lookup(data, key)
    return value if value is not None else _lookup(scene.to_dict(), key)


_UNSAFE = re.compile(r"[^A-Za-z0-9._+-]+")


def _label(value_text: str) -> str:
    """A value as a part of a folder name: a float to 6 digits, other characters than letters,
    digits and ``._+-`` as ``_``."""
    text = value_text.strip()
    try:
        number = float(text)
    except ValueError:
        number = None
    if number is not None and not text.lstrip("+-").isdigit():
        text = f"{number:.6g}"
    label = _UNSAFE.sub("_", text.strip("\"'")).strip("_")
    return label[:40] or "_"


def _short_names(keys: Sequence[str]) -> dict[str, str]:
    """The last part of each key where that is unambiguous, else the whole dotted key."""
    last = [key.rsplit(".", 1)[-1] for key in keys]
    return {key: (short if last.count(short) == 1 else key) for key, short in zip(keys, last)}


def plan_study(scene_path: str | Path, vary: Sequence[str] = (), zipped: Sequence[str] = (),
               overrides: Sequence[str] = (), refine: Sequence[str] = (),
               ratio: float = 2.0, levels: int = 3) -> StudyPlan:
    """Every run of ``ngfrac study``, validated before any starts.

    Parameters
    ----------
    scene_path : the scene file every run starts from
    vary : ``"KEY=V1,V2,..."`` texts; the product of their values is run
    zipped : ``"KEY=V1,V2,..."`` texts of one length, paired into one more axis
    overrides : ``"KEY=VALUE"`` applied to every run first (as ``--set``)
    refine : keys scaled together over ``levels`` refinement levels by ``ratio``
        (:func:`refinement_values`); empty: no refinement axis
    ratio, levels : the grid refinement ratio (> 1) and the number of levels (>= 3)

    Raises
    ------
    SceneError
        Bad syntax, a key given twice, no axis at all, or a combination the scene refuses
        (the message names the run).
    """
    scene_path = Path(scene_path)
    if scene_path.is_dir():
        raise SceneError(f"{str(scene_path)!r} is a folder; give a scene file (TOML)")
    raw = read_scene_data(scene_path)
    base_data = apply_overrides(raw, list(overrides))
    try:
        base = Scene.from_dict(_with_cad_path(base_data, scene_path), name=scene_path.stem)
    except SceneError as err:
        raise SceneError(f"{scene_path}: {err}") from None
    axes: list[Axis] = []
    for text in vary:
        key, values = parse_values("--vary", text)
        axes.append(Axis((key,), tuple((value,) for value in values)))
    if zipped:
        parsed = [parse_values("--zip", text) for text in zipped]
        lengths = {len(values) for _, values in parsed}
        if len(lengths) != 1:
            raise SceneError("--zip: the lists have different lengths ("
                             + ", ".join(f"{key}: {len(values)}" for key, values in parsed)
                             + "); give each the same number of values")
        axes.append(Axis(tuple(key for key, _ in parsed),
                         tuple(zip(*(values for _, values in parsed)))))
    refine = tuple(refine)
    if refine:
        if not ratio > 1 or not math.isfinite(ratio):
            raise SceneError(f"--ratio {ratio!r}: the refinement ratio must be a number > 1 "
                             "(2: each level halves the mesh size)")
        if levels < 3:
            raise SceneError(f"--levels {levels}: Richardson's extrapolation needs at least 3 "
                             "refinement levels")
        columns = [refinement_values(key, _scene_value(base_data, base, key), ratio, levels,
                                     base.geometry.dim) for key in refine]
        axes.append(Axis(refine, tuple(zip(*columns)), refinement=True))
    if not axes:
        raise SceneError("nothing to vary: give --vary KEY=V1,V2,..., --zip or --refine KEY")
    keys = [key for axis in axes for key in axis.keys]
    repeated = sorted({key for key in keys if keys.count(key) > 1})
    if repeated:
        raise SceneError(f"{repeated[0]!r} is varied twice; give each key in one --vary, --zip "
                         "or --refine only")
    shorts = _short_names(keys)
    runs, names = [], set()
    for combination in itertools.product(*(range(len(axis.point_texts)) for axis in axes)):
        texts = [f"{key}={value}" for axis, i in zip(axes, combination)
                 for key, value in zip(axis.keys, axis.point_texts[i])]
        name = "_".join(f"{shorts[t.split('=', 1)[0]]}={_label(t.split('=', 1)[1])}"
                        for t in texts)
        while name in names:  # two values that differ only in characters a folder cannot hold
            name += "+"
        names.add(name)
        level = next((i for axis, i in zip(axes, combination) if axis.refinement), None)
        runs.append(_validated(scene_path, base_data, texts, name, level))
    return StudyPlan(scene_path, tuple(axes), tuple(runs), tuple(overrides), refine,
                     ratio if refine else None, levels if refine else 0)


def _with_cad_path(data: dict[str, Any], scene_path: Path) -> dict[str, Any]:
    """A relative ``geometry.file`` taken relative to the scene file (as :func:`load_scene`)."""
    geometry = data.get("geometry")
    if isinstance(geometry, dict) and isinstance(geometry.get("file"), str) and geometry["file"]:
        data = {**data, "geometry": {**geometry, "file": str(
            scene_path.parent / Path(geometry["file"]).expanduser())}}
    return data


def _validated(scene_path: Path, base_data: dict[str, Any], texts: list[str], name: str,
               level: int | None) -> PlannedRun:
    try:
        data = _with_cad_path(apply_overrides(base_data, texts), scene_path)
        scene = Scene.from_dict(data, name=scene_path.stem)
    except SceneError as err:
        raise SceneError(f"run {name}: {err}") from None
    if scene.output.checkpoint_every < 1:
        raise SceneError(f"run {name}: output.checkpoint_every = 0, but a study knows a "
                         "finished run and continues an unfinished one by its checkpoint; "
                         "give a positive value (the default is 50)")
    values = {}
    for text in texts:
        path, value = parse_override(text)
        values[".".join(path)] = value
    return PlannedRun(name, values, tuple(texts), scene.to_dict(), scene.name, level)
