"""HDF5 results: the history table, the resolved scene and field snapshots with their meshes.

A results file can be read back without the run: :func:`open_results` gives the scene, the
history as numpy columns and each snapshot's fields as NGSolve GridFunctions on a mesh rebuilt
from the stored arrays, or as plain numpy arrays.

Layout (``format_version`` 1)::

    /                      attrs: format = "ngfrac-results", format_version
    /scene                 the resolved scene as TOML text; attrs: sha256
    /history               float64 (rows, columns), resizable; attrs: columns
    /snapshots/00000       attrs: t, step
        mesh/              see :class:`MeshArrays` (a hard link to the previous snapshot's
                           mesh group when the mesh did not change)
        fields/u, fields/z dof vectors; attrs: space (NGSolve type), order, dim
        vertex_values/u, /z the fields at the vertices, (nv,) or (nv, components), in the
                           order of mesh/coordinates; attrs: units

For readers without NGSolve, ``mesh/coordinates`` (nv, dim; attrs: units), ``mesh/cells``
(triangles or tetrahedra, vertex numbers from 0) and ``vertex_values`` are all a snapshot
needs (linear per cell); ``results.xdmf`` next to the file lists them for ParaView (XDMF
reader) as a time series. Lengths are in the scene's units (:data:`LENGTH_UNIT`).

Numeric datasets carry Fletcher-32 checksums, so damaged data raises :class:`ResultsError`
instead of being read silently.

``z`` is also the non-repair bound z^{k-1} of the next step. A mesh rebuilt from the arrays
adds vertices and elements in the stored order, so NGSolve numbers its vertices, edges and
faces as in the original mesh and the stored dof vectors apply unchanged; :meth:`MeshArrays.to_mesh`
is checked against the original by point values in the tests.
"""
from __future__ import annotations

import contextlib
import hashlib
import tomllib
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterator, Mapping, Sequence

import h5py
import netgen.meshing as ngm
import ngsolve as ngs
import numpy as np

from .output import atomic_write_text, to_toml
from ..scene import Scene, SceneError

if TYPE_CHECKING:
    from ..solve.stepper import PhaseFieldStepper, StepRecord

FORMAT = "ngfrac-results"
FORMAT_VERSION = 1
"""Version of the layout written here; files from a newer version are refused."""

LENGTH_UNIT = "scene units"
"""The ``units`` attribute of coordinates and displacements: scenes have no unit key, so
lengths are in whatever unit the scene's numbers are (the SENT/SENS demos: mm)."""


class ResultsError(RuntimeError):
    """A results (or checkpoint) file that cannot be used, with a one-line reason."""


