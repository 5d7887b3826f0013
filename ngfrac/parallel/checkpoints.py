"""Checkpoints of an MPI run: the serial checkpoint, written and read on rank 0.

A distributed run's fields are on its ranks; rank 0 holds the undistributed mesh and a
serial copy of the fields matched dof by dof (:class:`~ngfrac.parallel.adaptivity.RootCopy`,
the gather of a mesh change). :func:`gather_state` gathers u, u_prev and z into that copy and
gives rank 0 the serial :class:`~ngfrac.solve.state.StepperState`, which
:func:`~ngfrac.io.checkpoint.save_state` writes as a serial run's ``checkpoint.h5`` (same
format, same atomic write). :func:`resume_distributed` distributes the mesh of the
checkpoint rank 0 read (``comm.read_on_root``), scatters its fields as after a mesh change
and broadcasts the rest of the state (counters, crack tracking, the adapter's state). The checkpoint is serial, so a
run continues on any number of processes, or serially (:func:`ngfrac.io.checkpoint.resume`).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING

import ngsolve as ngs

from ..io.checkpoint import CheckpointError, CheckpointState
from ..solve.state import STATE_FIELDS, StepperState, copy_of

if TYPE_CHECKING:
    from ..scene import Scene
    from ..solve.stepper import PhaseFieldStepper
    from .communicator import MPICommunicator

__all__ = ["RootView", "gather_state", "gather_view", "resume_distributed"]


@dataclass(frozen=True, eq=False)
class RootView:
    """What the serial writers of results.h5 and crack_path.csv read of a stepper, on rank
    0's serial mesh (:func:`gather_view`)."""

    scene: "Scene"
    mesh: ngs.Mesh
    u: ngs.GridFunction
    z: ngs.GridFunction
    k: int
    t: float


def gather_view(stepper: "PhaseFieldStepper") -> RootView | None:
    """u and z of the stepper gathered to rank 0's serial mesh (None on the other ranks).
    Collective."""
    serial = stepper.comm.root_copy(stepper.scene).gather(stepper.fields, ("u", "z"))
    if serial is None:
        return None
    return RootView(stepper.scene, serial.mesh, serial.u, serial.z, stepper.k, stepper.t)


def gather_state(stepper: "PhaseFieldStepper") -> StepperState | None:
    """The stepper's state on rank 0's serial mesh (:meth:`PhaseFieldStepper.state` with u,
    u_prev and z gathered dof by dof); None on the other ranks. Collective
    (:meth:`MPICommunicator.gather_state <ngfrac.parallel.MPICommunicator.gather_state>`; on
    one process :meth:`Serial.gather_state <ngfrac.solve.communicator.Serial.gather_state>`
    is the stepper's own :meth:`~PhaseFieldStepper.state`).
    """
    comm = stepper.comm
    serial = comm.root_copy(stepper.scene).gather(stepper.fields, STATE_FIELDS)
    state = stepper.state()  # counters, crack tracking, adapter: the same on every rank
    if not comm.is_root:
        return None
    return dataclasses.replace(state, mesh=serial.mesh,
                               fields={name: copy_of(getattr(serial, name))
                                       for name in STATE_FIELDS})


def resume_distributed(checkpoint: CheckpointState | None, scene: "Scene",
                       comm: "MPICommunicator") -> "PhaseFieldStepper":
    """A distributed stepper of ``scene`` continuing from ``checkpoint`` (rank 0's, read by
    :meth:`MPICommunicator.read_on_root <ngfrac.parallel.MPICommunicator.read_on_root>`;
    None on the other ranks). Collective.

    Rank 0 rebuilds the checkpoint's serial mesh and fields; the mesh is distributed, rank
    0's copy matched to it and u, u_prev and z scattered to the ranks; the step counters,
    the crack tracking and the adapter's state are broadcast.
    """
    from ..solve.stepper import PhaseFieldStepper

    serial = checkpoint.stepper_state() if comm.is_root else None  # the serial mesh rebuilt
    copy = comm.root_copy(scene)
    mesh = copy.distribute(serial.mesh if comm.is_root else None)
    local = copy.serial_fields(mesh)  # this rank's zero fields on the distributed mesh
    copy.attach(local)
    if comm.is_root:
        root = copy.root_fields
        for name in STATE_FIELDS:
            mine, stored = getattr(root, name), serial.fields[name]
            if stored.space.ndof != mine.space.ndof:
                raise CheckpointError(f"checkpoint {str(checkpoint.path)!r}: field {name!r} has "
                                      f"{stored.space.ndof} dofs, the scene's space "
                                      f"{mine.space.ndof}; restart with the scene it was written for")
            mine.vec.data = stored.vec
    copy.scatter(local, STATE_FIELDS)
    rest = None
    if comm.is_root:
        rest = dataclasses.replace(serial, mesh=None, fields={})
    rest = comm.broadcast(rest)
    state = dataclasses.replace(rest, mesh=mesh,
                                fields={name: getattr(local, name) for name in STATE_FIELDS})
    stepper = PhaseFieldStepper(scene, state=state, comm=comm)
    copy.attach(stepper.fields)  # the stepper's own fields on the same mesh: no new match
    return stepper
