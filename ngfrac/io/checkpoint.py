"""Checkpoints: everything a stepper needs to continue a run exactly, in one HDF5 file.

A checkpoint holds the step counter k, the current mesh (as :class:`~ngfrac.io.results.MeshArrays`,
so a mesh made by adaptive remeshing is restored as it was), the dof vectors of u, u_prev and
z (z is also the non-repair bound of the next step), the adaptivity state when the scene adapts,
and the resolved scene with a hash of the keys that change the solution. Restoring into a
stepper of the same scene continues bit for bit up to the round-off of a new factorization.

The file is written under a temporary name and renamed (``os.replace``), so a run killed at any
moment leaves either the previous checkpoint or the new one, never a partial file.

Layout (``format_version`` 1)::

    /                      attrs: format = "ngfrac-checkpoint", format_version, k, t, scene_hash
    /scene                 the resolved scene as TOML text; attrs: sha256
    /mesh/                 see MeshArrays
    /fields/u, u_prev, z   dof vectors (Fletcher-32 checksums); attrs: space, order, dim
    /nucleus               with no initial crack: where z first reached 1/2 (once it has)
    /previous_tip          the last tip found
    /adapter/              attrs: eta_total, adaptations (JSON), vertex_density(_measured),
                           size_floor_ratio; datasets last_tip, achieved

A checkpoint is refused for a scene that differs in a key other than :data:`IGNORED_KEYS`
(``[output]`` and ``time.t_end``: a restart may write differently or run longer).
"""
from __future__ import annotations

import dataclasses
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import h5py
import ngsolve as ngs
import numpy as np

from .hdf5 import (IGNORED_KEYS, MeshArrays, ResultsError, StoredField, check_format,
                   read_hdf5, read_scene, scene_differences, scene_hash, write_scene)
from ..scene import Scene
from ..solve.state import StepperState

if TYPE_CHECKING:
    from ..solve.stepper import PhaseFieldStepper

FORMAT = "ngfrac-checkpoint"
FORMAT_VERSION = 1
FIELDS = ("u", "u_prev", "z")
"""The stepper's GridFunctions that a checkpoint stores."""


class CheckpointError(RuntimeError):
    """A checkpoint that cannot be written, read or used for this scene."""


# -- state ------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class CheckpointState:
    """A loaded checkpoint (see :func:`load_checkpoint`)."""

    path: Path
    k: int
    t: float
    scene_hash: str
    mesh_arrays: MeshArrays
    fields: dict[str, StoredField]
    adapter: dict[str, Any] | None = None
    ticks: int = 0
    """Time as a count of time.dt (t = ticks * dt)."""
    level: int = 0
    """The adaptive step level (step = dt * 2**level)."""
    nucleus: np.ndarray | None = None
    """With no initial crack: where z first reached 1/2 (:attr:`PhaseFieldStepper.nucleus`)."""
    previous_tip: np.ndarray | None = None
    """The last tip found (:attr:`PhaseFieldStepper.previous_tip`)."""

    def build_mesh(self) -> ngs.Mesh:
        """The checkpoint's mesh, numbered as the original (see :mod:`ngfrac.io.results`)."""
        return self.mesh_arrays.to_mesh()

    def stepper_state(self, mesh: ngs.Mesh | None = None) -> StepperState:
        """The stepper's state stored here, on ``mesh`` (a mesh equal to the stored one, e.g.
        a stepper's own) or on the stored mesh rebuilt."""
        mesh = self.build_mesh() if mesh is None else mesh
        try:
            fields = {name: stored.gridfunction(mesh, name) for name, stored in self.fields.items()}
        except ResultsError as err:
            raise CheckpointError(f"checkpoint {str(self.path)!r}: {err}") from None
        adapter = None
        if self.adapter is not None:
            from ..mesh.adapter import Adaptation
            adapter = {**self.adapter,
                       "adaptations": [Adaptation(**a) for a in self.adapter["adaptations"]]}
        return StepperState(self.k, self.ticks, self.level, mesh, fields, self.nucleus,
                            self.previous_tip, adapter)

    def resume(self, scene: Scene) -> "PhaseFieldStepper":
        """A stepper of ``scene`` continuing from this checkpoint on one process (no initial
        solve); a state the scene cannot continue raises :class:`CheckpointError`."""
        from ..solve.stepper import PhaseFieldStepper

        try:
            return PhaseFieldStepper.from_state(scene, self.stepper_state())
        except ValueError as err:
            raise CheckpointError(f"checkpoint {str(self.path)!r}: {err}") from None