# -- meshes as arrays -------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class MeshArrays:
    """A straight-sided simplex mesh as arrays (Netgen numbering, counted from 0).

    Attributes
    ----------
    coordinates : (nv, dim) float64
    cells : (ne, dim + 1) int32
        Triangles (2D) or tetrahedra (3D), vertex numbers in Netgen's local order.
    cell_index : (ne,) int32
        Region number of each cell (1 = ``materials[0]``).
    materials : tuple of str
    facets : (nf, dim) int32
        Boundary segments (2D) or surface triangles (3D), including interior ones (cracks).
    facet_index : (nf,) int32
        Boundary number of each facet (1 = ``boundaries[0]``; names may repeat); in 3D the
        face descriptor.
    boundaries : tuple of str
    facet_domains : (len(boundaries), 2) int32
        3D: the inside and outside domain of each face descriptor (0 = none); 2D: unused.
    """

    coordinates: np.ndarray
    cells: np.ndarray
    cell_index: np.ndarray
    materials: tuple[str, ...]
    facets: np.ndarray
    facet_index: np.ndarray
    boundaries: tuple[str, ...]
    facet_domains: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int32))

    @property
    def dim(self) -> int:
        """2 or 3: the columns of ``coordinates``."""
        return int(self.coordinates.shape[1])

    @property
    def nv(self) -> int:
        return len(self.coordinates)

    @classmethod
    def of(cls, mesh: ngs.Mesh) -> "MeshArrays":
        """Read the arrays of an NGSolve mesh (2D triangles or 3D tetrahedra)."""
        dim = mesh.dim
        ng = mesh.ngmesh
        if dim == 2:
            cells, facets = ng.Elements2D().NumPy(), ng.Elements1D().NumPy()
            boundaries = tuple(mesh.GetBoundaries())  # by segment index
            domains = np.zeros((0, 2), dtype=np.int32)
        elif dim == 3:
            # Surface elements refer to face descriptors, which carry name and neighbours.
            cells, facets = ng.Elements3D().NumPy(), ng.Elements2D().NumPy()
            descriptors = list(ng.FaceDescriptors())
            boundaries = tuple(fd.bcname for fd in descriptors)
            domains = np.array([(fd.domin, fd.domout) for fd in descriptors],
                               dtype=np.int32).reshape(-1, 2)
        else:
            raise ResultsError(f"cannot store a {dim}D mesh; only 2D and 3D meshes are supported")
        return cls(coordinates=np.array(ng.Coordinates(), dtype=np.float64)[:, :dim],
                   cells=_simplices(cells["nodes"], dim + 1, "cells"),
                   cell_index=np.asarray(cells["index"], dtype=np.int32),
                   materials=tuple(mesh.GetMaterials()),
                   facets=_simplices(facets["nodes"], dim, "boundary elements"),
                   facet_index=np.asarray(facets["index"], dtype=np.int32),
                   boundaries=boundaries, facet_domains=domains)

    def to_mesh(self) -> ngs.Mesh:
        """Rebuild the mesh: same vertex and element order, so NGSolve numbers alike."""
        dim = self.dim
        ng = ngm.Mesh(dim=dim)
        ng.AddPoints(np.ascontiguousarray(self.coordinates, dtype=np.float64))
        for name in self.materials:
            ng.AddRegion(name, dim=dim)
        if dim == 2:
            for name in self.boundaries:
                ng.AddRegion(name, dim=1)
        else:
            for i, (name, (inside, outside)) in enumerate(zip(self.boundaries, self.facet_domains)):
                ng.Add(ngm.FaceDescriptor(surfnr=i + 1, domin=int(inside), domout=int(outside),
                                          bc=i + 1))
                ng.SetBCName(i, name)
        # Runs of equal region number keep the element order (and so the numbering) intact.
        for index, block in _runs(self.cell_index, self.cells):
            ng.AddElements(dim=dim, index=index, data=block, base=0)
        for index, block in _runs(self.facet_index, self.facets):
            ng.AddElements(dim=dim - 1, index=index, data=block, base=0)
        return ngs.Mesh(ng)

    def same_as(self, other: "MeshArrays") -> bool:
        """Whether two meshes are identical (same arrays and names)."""
        return (self.materials == other.materials and self.boundaries == other.boundaries
                and all(np.array_equal(getattr(self, name), getattr(other, name))
                        for name in ("coordinates", "cells", "cell_index", "facets",
                                     "facet_index", "facet_domains")))

    def write(self, group: h5py.Group) -> None:
        """Store the arrays in an (empty) HDF5 group."""
        group.attrs["dim"] = self.dim
        for name in ("coordinates", "cells", "cell_index", "facets", "facet_index", "facet_domains"):
            group.create_dataset(name, data=getattr(self, name), fletcher32=True)
        group["coordinates"].attrs["units"] = LENGTH_UNIT
        for name in ("materials", "boundaries"):
            group.create_dataset(name, data=list(getattr(self, name)), dtype=h5py.string_dtype())

    @classmethod
    def read(cls, group: h5py.Group) -> "MeshArrays":
        """Read arrays written by :meth:`write`."""
        arrays = cls(coordinates=group["coordinates"][()], cells=group["cells"][()],
                     cell_index=group["cell_index"][()],
                     materials=tuple(group["materials"].asstr()[()]),
                     facets=group["facets"][()], facet_index=group["facet_index"][()],
                     boundaries=tuple(group["boundaries"].asstr()[()]),
                     facet_domains=group["facet_domains"][()])
        arrays.check()
        return arrays

    def check(self) -> None:
        """Raise :class:`ResultsError` on arrays that do not form a mesh."""
        nv, dim = self.coordinates.shape if self.coordinates.ndim == 2 else (0, 0)
        problems = []
        if dim not in (2, 3):
            problems.append(f"coordinates have shape {self.coordinates.shape}")
        elif self.cells.ndim != 2 or self.cells.shape[1] != dim + 1 or len(self.cells) == 0:
            problems.append(f"cells have shape {self.cells.shape}")
        elif self.cells.min() < 0 or self.cells.max() >= nv:
            problems.append("cells refer to missing vertices")
        elif len(self.facets) and (self.facets.min() < 0 or self.facets.max() >= nv):
            problems.append("boundary elements refer to missing vertices")
        elif len(self.cell_index) != len(self.cells) or len(self.facet_index) != len(self.facets):
            problems.append("region numbers do not match the elements")
        elif (self.cell_index.min() < 1 or self.cell_index.max() > len(self.materials)
              or (len(self.facet_index) and (self.facet_index.min() < 1
                                             or self.facet_index.max() > len(self.boundaries)))):
            problems.append("region numbers lack names")
        if problems:
            raise ResultsError(f"stored mesh is inconsistent: {problems[0]}")


