"""The seam between one process and many: what the stepper, its sub-problems, the writers and
the run (:mod:`ngfrac.runner`) ask of the processes of a run (:class:`Communicator`), and the
one-process answer (:class:`Serial`, :data:`SERIAL`). The MPI answer is
:class:`ngfrac.parallel.MPICommunicator`.

What the run asks (its folder, its restart, its writers) is built from layers above this one
(``ngfrac.io``), so those methods take it as arguments: the serial answer calls what it is
given, the MPI answer (in ``ngfrac.parallel``, which may import io) builds its own.
"""
from __future__ import annotations

import contextlib
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Protocol, Sequence, TypeVar

import ngsolve as ngs

if TYPE_CHECKING:
    from ..mesh.adapter import MeshAdapter
    from ..mesh.fields import MeshFields
    from ..physics.crack_models import CrackModel
    from ..post.crackset import CrackSet
    from ..scene import Scene
    from .crack_tracking import CrackTracker
    from .state import StepperState
    from .stepper import PhaseFieldStepper
    from .z_system import AssembledSystem, ZForms, ZSystem

__all__ = ["SERIAL", "Communicator", "ParallelError", "Serial"]

T = TypeVar("T")


class ParallelError(RuntimeError):
    """A scene or a launch that cannot run distributed (yet); the message says what to do."""


class Communicator(Protocol):
    """What the stepper and its sub-problems ask of the processes of a run."""

    size: int
    rank: int
    is_root: bool

    def check(self, scene: "Scene") -> None: ...
    def check_start(self, mesh: ngs.Mesh | None, state: "StepperState | None") -> None: ...
    def concurrent_substeps(self, requested: bool) -> bool: ...
    def distribute(self, build: Callable[[], ngs.Mesh]) -> ngs.Mesh: ...
    def u_solver(self, solver: str) -> str: ...
    def mesh_adapter(self, scene: "Scene", crack_model: "CrackModel") -> "MeshAdapter": ...
    def max(self, value: float) -> float: ...
    def crack(self, tracker: "CrackTracker", fields: "MeshFields") -> "CrackSet": ...
    def size_range(self, tracker: "CrackTracker", fields: "MeshFields") -> tuple[float, float]: ...
    def counts(self, fields: "MeshFields") -> tuple[int, int]: ...
    def guard(self, exit_code: Callable[[BaseException], int]) -> contextlib.AbstractContextManager: ...
    def gather_state(self, stepper: "PhaseFieldStepper") -> "StepperState | None": ...
    def gather_view(self, stepper: "PhaseFieldStepper") -> Any: ...
    def broadcast(self, value: Any) -> Any: ...
    def z_system(self, forms: "ZForms") -> "ZSystem": ...
    def barrier(self) -> None: ...
    # -- the run (ngfrac.runner): rank rules of its folder, restart and writers
    def on_root(self, make: Callable[[], T]) -> T | None: ...
    def read_on_root(self, read: Callable[[], T]) -> T | None: ...
    def resume(self, checkpoint: Any, scene: "Scene") -> "PhaseFieldStepper": ...
    def run_writers(self, default: Callable[[], list[Any]], folder: Any, out: Path,
                    scene: "Scene", extra: Sequence[Any], restart: bool) -> list[Any]: ...


class Serial:
    """One process: every answer is the serial code path."""

    size = 1
    rank = 0
    is_root = True

    def check(self, scene: "Scene") -> None:
        """Nothing to refuse: every scene runs on one process."""

    def check_start(self, mesh: ngs.Mesh | None, state: "StepperState | None") -> None:
        """Nothing to refuse: a stepper on one process starts from any given mesh or state."""

    def concurrent_substeps(self, requested: bool) -> bool:
        """``requested`` (``discretization.concurrent_substeps``): the u- and the z-sub-step
        may run at the same time."""
        return requested

    def distribute(self, build: Callable[[], ngs.Mesh]) -> ngs.Mesh:
        """The mesh ``build()`` makes."""
        return build()

    def u_solver(self, solver: str) -> str:
        """The scene's ``discretization.u_solver``."""
        return solver

    def mesh_adapter(self, scene: "Scene", crack_model: "CrackModel") -> "MeshAdapter":
        """The adapter of an adaptive scene: :class:`~ngfrac.mesh.adapter.MeshAdapter`."""
        from ..mesh.adapter import MeshAdapter

        return MeshAdapter(scene, crack_model)

    def max(self, value: float) -> float:
        return value

    def crack(self, tracker: "CrackTracker", fields: "MeshFields") -> "CrackSet":
        """The tracker's crack set of the fields' z."""
        return tracker.crack(fields)

    def size_range(self, tracker: "CrackTracker", fields: "MeshFields") -> tuple[float, float]:
        """The smallest and the largest element diameter."""
        sizes = tracker.element_sizes(fields)
        return float(sizes.min()), float(sizes.max())

    def counts(self, fields: "MeshFields") -> tuple[int, int]:
        """Vertices of the mesh and unknowns of u and z."""
        return fields.mesh.nv, fields.ndof

    def guard(self, exit_code: Callable[[BaseException], int]) -> contextlib.AbstractContextManager:
        """Errors propagate as they are."""
        return contextlib.nullcontext()

    def gather_state(self, stepper: "PhaseFieldStepper") -> "StepperState":
        """The stepper's own :meth:`~ngfrac.solve.stepper.PhaseFieldStepper.state`."""
        return stepper.state()

    def gather_view(self, stepper: "PhaseFieldStepper") -> "PhaseFieldStepper":
        """The stepper itself: its scene, mesh, u, z, k and t are the serial ones."""
        return stepper

    def broadcast(self, value: Any) -> Any:
        """``value`` (rank 0's, on every rank)."""
        return value

    def z_system(self, forms: "ZForms") -> "AssembledSystem":
        """The z-system of one process: K, M and the drive assembled apart, a direct solve
        (factorized once, updated per step), CG or the obstacle problem
        (:class:`~ngfrac.solve.z_system.AssembledSystem`)."""
        from .z_system import AssembledSystem

        return AssembledSystem(forms)

    def barrier(self) -> None:
        """Nothing to wait for."""

    def on_root(self, make: Callable[[], T]) -> T:
        """``make()``: the one process is rank 0 (what only rank 0 does, e.g. the run folder)."""
        return make()

    def read_on_root(self, read: Callable[[], T]) -> T:
        """``read()``; its errors propagate as they are."""
        return read()

    def resume(self, checkpoint: Any, scene: "Scene") -> "PhaseFieldStepper":
        """The stepper a checkpoint continues
        (:meth:`ngfrac.io.checkpoint.CheckpointState.resume`)."""
        return checkpoint.resume(scene)

    def run_writers(self, default: Callable[[], list[Any]], folder: Any, out: Path,
                    scene: "Scene", extra: Sequence[Any], restart: bool) -> list[Any]:
        """The run's writers: ``default()`` (:func:`ngfrac.io.writers.default_writers` of
        the folder) and then ``extra``."""
        return [*default(), *extra]


SERIAL = Serial()
"""The communicator of a run on one process."""