# -- writing ----------------------------------------------------------------------------------
def save_checkpoint(stepper: "PhaseFieldStepper", path: str | Path) -> Path:
    """Write the stepper's state (:meth:`PhaseFieldStepper.state`) to ``path`` atomically (a
    temporary file, then a rename).

    Raises :class:`CheckpointError` when the file cannot be written (a full disk, a missing
    folder); an earlier checkpoint at ``path`` is then left as it was.
    """
    return save_state(stepper.state(), stepper.scene, path)


def save_state(state: StepperState, scene: Scene, path: str | Path) -> Path:
    """Write a stepper state of ``scene`` to ``path`` atomically (see :func:`save_checkpoint`)."""
    path = Path(path)
    tmp = path.with_suffix(".tmp")
    try:
        with h5py.File(tmp, "w") as f:
            f.attrs["format"] = FORMAT
            f.attrs["format_version"] = FORMAT_VERSION
            f.attrs["k"] = int(state.k)
            f.attrs["ticks"] = int(state.ticks)
            f.attrs["level"] = int(state.level)
            f.attrs["t"] = float(state.ticks * scene.time.dt)
            f.attrs["scene_hash"] = scene_hash(scene)
            write_scene(f, scene)
            MeshArrays.of(state.mesh).write(f.create_group("mesh"))
            group = f.create_group("fields")
            for name in FIELDS:
                StoredField.of(state.fields[name]).write(group, name)
            if state.nucleus is not None:  # no initial crack: where the crack started
                f.create_dataset("nucleus", data=np.asarray(state.nucleus, dtype=np.float64))
            if state.previous_tip is not None:  # the tip is kept while it is farther along
                f.create_dataset("previous_tip", data=np.asarray(state.previous_tip, dtype=np.float64))
            if state.adapter is not None:
                _write_adapter(f, state.adapter)
        with open(tmp, "rb") as handle:  # the data must be on disk before the rename is
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except OSError as err:
        tmp.unlink(missing_ok=True)
        reason = err.strerror or str(err).splitlines()[0]
        raise CheckpointError(f"cannot write checkpoint {str(path)!r} ({reason}); the previous "
                              "checkpoint is unchanged") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    _fsync_folder(path.parent)
    return path