def _simplices(nodes: np.ndarray, n: int, what: str) -> np.ndarray:
    """Netgen node numbers (from 1, zero-padded) as an (m, n) int32 array from 0."""
    nodes = np.asarray(nodes)
    if nodes.ndim != 2 or nodes.shape[1] < n or np.any(nodes[:, n:] != 0) or np.any(nodes[:, :n] <= 0):
        raise ResultsError(f"cannot store this mesh: its {what} are not straight simplices "
                           f"with {n} vertices (second-order or mixed meshes are not supported)")
    return np.ascontiguousarray(nodes[:, :n] - 1, dtype=np.int32)


def _runs(index: np.ndarray, data: np.ndarray) -> Iterator[tuple[int, np.ndarray]]:
    """Consecutive blocks of equal ``index``, in order."""
    if len(index) == 0:
        return
    starts = np.flatnonzero(np.diff(index)) + 1
    for lo, hi in zip(np.r_[0, starts], np.r_[starts, len(index)]):
        yield int(index[lo]), np.ascontiguousarray(data[lo:hi], dtype=np.int32)


# -- fields -----------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class StoredField:
    """A field as stored: the NGSolve space type, order and components, and the dof vector."""

    kind: str
    order: int
    dim: int
    values: np.ndarray

    @classmethod
    def of(cls, gf: ngs.GridFunction) -> "StoredField":
        fes = gf.space
        return cls(fes.type, int(fes.globalorder), int(fes.dim),
                   np.array(gf.vec.FV().NumPy(), dtype=np.float64))

    def write(self, group: h5py.Group, name: str) -> None:
        dset = group.create_dataset(name, data=self.values, fletcher32=True)
        dset.attrs["space"] = self.kind
        dset.attrs["order"] = self.order
        dset.attrs["dim"] = self.dim

    @classmethod
    def read(cls, dset: h5py.Dataset) -> "StoredField":
        return cls(str(dset.attrs["space"]), int(dset.attrs["order"]), int(dset.attrs["dim"]),
                   np.asarray(dset[()], dtype=np.float64))

    def matches(self, fes: ngs.FESpace) -> bool:
        """Whether the dof vector fits ``fes`` (same type, order, components and size)."""
        return (fes.type, fes.globalorder, fes.dim, fes.ndof) == \
            (self.kind, self.order, self.dim, len(self.values))

    def describe(self) -> str:
        return f"{self.kind} of order {self.order} with {len(self.values)} dofs"

    def gridfunction(self, mesh: ngs.Mesh, name: str) -> ngs.GridFunction:
        """A GridFunction on ``mesh`` (rebuilt from the stored arrays) with the stored dofs."""
        flags = {"dim": self.dim} if self.dim > 1 else {}
        try:
            fes = ngs.FESpace(self.kind, mesh, order=self.order, **flags)
        except Exception as err:  # NGSolve raises plain Exceptions for unknown space types
            raise ResultsError(f"field {name!r}: cannot rebuild its space {self.describe()} "
                               f"({_reason(err)})") from None
        if not self.matches(fes):
            raise ResultsError(f"field {name!r} is {self.describe()}, but that space on the "
                               f"stored mesh has {fes.ndof} dofs")
        gf = ngs.GridFunction(fes, name)
        gf.vec.FV().NumPy()[:] = self.values
        return gf

    def vertex_values(self, nv: int) -> np.ndarray | None:
        """Values at the vertices when the dofs hold them directly (scalar hierarchical H1)."""
        return self.values[:nv].copy() if self.kind == "h1ho" and self.dim == 1 else None


