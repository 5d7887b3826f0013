"""Mesh changes of an MPI run: the serial adapter on rank 0, on an exact copy of the fields.

At a mesh change every rank sends its dof values of u and z to rank 0, which holds the
undistributed mesh; the dofs are matched node by node (vertices by their coordinates, which
``Distribute`` copies bitwise, edges by their two vertices), so rank 0's copy of u and z is
the distributed fields' own coefficients, edge dofs included. Rank 0 then runs the serial
:class:`~ngfrac.mesh.adapter.MeshAdapter` on that copy (estimate, sizes, Netgen under the
vertex cap, transfer of u and z with the non-repair bound), distributes the new mesh, and
sends each rank the transferred coefficients of its dofs. The new mesh and the transferred
fields are therefore the serial code's for the same u and z; the decision to remesh
(:meth:`MeshAdapter.wants_new_mesh`) is made on rank 0 in the same way and broadcast.

Estimating in parallel and gathering only sizes was not chosen: the estimators' patches and
jumps cross the ranks' interfaces, the tip lane and the band sizes need node values of the
whole crack, and the transfer needs the old fields wherever a new node falls, which no rank
has.
"""
from __future__ import annotations

import dataclasses
import logging
import time
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

import numpy as np
import ngsolve as ngs

from ..mesh.adapter import Adaptation, MeshAdapter
from ..scene.build import crack_model_of, elastic_model_of
from ..mesh.fields import MeshFields

if TYPE_CHECKING:
    from ..scene import Scene
    from ..physics.crack_models import CrackModel
    from .communicator import MPICommunicator

__all__ = ["DistributedMeshAdapter", "MeshChangeCost", "RootCopy", "node_dofs"]

log = logging.getLogger(__name__)

GATHERED = ("u", "z")
"""The fields a mesh change moves (u_prev is u right after it, as in the serial transfer)."""


@dataclass(frozen=True)
class MeshChangeCost:
    """The seconds of one distributed mesh change, measured on rank 0."""

    step: int
    gather_s: float
    """u and z to rank 0 (and, at a new mesh, the node matching)."""
    estimate_s: float
    mark_s: float
    remesh_s: float
    transfer_s: float
    """The serial transfer on rank 0 (with its serial spaces)."""
    distribute_s: float
    """``Distribute`` / ``Receive`` of the new mesh."""
    rebuild_s: float
    """The distributed spaces and sub-problems on the new mesh."""
    scatter_s: float
    """The node matching of the new mesh and the transferred coefficients to the ranks."""

    @property
    def total_s(self) -> float:
        return (self.gather_s + self.estimate_s + self.mark_s + self.remesh_s + self.transfer_s
                + self.distribute_s + self.rebuild_s + self.scatter_s)


def node_dofs(fes: ngs.FESpace) -> tuple[np.ndarray, np.ndarray]:
    """The dofs of ``fes`` per vertex and per edge: arrays (nv, k_v) and (nedge, k_e).

    Raises when a dof lies on another node (faces, cells: order >= 3) or the count per node
    varies: the matching of :class:`DistributedMeshAdapter` knows vertices and edges only.
    """
    mesh = fes.mesh
    blocked = _blocked_layout(fes)
    if blocked is not None:
        return blocked
    vertex = [tuple(fes.GetDofNrs(ngs.NodeId(ngs.VERTEX, i))) for i in range(mesh.nv)]
    edge = [tuple(fes.GetDofNrs(ngs.NodeId(ngs.EDGE, i))) for i in range(mesh.nedge)]
    vertex_dofs = _table(vertex)
    edge_dofs = _table(edge)
    if vertex_dofs.size + edge_dofs.size != fes.ndof:
        raise RuntimeError(f"{fes.ndof} dofs of {fes.type}, {vertex_dofs.size + edge_dofs.size} "
                           "on vertices and edges: a distributed mesh change moves P1/P2 "
                           "fields only (discretization.order <= 2)")
    return vertex_dofs, edge_dofs