def _fsync_folder(folder: Path) -> None:
    """Make the rename durable (POSIX; a no-op where folders cannot be opened)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _write_adapter(f: h5py.File, state: dict[str, Any]) -> None:
    """The adaptivity state that decides when the next mesh change happens
    (:meth:`ngfrac.mesh.adapter.MeshAdapter.state` and the changes so far)."""
    group = f.create_group("adapter")
    group.attrs["eta_total"] = float(state["eta_total"])
    # the learned vertex constant decides the next meshes: without it a restart remeshes
    # differently from the uninterrupted run
    group.attrs["vertex_density"], group.attrs["vertex_density_measured"] = state["vertex_density"]
    group.attrs["size_floor_ratio"] = float(state["size_floor_ratio"])  # learned like the density
    if state["last_tip"] is not None:
        group.create_dataset("last_tip", data=np.asarray(state["last_tip"], dtype=np.float64))
    if state["achieved"] is not None:
        group.create_dataset("achieved", data=np.asarray(state["achieved"], dtype=np.float64))
    group.attrs["adaptations"] = json.dumps([dataclasses.asdict(a) for a in state["adaptations"]])


# -- reading ----------------------------------------------------------------------------------
def load_checkpoint(path: str | Path, scene: Scene) -> CheckpointState:
    """Read a checkpoint and check that it belongs to ``scene``.

    Raises :class:`CheckpointError` with one line for a missing, foreign, truncated or
    corrupt file, one from a newer ngfrac, or one written for another scene (the message
    names the first key that differs). Keys in :data:`IGNORED_KEYS` may differ.
    """
    path = Path(path)
    try:
        with read_hdf5(path, "checkpoint", CheckpointError) as f:
            check_format(f, path, FORMAT, FORMAT_VERSION, "checkpoint", CheckpointError)
            stored, _ = read_scene(f, path, CheckpointError)
            k, t = int(f.attrs["k"]), float(f.attrs["t"])
            ticks = int(f.attrs.get("ticks", k))
            level = int(f.attrs.get("level", 0))
            mesh = MeshArrays.read(f["mesh"])
            fields = {name: StoredField.read(f["fields"][name]) for name in FIELDS}
            adapter = _read_adapter(f["adapter"]) if "adapter" in f else None
            nucleus = f["nucleus"][()] if "nucleus" in f else None
            previous_tip = f["previous_tip"][()] if "previous_tip" in f else None
    except ResultsError as err:  # raised by the mesh checks
        raise CheckpointError(f"checkpoint {str(path)!r}: {err}") from None
    # Compare the scenes, not stored hashes: a newer ngfrac may add keys with defaults.
    differences = scene_differences(stored, scene)
    if differences:
        raise CheckpointError(f"checkpoint {str(path)!r} was written for another scene "
                              f"({differences[0]}{' and more' if len(differences) > 1 else ''}); "
                              "restart with the scene it was written for")
    if k < 0 or not math.isfinite(t):
        raise CheckpointError(f"checkpoint {str(path)!r} is corrupt (step {k}, time {t})")
    return CheckpointState(path, k, t, scene_hash(stored), mesh, fields, adapter, ticks, level,
                           nucleus, previous_tip)


def _read_adapter(group: h5py.Group) -> dict[str, Any]:
    return {"eta_total": float(group.attrs["eta_total"]),
            "last_tip": group["last_tip"][()] if "last_tip" in group else None,
            "achieved": tuple(float(v) for v in group["achieved"][()]) if "achieved" in group else None,
            "adaptations": json.loads(str(group.attrs["adaptations"])),
            "size_floor_ratio": float(group.attrs.get("size_floor_ratio", 1.0)),
            "vertex_density": (float(group.attrs["vertex_density"]),
                               bool(group.attrs["vertex_density_measured"]))
            if "vertex_density" in group.attrs else None}


# -- restoring --------------------------------------------------------------------------------
def restore(stepper: "PhaseFieldStepper", state: CheckpointState) -> None:
    """Put a loaded checkpoint into ``stepper`` (a stepper of the same scene).

    A stepper on a mesh equal to the checkpoint's keeps its mesh; any other stepper moves to
    the checkpoint's mesh (:meth:`PhaseFieldStepper.load_state`). Factorizations are rebuilt
    on the next step.
    """
    if scene_hash(stepper.scene) != state.scene_hash:
        raise CheckpointError(f"checkpoint {str(state.path)!r} was written for another scene than "
                              f"the stepper's ({stepper.scene.name!r})")
    same = MeshArrays.of(stepper.mesh).same_as(state.mesh_arrays)
    for name, stored in state.fields.items():
        mine = getattr(stepper, name)
        if same and not stored.matches(mine.space):
            raise CheckpointError(f"checkpoint {str(state.path)!r}: field {name!r} is "
                                  f"{stored.describe()}, the stepper's is "
                                  f"{StoredField.of(mine).describe()}")
    try:
        stepper.load_state(state.stepper_state(stepper.mesh if same else None))
    except ValueError as err:
        raise CheckpointError(f"checkpoint {str(state.path)!r}: {err}") from None


def resume(path: str | Path, scene: Scene) -> "PhaseFieldStepper":
    """A stepper of ``scene`` continuing from the checkpoint at ``path`` (no initial solve;
    :meth:`CheckpointState.resume`)."""
    return load_checkpoint(path, scene).resume(scene)


__all__ = ["IGNORED_KEYS", "CheckpointError", "CheckpointState", "load_checkpoint", "restore",
           "resume", "save_checkpoint", "save_state", "scene_hash"]
