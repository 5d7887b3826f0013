"""HDF5 results: the history table, the resolved scene and field snapshots with their meshes.

A results file can be read back without the run: :func:`open_results` gives the scene, the
history as numpy columns and each snapshot's fields as NGSolve GridFunctions on a mesh rebuilt
from the stored arrays, or as plain numpy arrays.

Layout (``format_version`` 1)::

    /                      attrs: format = "ngfrac-results", format_version, units (the
                           scene's unit system)
    /scene                 the resolved scene as TOML text; attrs: sha256
    /history               float64 (rows, columns), resizable; attrs: columns, units (one
                           per column)
    /snapshots/00000       attrs: t, step
        mesh/              see :class:`~ngfrac.io.hdf5.MeshArrays` (a hard link to the previous snapshot's
                           mesh group when the mesh did not change)
        fields/u, fields/z dof vectors; attrs: space (NGSolve type), order, dim
        vertex_values/u, /z the fields at the vertices, (nv,) or (nv, components), in the
                           order of mesh/coordinates; attrs: units

For readers without NGSolve, ``mesh/coordinates`` (nv, dim; attrs: units), ``mesh/cells``
(triangles or tetrahedra, vertex numbers from 0) and ``vertex_values`` are all a snapshot
needs (linear per cell); ``results.xdmf`` next to the file lists them for ParaView (XDMF
reader) as a time series. The ``units`` attributes name the units of the scene's unit system
(the top-level key ``units``; "scene units" by default).

Numeric datasets carry Fletcher-32 checksums, so damaged data raises
:class:`~ngfrac.io.hdf5.ResultsError` instead of being read silently. Meshes, fields and the
stored scene are written by the HDF5 layer that checkpoints share (:mod:`ngfrac.io.hdf5`).

``z`` is also the non-repair bound z^{k-1} of the next step.
"""
from __future__ import annotations

import contextlib
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterator, Mapping, Sequence

import h5py
import ngsolve as ngs
import numpy as np

from .hdf5 import (LENGTH_UNIT, MeshArrays, ResultsError, StoredField, check_format,
                   error_reason, read_hdf5, read_scene, scene_differences, scene_text,
                   write_scene)
from .output import atomic_write_text
from ..scene import Scene

if TYPE_CHECKING:
    from ..solve.stepper import PhaseFieldStepper, StepRecord

FORMAT = "ngfrac-results"
FORMAT_VERSION = 1
"""Version of the layout written here; files from a newer version are refused."""


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
"""The ``units`` attribute of the stored vertex values (other fields: ""); u's is the length
unit of the scene's ``units`` (:mod:`ngfrac.scene.units`)."""


def _column_units(columns: list[str], scene: Scene) -> list[str]:
    """The ``units`` attribute of /history: one per column (:func:`ngfrac.scene.units.column_units`)."""
    from ..scene.units import column_units, unit_system

    return column_units(columns, unit_system(scene.units), scene.geometry.dim)