def vertex_values(gf: ngs.GridFunction) -> np.ndarray:
    """A GridFunction at the vertices of its mesh: (nv,) for a scalar, (nv, n) for a vector.

    Hierarchical H1 spaces (NGSolve's H1 and VectorH1 of any order) hold the vertex values in
    their first nv dofs (per component); other spaces are evaluated at the vertices.
    """
    mesh = gf.space.mesh
    nv = mesh.nv
    if gf.space.type == "h1ho":
        return np.array(gf.vec.FV().NumPy()[:nv], dtype=np.float64)
    if gf.space.type == "VectorH1" and all(c.space.type == "h1ho" for c in gf.components):
        return np.column_stack([np.array(c.vec.FV().NumPy()[:nv], dtype=np.float64)
                                for c in gf.components])
    x = np.array(mesh.ngmesh.Coordinates())[:, :mesh.dim]
    values = np.asarray(gf(mesh(*(x[:, i] for i in range(mesh.dim)))), dtype=np.float64)
    return values.reshape(nv, -1).squeeze(axis=1) if gf.dim == 1 else values.reshape(nv, -1)


FIELD_UNITS = {"u": LENGTH_UNIT, "z": "1"}
"""The ``units`` attribute of the stored vertex values (other fields: "")."""


# -- file checks ------------------------------------------------------------------------------
@contextlib.contextmanager
def read_hdf5(path: Path, kind: str, error: type[RuntimeError]) -> Iterator[h5py.File]:
    """Open an HDF5 file for reading; any failure inside becomes one line of ``error``."""
    if not path.exists():
        raise error(f"{kind} {str(path)!r} does not exist")
    if not path.is_file():
        raise error(f"{kind} {str(path)!r} is not a file")
    if not h5py.is_hdf5(path):
        raise error(f"{kind} {str(path)!r} is not an HDF5 file")
    try:
        handle = h5py.File(path, "r")
    except OSError as err:
        if "unable to lock file" in str(err):
            raise error(f"{kind} {str(path)!r} is open for writing in another process (a "
                        "running ngfrac?); read it when that run ends, or read a copy") from None
        raise error(f"{kind} {str(path)!r} is truncated or corrupt and cannot be opened "
                    f"({_reason(err)})") from None
    try:
        with handle:
            yield handle
    except KeyError as err:
        raise error(f"{kind} {str(path)!r} lacks {_reason(err)}: it is incomplete or not "
                    "written by ngfrac") from None
    except (OSError, ValueError, TypeError) as err:
        raise error(f"{kind} {str(path)!r} is truncated or corrupt ({_reason(err)})") from None


def _reason(err: BaseException) -> str:
    text = str(err).strip().strip('"').splitlines()
    return text[0] if text else type(err).__name__


def check_format(handle: h5py.File, path: Path, fmt: str, version: int, kind: str,
                 error: type[RuntimeError]) -> int:
    """Check the format marker and version of an open file; returns the version."""
    if handle.attrs.get("format") != fmt:
        raise error(f"{str(path)!r} is not an ngfrac {kind} (format {handle.attrs.get('format')!r})")
    found = int(handle.attrs.get("format_version", -1))
    if found > version:
        raise error(f"{kind} {str(path)!r} has format version {found}, newer than this ngfrac "
                    f"reads ({version}); upgrade ngfrac")
    if found < 1:
        raise error(f"{kind} {str(path)!r} has no valid format version")
    if "scene" not in handle:
        raise error(f"{kind} {str(path)!r} lacks 'scene': it is incomplete")
    return found


def scene_from_toml(text: str, path: Path, error: type[RuntimeError]) -> Scene:
    """The Scene stored as TOML text in a results or checkpoint file."""
    try:
        return Scene.from_dict(tomllib.loads(text))
    except (tomllib.TOMLDecodeError, SceneError) as err:
        raise error(f"{str(path)!r} holds a scene that does not load ({err})") from None


def scene_text(scene: Scene) -> str:
    """The resolved scene as the TOML text stored in files."""
    return to_toml(scene.to_dict())


def write_scene(handle: h5py.File, scene: Scene) -> None:
    """Store the scene as TOML text with a checksum (text datasets have no checksum filter)."""
    text = scene_text(scene)
    handle.create_dataset("scene", data=text, dtype=h5py.string_dtype())
    handle["scene"].attrs["sha256"] = hashlib.sha256(text.encode()).hexdigest()