def _blocked_layout(fes: ngs.FESpace, samples: int = 25) -> tuple[np.ndarray, np.ndarray] | None:
    """NGSolve's layout of H1 and VectorH1 of order 1 or 2, or None when ``fes`` has
    another: per component the vertex dofs in vertex order, then the edge dofs in edge order
    (as :class:`~ngfrac.fem.nodal.LagrangeNodes` assumes), the components one after the
    other. Checked with ``GetDofNrs`` at ``samples`` vertices and edges (a loop over every
    node costs 0.1-0.3 s per space at 5,000 vertices)."""
    mesh = fes.mesh
    nv, ne, order = mesh.nv, mesh.nedge, fes.globalorder
    nodes = nv + (ne if order == 2 else 0)
    if order not in (1, 2) or nodes == 0 or fes.ndof % nodes:
        return None
    shift = nodes * np.arange(fes.ndof // nodes)
    vertex = np.arange(nv)[:, None] + shift
    edge = (nv + np.arange(ne))[:, None] + shift if order == 2 else np.zeros((ne, 0), dtype=int)
    for kind, table in ((ngs.VERTEX, vertex), (ngs.EDGE, edge)):
        for i in np.unique(np.linspace(0, len(table) - 1, samples).astype(int)) if len(table) else ():
            if tuple(fes.GetDofNrs(ngs.NodeId(kind, int(i)))) != tuple(table[i]):
                return None
    return vertex, edge


def _table(rows: list[tuple[int, ...]]) -> np.ndarray:
    """Rows of equal length as an int array (0 rows: shape (0, 0))."""
    if not rows:
        return np.zeros((0, 0), dtype=int)
    if len({len(row) for row in rows}) != 1:
        raise RuntimeError("the number of dofs per node varies: a distributed mesh change needs "
                           "a uniform order")
    return np.array(rows, dtype=int)


def _edge_vertices(mesh: ngs.Mesh) -> np.ndarray:
    """The two vertex numbers of every edge, shape (nedge, 2)."""
    return np.array([(e.vertices[0].nr, e.vertices[1].nr) for e in mesh.edges],
                    dtype=int).reshape(-1, 2)


@dataclass(eq=False)
class _NodeLayout:
    """What a rank sends once per mesh to have its dofs matched: its vertices, its edges and
    the dofs of u and z on each."""

    points: np.ndarray
    edges: np.ndarray
    dofs: dict[str, tuple[np.ndarray, np.ndarray]]

    @classmethod
    def of(cls, fields: MeshFields) -> "_NodeLayout":
        mesh = fields.mesh
        points = np.array(mesh.ngmesh.Coordinates())[:, : mesh.dim] if mesh.nv else \
            np.zeros((0, mesh.dim))
        dofs = {name: node_dofs(getattr(fields, name).space) for name in GATHERED}
        if not any(edge.size for _, edge in dofs.values()):  # P1: no edge is matched
            edges = np.zeros((0, 2), dtype=int)
        elif fields.nodes.order == 2:
            edges = fields.nodes.edge_vertices  # the same pairs, already listed
        else:
            edges = _edge_vertices(mesh)
        return cls(points, edges, dofs)


@dataclass(eq=False)
class _RootDofMatch:
    """On rank 0: serial fields on the undistributed mesh and, per rank, the serial dof of
    each of its local dofs (per field)."""

    fields: MeshFields
    index: list[dict[str, np.ndarray]]

    @classmethod
    def match(cls, fields: MeshFields, layouts: list[_NodeLayout]) -> "_RootDofMatch":
        from scipy.spatial import cKDTree

        mine = _NodeLayout.of(fields)
        n = max(len(mine.points), 1)
        keys = np.sort(mine.edges, axis=1) @ np.array([n, 1])  # an edge by its two vertices
        order = np.argsort(keys)
        sorted_keys = keys[order]
        tree = cKDTree(mine.points)
        extent = float(np.ptp(mine.points, axis=0).max())
        index = []
        for rank, layout in enumerate(layouts):
            per_field: dict[str, np.ndarray] = {}
            if len(layout.points) == 0:
                index.append({name: np.zeros(0, dtype=int) for name in GATHERED})
                continue
            distance, vertex = tree.query(layout.points)
            if distance.max() > 1e-12 * extent:
                raise RuntimeError(f"a vertex of rank {rank} is {distance.max():.3g} from every "
                                   "vertex of rank 0's mesh: the distributed mesh is not rank 0's")
            wanted = np.sort(vertex[layout.edges], axis=1) @ np.array([n, 1])
            at = np.minimum(np.searchsorted(sorted_keys, wanted), max(len(keys) - 1, 0))
            if len(wanted) and not np.array_equal(sorted_keys[at], wanted):
                raise RuntimeError(f"an edge of rank {rank} is no edge of rank 0's mesh")
            edge = order[at] if len(wanted) else np.zeros(0, dtype=int)
            for name in GATHERED:
                local_v, local_e = layout.dofs[name]
                serial_v, serial_e = mine.dofs[name]
                serial = np.zeros(local_v.size + local_e.size, dtype=int)
                serial[local_v.ravel()] = serial_v[vertex].ravel()
                if local_e.size:
                    serial[local_e.ravel()] = serial_e[edge].ravel()
                per_field[name] = serial
            index.append(per_field)
        for name in GATHERED:  # every dof of the whole mesh is some rank's
            covered = np.zeros(getattr(fields, name).space.ndof, dtype=bool)
            for per_field in index:
                covered[per_field[name]] = True
            if not covered.all():
                raise RuntimeError(f"{np.count_nonzero(~covered)} dofs of {name} on rank 0's "
                                   "mesh belong to no rank")
        return cls(fields, index)


SPACE_OF = {"u": "u", "u_prev": "u", "z": "z"}
"""The field whose dof matching a field uses (u_prev lives in u's space)."""


class RootCopy:
    """On rank 0 a serial copy of a distributed run's fields, dof for dof (made on every
    rank; the other ranks take part in the gathers and scatters).

    The copy is matched to the current distributed mesh once (:class:`_RootDofMatch`, collective):
    on the mesh rank 0 gave :meth:`distribute`, or else on a copy of the communicator's
    serial mesh (the scene's first mesh). Mesh changes (:class:`DistributedMeshAdapter`) and
    checkpoints (:mod:`ngfrac.parallel.checkpoints`) share it, so a checkpoint after a mesh
    change matches nothing again.

    Parameters
    ----------
    scene : Scene
    comm : MPICommunicator
    """

    def __init__(self, scene: "Scene", comm: "MPICommunicator") -> None:
        self.scene = scene
        self.comm = comm
        self.model = elastic_model_of(scene)
        self.crack_model = crack_model_of(scene)
        self.fields: MeshFields | None = None
        """This rank's fields of the last gather or scatter."""
        self._mesh: ngs.Mesh | None = None
        self._root: _RootDofMatch | None = None
        self._next_serial: MeshFields | ngs.Mesh | None = None

    @property
    def mesh(self) -> ngs.Mesh | None:
        """The distributed mesh the copy is matched to."""
        return self._mesh

    @property
    def root_fields(self) -> MeshFields | None:
        """On rank 0 the serial fields (None elsewhere and before the first match)."""
        return self._root.fields if self.comm.is_root and self._root is not None else None

    def serial_fields(self, mesh: ngs.Mesh) -> MeshFields:
        """Zero serial fields of the scene on ``mesh`` (rank 0's)."""
        return MeshFields.on(mesh, self.scene, self.model, self.crack_model)

    def attach(self, fields: MeshFields) -> None:
        """Match ``fields`` (this rank's, on the current distributed mesh) to rank 0's serial
        copy of the same mesh (collective, once per mesh; later fields on the same mesh
        share the match)."""
        if self._mesh is fields.mesh:
            self.fields = fields
            return
        layouts = self.comm.comm.gather(_NodeLayout.of(fields), root=0)
        if self.comm.is_root:
            serial = self._next_serial
            if serial is None:  # the scene's first mesh: the communicator kept it
                serial = ngs.Mesh(self.comm.serial_ngmesh.Copy())
            if isinstance(serial, ngs.Mesh):
                serial = self.serial_fields(serial)
            self._root = _RootDofMatch.match(serial, layouts)
        self._next_serial = None
        self._mesh, self.fields = fields.mesh, fields

    def distribute(self, serial: MeshFields | ngs.Mesh | None) -> ngs.Mesh:
        """The new mesh (rank 0's ``serial`` mesh, or its fields' mesh; None elsewhere)
        distributed; the next :meth:`attach` matches rank 0's ``serial`` to it."""
        if self.comm.is_root:
            mesh = serial.mesh if isinstance(serial, MeshFields) else serial
            distributed = self.comm.distribute(lambda: mesh)
            self._next_serial = serial
            return distributed
        return self.comm.distribute(None)

    def gather(self, fields: MeshFields, names: tuple[str, ...] = GATHERED) -> MeshFields | None:
        """Rank 0's copy gets the coefficients of ``names`` of every rank's ``fields``;
        returns the copy on rank 0, None elsewhere. Collective."""
        self.attach(fields)
        sent = [getattr(fields, name).vec.FV().NumPy().copy() for name in names]
        gathered = self.comm.comm.gather(sent, root=0)
        if not self.comm.is_root:
            return None
        for i, name in enumerate(names):
            values = getattr(self._root.fields, name).vec.FV().NumPy()
            for index, rank_values in zip(self._root.index, gathered):
                values[index[SPACE_OF[name]]] = rank_values[i]
        return self._root.fields

    def scatter(self, fields: MeshFields, names: tuple[str, ...] = GATHERED) -> None:
        """Every rank's ``names`` of ``fields`` from rank 0's copy; u_prev = u when u_prev
        is not among them (as after a mesh change). Collective."""
        self.attach(fields)
        parts = None
        if self.comm.is_root:
            serial = {name: getattr(self._root.fields, name).vec.FV().NumPy() for name in names}
            parts = [[serial[name][index[SPACE_OF[name]]] for name in names]
                     for index in self._root.index]
        mine = self.comm.comm.scatter(parts, root=0)
        for name, values in zip(names, mine):
            getattr(fields, name).vec.FV().NumPy()[:] = values
        if "u_prev" not in names:
            fields.u_prev.vec.data = fields.u.vec


class DistributedMeshAdapter(MeshAdapter):
    """The :class:`~ngfrac.mesh.adapter.MeshAdapter` of an MPI run (made on every rank).

    Rank 0 holds a serial copy of the current fields (:class:`RootCopy`, the
    communicator's) and runs the serial adapter's code on it; the other ranks take part in
    the gathers, the distribution of each new mesh and the scatters, and receive the
    adapter's state after every change (so :attr:`adaptations`, :attr:`eta_total` and the tip
    are the same on every rank).

    Parameters
    ----------
    scene : Scene
    comm : MPICommunicator
        The run's communicator (its ``distribute`` makes every distributed mesh).
    """

    def __init__(self, scene: "Scene", comm: "MPICommunicator",
                 crack_model: "CrackModel | None" = None) -> None:
        super().__init__(scene, crack_model)
        self.comm = comm
        self.copy = comm.root_copy(scene)
        """Rank 0's serial copy of the fields (shared with the checkpoints)."""
        self.costs: list[MeshChangeCost] = []
        """The seconds of each distributed mesh change (rank 0's clock)."""

    # -- the serial copy on rank 0 --------------------------------------------------------------
    def _distribute(self, serial: MeshFields | ngs.Mesh | None) -> ngs.Mesh:
        return self.copy.distribute(serial)

    def _gather(self, fields: MeshFields, names: tuple[str, ...] = GATHERED) -> None:
        self.copy.gather(fields, names)

    def gather(self, fields: MeshFields) -> MeshFields | None:
        """Rank 0's serial copy of ``fields`` (this rank's fields on the current distributed
        mesh) with the coefficients of u and z of every rank; None on the other ranks.
        Collective."""
        return self.copy.gather(fields)

    @property
    def serial_fields(self) -> MeshFields | None:
        """On rank 0 the serial copy as it is: right after a mesh change the transferred u
        and z that were sent to the ranks, after a gather the ranks' values (the remesh
        test gathers z only); None elsewhere."""
        return self.copy.root_fields

    @property
    def _root_fields(self) -> MeshFields:
        return self.copy.root_fields

    def _share_state(self) -> None:
        """Rank 0's adapter state (tip, sizes, learned constants, the changes) on every rank."""
        state = {**self.state(), "adaptations": list(self.adaptations)} if self.comm.is_root else None
        state = self.comm.comm.bcast(state, root=0)
        if not self.comm.is_root:
            self.restore(state)

    # -- the adapter's entries ------------------------------------------------------------------
    def wants_new_mesh(self, mesh: ngs.Mesh, nodes: Any, z_values: np.ndarray,
                       tip: np.ndarray) -> str | None:
        """Rank 0's answer (the serial test on the whole mesh), the same on every rank."""
        fields = self.copy.fields
        if fields is None or fields.mesh is not mesh:
            raise RuntimeError("wants_new_mesh: not the mesh of the last distributed change")
        self._gather(fields, ("z",))
        reason = None
        if self.comm.is_root:
            root = self._root_fields
            reason = super().wants_new_mesh(root.mesh, root.nodes, root.z_values(), tip)
        return self.comm.comm.bcast(reason, root=0)

    def change(self, fields: MeshFields, tip: np.ndarray, step: int, reason: str,
               rebuild: Callable[[ngs.Mesh], MeshFields],
               relax: Callable[[MeshFields], np.ndarray] | None = None,
               solves: Callable[[], AbstractContextManager] = nullcontext,
               ) -> tuple[MeshFields, Adaptation]:
        """:meth:`MeshAdapter.change` for a distributed run (on every rank): gather u and z,
        the serial change on rank 0, distribute the new mesh, ``rebuild`` on it, scatter."""
        started = time.perf_counter()
        self._gather(fields)
        gathered = time.perf_counter()
        serial = record = None
        if self.comm.is_root:
            serial, record = super().change(self._root_fields, tip, step, reason,
                                            self.copy.serial_fields, None, solves)
        changed = time.perf_counter()
        mesh = self._distribute(serial)
        distributed = time.perf_counter()
        new = rebuild(mesh)
        rebuilt = time.perf_counter()
        self.copy.scatter(new)
        if relax is not None and self.settings.relax_core:
            self._relax_core(new, relax(new), tip)  # node-wise: on each rank's own nodes
            self._gather(new, ("z",))
            if self.comm.is_root:
                root = self._root_fields
                self.remember(root.mesh, root.nodes, root.z_values(), tip)
        scattered = time.perf_counter()
        if self.comm.is_root:
            cost = MeshChangeCost(step, gathered - started, record.estimate_s, record.mark_s,
                                  record.remesh_s, record.transfer_s, distributed - changed,
                                  rebuilt - distributed, scattered - rebuilt)
            # the record's transfer is all of the move: serial transfer, distribute, rebuild, scatter
            record = dataclasses.replace(record, transfer_s=cost.transfer_s + scattered - changed)
            self.adaptations[-1] = record
            self.costs.append(cost)
            log.info("step %d: distributed mesh change in %.2f s (gather %.2f, estimate + remesh "
                     "%.2f, transfer %.2f, distribute %.2f, rebuild %.2f, scatter %.2f)", step,
                     cost.total_s, cost.gather_s, cost.estimate_s + cost.mark_s + cost.remesh_s,
                     cost.transfer_s, cost.distribute_s, cost.rebuild_s, cost.scatter_s)
        self._share_state()
        return new, self.adaptations[-1]

    def resolve_initial(self, fields: MeshFields, tip: Callable[[MeshFields], np.ndarray],
                        initial_z: Callable[[ngs.Mesh], MeshFields],
                        solves: Callable[[], AbstractContextManager] = nullcontext,
                        ) -> MeshFields:
        """:meth:`MeshAdapter.resolve_initial` for a distributed run: each new mesh made on
        rank 0 from the gathered z0, distributed, and z0 set on it by ``initial_z``."""
        for _ in range(self.initial_passes):
            at = tip(fields)
            self._gather(fields, ("z",))
            mesh = None
            if self.comm.is_root:
                root = self._root_fields
                with solves():
                    mesh, _ = self.new_mesh(root.mesh, root.nodes, root.z, at)
            fields = initial_z(self._distribute(mesh))
        at = tip(fields)
        self._gather(fields, ("z",))
        if self.comm.is_root:
            root = self._root_fields
            self.remember(root.mesh, root.nodes, root.z_values(), at)
        self._share_state()
        return fields