# -- writing ----------------------------------------------------------------------------------
class ResultsWriter:
    """Writes one run's results file; every write is flushed to disk.

    Parameters
    ----------
    path : str or Path
        The ``.h5`` file to create.
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
            raise ResultsError(f"cannot create results file {str(path)!r} ({error_reason(err)})") from None
        f.attrs["format"] = FORMAT
        f.attrs["format_version"] = FORMAT_VERSION
        f.attrs["units"] = scene.units
        write_scene(f, scene)
        # Without given columns the first record names them (its force columns vary by scene).
        n = len(columns) if columns is not None else 0
        history = f.create_dataset("history", shape=(0, n), dtype=np.float64,
                                   maxshape=(None, None), chunks=(64, max(n, 32)), fletcher32=True)
        history.attrs["columns"] = list(columns or [])
        history.attrs["units"] = _column_units(list(columns or []), scene)
        f.create_group("snapshots")
        f.flush()
        self._attach(path, scene, f)
        self.write_xdmf()  # an index of no snapshots yet: the file exists from the start

    @property
    def _units(self) -> Any:
        from ..scene.units import unit_system

        return unit_system(self.scene.units)

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
        restarts from) are removed. A file of another scene raises :class:`~ngfrac.io.hdf5.ResultsError`.
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
        if stored_text != scene_text(scene, path.parent):  # a longer time.t_end, other [output] keys
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
                history.attrs["units"] = _column_units(self.columns, self.scene)
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
                               f"({error_reason(err)})") from None

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
            group["mesh/coordinates"].attrs["units"] = self._units.length
            data = group.create_group("fields")
            at_vertices = group.create_group("vertex_values")
            for field_name, gf in fields.items():
                StoredField.of(gf).write(data, field_name)
                dset = at_vertices.create_dataset(field_name, data=vertex_values(gf),
                                                  fletcher32=True)
                dset.attrs["units"] = (self._units.length if field_name == "u"
                                       else FIELD_UNITS.get(field_name, ""))
            self._file.flush()
        self.write_xdmf()
        return name

    @property
    def xdmf_path(self) -> Path:
        """``results.xdmf`` next to ``results.h5``."""
        return self.path.with_suffix(".xdmf")

    manifest: Any = None
    """The run folder's :class:`~ngfrac.io.output.Manifest` (set by the run's writer): the
    per-mesh XDMF files are listed in it before they are written."""

    def write_xdmf(self) -> Path:
        """(Re)write the XDMF indexes of the snapshots: ``results.xdmf``, every snapshot with
        its own grid (ParaView's XDMF reader), and one ``results_mesh_NNN.xdmf`` per mesh
        with the snapshots on it, as meshio's ``TimeSeriesReader`` reads them (one mesh per
        file); files of meshes no longer in the results (a restart dropped them) are removed."""
        per_mesh = mesh_series(self._file)
        names = [f"{self.path.stem}_mesh_{i:03d}.xdmf" for i in range(len(per_mesh))]
        folder = self.path.parent
        listed = (self.manifest.writing(*names) if self.manifest is not None and names
                  else contextlib.nullcontext())
        with listed:
            for name, snapshots in zip(names, per_mesh):
                atomic_write_text(folder / name, xdmf_text(self._file, self.path.name, snapshots,
                                                           mesh_grid=True))
        atomic_write_text(self.xdmf_path, xdmf_text(self._file, self.path.name))
        for stale in sorted(folder.glob(f"{self.path.stem}_mesh_[0-9][0-9][0-9].xdmf")):
            if stale.name not in names and (self.manifest is None
                                            or self.manifest.owns(stale.name)):
                stale.unlink()
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


def mesh_series(handle: h5py.File) -> list[list[str]]:
    """The names of the snapshots (with vertex values) in an open results file, grouped by
    mesh, in order: a snapshot whose mesh group is the previous one's (a hard link) joins its
    group."""
    groups: list[list[str]] = []
    last = None
    for name in sorted(handle["snapshots"]):
        group = handle["snapshots"][name]
        if "vertex_values" not in group:
            continue
        mesh = group["mesh"]
        if last is None or mesh != last:
            groups.append([])
        groups[-1].append(name)
        last = mesh
    return groups


def xdmf_text(handle: h5py.File, h5_name: str, names: Sequence[str] | None = None,
              mesh_grid: bool = False) -> str:
    """An XDMF 3 temporal collection of snapshots in an open results file (``names``, default
    all): per snapshot its own grid, the mesh (coordinates, cells) and every ``vertex_values``
    dataset as node data. ``mesh_grid``: also the first snapshot's mesh as a grid of its own
    before the collection, the layout of meshio's ``TimeSeriesReader`` (all ``names`` on one
    mesh, :func:`mesh_series`)."""
    lines = ['<?xml version="1.0"?>', '<Xdmf Version="3.0">', "  <Domain>"]

    def item(dset: h5py.Dataset, path: str, indent: str = "          ") -> str:
        kind, precision = ("Int", 4) if dset.dtype.kind == "i" else ("Float", 8)
        dims = " ".join(str(n) for n in dset.shape)
        return (f'{indent}<DataItem Dimensions="{dims}" NumberType="{kind}" '
                f'Precision="{precision}" Format="HDF">{h5_name}:{path}</DataItem>')

    def mesh_lines(group: h5py.Group, indent: str) -> list[str]:
        mesh = group["mesh"]
        cells, coordinates = mesh["cells"], mesh["coordinates"]
        topology = "Triangle" if coordinates.shape[1] == 2 else "Tetrahedron"
        geometry = "XY" if coordinates.shape[1] == 2 else "XYZ"
        return [f'{indent}<Topology TopologyType="{topology}" NumberOfElements="{len(cells)}">',
                item(cells, f"{group.name}/mesh/cells", indent + "  "), f"{indent}</Topology>",
                f'{indent}<Geometry GeometryType="{geometry}">',
                item(coordinates, f"{group.name}/mesh/coordinates", indent + "  "),
                f"{indent}</Geometry>"]

    snapshots = handle["snapshots"]
    chosen = [name for name in (sorted(snapshots) if names is None else names)
              if "vertex_values" in snapshots[name]]  # older files: written before them
    if mesh_grid and chosen:
        lines += ['    <Grid Name="mesh" GridType="Uniform">',
                  *mesh_lines(snapshots[chosen[0]], "      "), "    </Grid>"]
    lines.append('    <Grid Name="snapshots" GridType="Collection" CollectionType="Temporal">')
    for name in chosen:
        group = snapshots[name]
        path = group.name
        lines += [f'      <Grid Name="{name}" GridType="Uniform">',
                  f'        <Time Value="{float(group.attrs["t"])!r}"/>',
                  *mesh_lines(group, "        ")]
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

    Raises :class:`~ngfrac.io.hdf5.ResultsError` with a one-line reason for a missing, foreign, truncated or
    corrupt file, or one from a newer ngfrac.
    """
    return Results(Path(path))


__all__ = ["FORMAT_VERSION", "Results", "ResultsWriter", "Snapshot", "SnapshotArrays",
           "mesh_series", "open_results", "vertex_values", "xdmf_text"]