def read_scene(handle: h5py.File, path: Path, error: type[RuntimeError]) -> tuple[Scene, str]:
    """The stored scene and its TOML text; a changed text raises ``error``."""
    dset = handle["scene"]
    text = dset.asstr()[()]
    if hashlib.sha256(text.encode()).hexdigest() != dset.attrs.get("sha256"):
        raise error(f"{str(path)!r} is corrupt: its scene text does not match its checksum")
    return scene_from_toml(text, path, error), text


IGNORED_KEYS = ("output", "time.t_end")
"""Scene keys a continued run may change: they do not change the steps already taken."""


def _flatten(data: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(data, dict):
        out: dict[str, Any] = {}
        for key, value in data.items():
            out.update(_flatten(value, f"{prefix}.{key}" if prefix else str(key)))
        return out
    if isinstance(data, list) and any(isinstance(v, dict) for v in data):
        out = {}
        for i, value in enumerate(data):
            out.update(_flatten(value, f"{prefix}[{i}]"))
        return out
    return {prefix: data}


def _solution_keys(scene: Scene) -> dict[str, Any]:
    """The scene's keys that change the solution (all but :data:`IGNORED_KEYS`)."""
    return {key: value for key, value in _flatten(scene.to_dict()).items()
            if not any(key == k or key.startswith(k + ".") for k in IGNORED_KEYS)}


def scene_hash(scene: Scene) -> str:
    """SHA-256 of the keys that change the solution."""
    text = "\n".join(f"{key} = {value!r}" for key, value in sorted(_solution_keys(scene).items()))
    return hashlib.sha256(text.encode()).hexdigest()


def scene_differences(stored: Scene, current: Scene) -> list[str]:
    """One description per solution key that differs between two scenes."""
    a, b = _solution_keys(stored), _solution_keys(current)
    return [f"{key} = {_show(a, key)} there, {_show(b, key)} here"
            for key in sorted(set(a) | set(b)) if a.get(key, a) != b.get(key, b)]


def _show(values: dict[str, Any], key: str) -> str:
    return repr(values[key]) if key in values else "(absent)"


# -- writing ----------------------------------------------------------------------------------
class ResultsWriter:
    """Writes one run's results file; every write is flushed to disk.

    Parameters
    ----------
    path : path of the ``.h5`` file to create
    scene : the resolved scene, stored as TOML
    columns : history column names (by default those of the first record appended)
    overwrite : replace an existing file (otherwise an existing file is an error)

    Examples
    --------
    >>> with ResultsWriter(out / "results.h5", scene) as results:   # doctest: +SKIP
    ...     results.write_snapshot(stepper)
    ...     for record in stepper.run():
    ...         results.append(record)
    """

    def __init__(self, path: str | Path, scene: Scene, columns: Sequence[str] | None = None,
                 overwrite: bool = False) -> None:
        path = Path(path)
        if path.exists() and not overwrite:
            raise ResultsError(f"results file {str(path)!r} exists; pass overwrite=True "
                               "(ngfrac run --overwrite) to replace it")
        try:
            f = h5py.File(path, "w")
        except OSError as err:
            raise ResultsError(f"cannot create results file {str(path)!r} ({_reason(err)})") from None
        f.attrs["format"] = FORMAT
        f.attrs["format_version"] = FORMAT_VERSION
        write_scene(f, scene)
        # Without given columns the first record names them (its force columns vary by scene).
        n = len(columns) if columns is not None else 0
        history = f.create_dataset("history", shape=(0, n), dtype=np.float64,
                                   maxshape=(None, None), chunks=(64, max(n, 32)), fletcher32=True)
        history.attrs["columns"] = list(columns or [])
        f.create_group("snapshots")
        f.flush()
        self._attach(path, scene, f)
        self.write_xdmf()  # an index of no snapshots yet: the file exists from the start

    def _attach(self, path: Path, scene: Scene, handle: h5py.File) -> None:
        self.path = path
        self.scene = scene
        self._file = handle
        self.columns = [str(c) for c in handle["history"].attrs["columns"]]
        self._last_mesh: tuple[MeshArrays, str] | None = None

    @classmethod
    def resume(cls, path: str | Path, scene: Scene, step: int) -> "ResultsWriter":
        """Reopen a results file to continue a run from ``step``.

        History rows and snapshots after ``step`` (written after the checkpoint the run
        restarts from) are removed. A file of another scene raises :class:`ResultsError`.
        """
        path = Path(path)
        with read_hdf5(path, "results file", ResultsError) as f:
            check_format(f, path, FORMAT, FORMAT_VERSION, "results file", ResultsError)
            stored, stored_text = read_scene(f, path, ResultsError)
            columns = [str(c) for c in f["history"].attrs["columns"]]
            f["snapshots"]  # noqa: B018 - a missing group raises here, with a clear message
        differences = scene_differences(stored, scene)
        if differences:
            raise ResultsError(f"results file {str(path)!r} belongs to another scene "
                               f"({differences[0]})")
        if columns and "step" not in columns:
            raise ResultsError(f"results file {str(path)!r} has no 'step' column in its history")
        writer = cls.__new__(cls)
        writer._attach(path, scene, h5py.File(path, "a"))
        f = writer._file
        history = f["history"]
        if columns:
            steps = history[:, columns.index("step")]
            history.resize(int(np.count_nonzero(steps <= step)), axis=0)  # rows in step order
        for name in list(f["snapshots"]):
            if int(f["snapshots"][name].attrs["step"]) > step:
                del f["snapshots"][name]
        if stored_text != scene_text(scene):  # a longer time.t_end, other [output] keys
            writer.replace_scene(scene)
        f.flush()
        writer.write_xdmf()
        return writer

    def replace_scene(self, scene: Scene) -> None:
        """Store ``scene`` instead of the file's scene (a restart that runs longer)."""
        with self._writing():
            del self._file["scene"]
            write_scene(self._file, scene)
            self.scene = scene
            self._file.flush()

    def set_attributes(self, attributes: Mapping[str, Any]) -> None:
        """Store run metadata as root attributes: lists and dicts as JSON text, None left out."""
        import json

        with self._writing():
            for key, value in attributes.items():
                if key in ("format", "format_version"):
                    continue  # the run.json's own format marker, not the file's
                if isinstance(value, (list, dict)):
                    value = json.dumps(value)
                if value is not None:
                    self._file.attrs[key] = value
            self._file.flush()

    # -- history --
    def append(self, record: "StepRecord | Sequence[float]") -> None:
        """Append one history row (a StepRecord or values in column order)."""
        row = record.row() if hasattr(record, "row") else list(record)
        with self._writing():
            history = self._file["history"]
            if not self.columns:
                if not hasattr(record, "header"):
                    raise ValueError("the first history row must be a StepRecord when the "
                                     "writer was made without columns")
                self.columns = list(record.header())
                history.attrs["columns"] = self.columns
            if len(row) != len(self.columns):
                raise ValueError(f"history row has {len(row)} values, the table has "
                                 f"{len(self.columns)} columns")
            n = history.shape[0]
            history.resize((n + 1, len(self.columns)))
            history[n] = np.asarray(row, dtype=np.float64)
            self._file.flush()

    @contextlib.contextmanager
    def _writing(self) -> Iterator[None]:
        try:
            yield
        except OSError as err:
            raise ResultsError(f"cannot write to results file {str(self.path)!r} "
                               f"({_reason(err)})") from None

    # -- snapshots --
    @property
    def n_snapshots(self) -> int:
        return len(self._file["snapshots"])

    def write_snapshot(self, stepper: "PhaseFieldStepper") -> str:
        """Store the stepper's u and z (z is also the non-repair bound) on its mesh."""
        return self.write_fields(stepper.mesh, {"u": stepper.u, "z": stepper.z},
                                 t=stepper.t, step=stepper.k)

    def write_fields(self, mesh: ngs.Mesh, fields: Mapping[str, ngs.GridFunction], t: float,
                     step: int) -> str:
        """Store named GridFunctions on ``mesh`` at time ``t``; returns the snapshot name."""
        arrays = MeshArrays.of(mesh)
        with self._writing():
            name = f"{self._next_number():05d}"
            group = self._file["snapshots"].create_group(name)
            group.attrs["t"] = float(t)
            group.attrs["step"] = int(step)
            if self._last_mesh is not None and self._last_mesh[0].same_as(arrays):
                group["mesh"] = self._file[self._last_mesh[1]]  # a hard link: no second copy
            else:
                arrays.write(group.create_group("mesh"))
            self._last_mesh = (arrays, group["mesh"].name)
            data = group.create_group("fields")
            at_vertices = group.create_group("vertex_values")
            for field_name, gf in fields.items():
                StoredField.of(gf).write(data, field_name)
                dset = at_vertices.create_dataset(field_name, data=vertex_values(gf),
                                                  fletcher32=True)
                dset.attrs["units"] = FIELD_UNITS.get(field_name, "")
            self._file.flush()
        self.write_xdmf()
        return name

    @property
    def xdmf_path(self) -> Path:
        """``results.xdmf`` next to ``results.h5``."""
        return self.path.with_suffix(".xdmf")

    def write_xdmf(self) -> Path:
        """(Re)write the XDMF index of the snapshots (ParaView's XDMF reader, meshio)."""
        atomic_write_text(self.xdmf_path, xdmf_text(self._file, self.path.name))
        return self.xdmf_path

    def _next_number(self) -> int:
        names = list(self._file["snapshots"])
        return max((int(n) for n in names), default=-1) + 1

    def close(self) -> None:
        if self._file.id.valid:
            self._file.close()

    def __enter__(self) -> "ResultsWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def xdmf_text(handle: h5py.File, h5_name: str) -> str:
    """An XDMF 3 temporal collection of the snapshots in an open results file: per snapshot
    the mesh (coordinates, cells) and every ``vertex_values`` dataset as node data."""
    lines = ['<?xml version="1.0"?>', '<Xdmf Version="3.0">', "  <Domain>",
             '    <Grid Name="snapshots" GridType="Collection" CollectionType="Temporal">']

    def item(dset: h5py.Dataset, path: str) -> str:
        kind, precision = ("Int", 4) if dset.dtype.kind == "i" else ("Float", 8)
        dims = " ".join(str(n) for n in dset.shape)
        return (f'          <DataItem Dimensions="{dims}" NumberType="{kind}" '
                f'Precision="{precision}" Format="HDF">{h5_name}:{path}</DataItem>')

    for name in sorted(handle["snapshots"]):
        group = handle["snapshots"][name]
        if "vertex_values" not in group:
            continue  # written before vertex values were stored
        mesh = group["mesh"]
        cells, coordinates = mesh["cells"], mesh["coordinates"]
        path = group.name
        topology = "Triangle" if coordinates.shape[1] == 2 else "Tetrahedron"
        lines += [f'      <Grid Name="{name}" GridType="Uniform">',
                  f'        <Time Value="{float(group.attrs["t"])!r}"/>',
                  f'        <Topology TopologyType="{topology}" NumberOfElements="{len(cells)}">',
                  item(cells, f"{path}/mesh/cells"),
                  "        </Topology>",
                  f'        <Geometry GeometryType="{"XY" if coordinates.shape[1] == 2 else "XYZ"}">',
                  item(coordinates, f"{path}/mesh/coordinates"),
                  "        </Geometry>"]
        for field_name, dset in group["vertex_values"].items():
            kind = "Scalar" if dset.ndim == 1 else "Vector"
            lines += [f'        <Attribute Name="{field_name}" AttributeType="{kind}" Center="Node">',
                      item(dset, f"{path}/vertex_values/{field_name}"), "        </Attribute>"]
        lines.append("      </Grid>")
    lines += ["    </Grid>", "  </Domain>", "</Xdmf>", ""]
    return "\n".join(lines)


# -- reading ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class SnapshotArrays:
    """A snapshot as numpy arrays: vertex coordinates, cells and vertex values."""

    coordinates: np.ndarray
    cells: np.ndarray
    t: float
    step: int
    values: dict[str, np.ndarray]

    @property
    def u(self) -> np.ndarray:
        return self.values["u"]

    @property
    def z(self) -> np.ndarray:
        return self.values["z"]


class Snapshot:
    """The fields of one snapshot; the mesh is rebuilt on first use."""

    def __init__(self, path: Path, name: str, t: float, step: int, mesh: MeshArrays,
                 stored: dict[str, StoredField],
                 at_vertices: dict[str, np.ndarray] | None = None) -> None:
        self.path = path
        self.name = name
        self.t = t
        self.step = step
        self.mesh_arrays = mesh
        self._stored = stored
        self._at_vertices = at_vertices or {}

    @property
    def field_names(self) -> list[str]:
        return list(self._stored)

    @cached_property
    def mesh(self) -> ngs.Mesh:
        """The NGSolve mesh rebuilt from the stored arrays."""
        return self.mesh_arrays.to_mesh()

    @cached_property
    def fields(self) -> dict[str, ngs.GridFunction]:
        """All stored fields as GridFunctions on :attr:`mesh`."""
        try:
            return {name: stored.gridfunction(self.mesh, name)
                    for name, stored in self._stored.items()}
        except ResultsError as err:
            raise ResultsError(f"snapshot {self.name} of {str(self.path)!r}: {err}") from None

    @property
    def u(self) -> ngs.GridFunction:
        return self.fields["u"]

    @property
    def z(self) -> ngs.GridFunction:
        """The phase field, also the non-repair bound of the next step."""
        return self.fields["z"]

    def arrays(self) -> SnapshotArrays:
        """Coordinates, cells and vertex values of every field, as numpy arrays."""
        nv = self.mesh_arrays.nv
        values = {}
        for name, stored in self._stored.items():
            direct = self._at_vertices.get(name)
            if direct is None:
                direct = stored.vertex_values(nv)
            if direct is None:
                x = self.mesh_arrays.coordinates
                points = self.mesh(*(x[:, i] for i in range(x.shape[1])))
                direct = np.asarray(self.fields[name](points)).reshape(nv, -1).squeeze()
            values[name] = direct
        return SnapshotArrays(self.mesh_arrays.coordinates.copy(), self.mesh_arrays.cells.copy(),
                              self.t, self.step, values)


class Results:
    """A results file opened for reading (see :func:`open_results`)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        with self._open() as f:
            self.format_version = check_format(f, path, FORMAT, FORMAT_VERSION, "results file",
                                               ResultsError)
            self.scene, self.scene_toml = read_scene(f, path, ResultsError)
            history = f["history"]
            columns = [str(c) for c in history.attrs["columns"]]
            table = history[()]
            if table.ndim != 2 or table.shape[1] != len(columns):
                raise ResultsError(f"results file {str(path)!r}: the history table has shape "
                                   f"{table.shape} for {len(columns)} columns")
            self.history: dict[str, np.ndarray] = {c: table[:, i].copy() for i, c in enumerate(columns)}
            snapshots = f["snapshots"]
            self._names = sorted(snapshots)
            self._times = np.array([float(snapshots[n].attrs["t"]) for n in self._names])
            self._steps = np.array([int(snapshots[n].attrs["step"]) for n in self._names], dtype=int)

    def _open(self) -> contextlib.AbstractContextManager[h5py.File]:
        return read_hdf5(self.path, "results file", ResultsError)

    def __len__(self) -> int:
        return len(self._names)

    def snapshot_times(self) -> np.ndarray:
        """Times of the snapshots, in the order written."""
        return self._times.copy()

    def snapshot_steps(self) -> np.ndarray:
        return self._steps.copy()

    def snapshot(self, i: int) -> Snapshot:
        """Snapshot number ``i`` (negative counts from the end)."""
        n = len(self._names)
        if not -n <= i < n:
            raise IndexError(f"snapshot {i} does not exist; the file has {n} snapshots")
        name = self._names[i]
        with self._open() as f:
            group = f["snapshots"][name]
            mesh = MeshArrays.read(group["mesh"])
            stored = {field_name: StoredField.read(d) for field_name, d in group["fields"].items()}
            at_vertices = ({field_name: d[()] for field_name, d in group["vertex_values"].items()}
                           if "vertex_values" in group else {})
        return Snapshot(self.path, name, float(self._times[i]), int(self._steps[i]), mesh, stored,
                        at_vertices)

    def snapshot_at(self, t: float) -> Snapshot:
        """The snapshot nearest to time ``t``."""
        if not len(self._names):
            raise ResultsError(f"results file {str(self.path)!r} has no snapshots")
        return self.snapshot(int(np.argmin(np.abs(self._times - t))))


def open_results(path: str | Path) -> Results:
    """Open a results file written by :class:`ResultsWriter`.

    Raises :class:`ResultsError` with a one-line reason for a missing, foreign, truncated or
    corrupt file, or one from a newer ngfrac.
    """
    return Results(Path(path))


__all__ = ["FORMAT_VERSION", "LENGTH_UNIT", "MeshArrays", "Results", "ResultsError", "ResultsWriter",
           "Snapshot", "SnapshotArrays", "StoredField", "open_results", "vertex_values"]
