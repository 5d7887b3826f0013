"""The HDF5 layer that results files and checkpoints share: meshes and fields as arrays,
opening a file with one-line errors, the format marker, and the stored scene.

A mesh rebuilt from :class:`MeshArrays` adds vertices and elements in the stored order, so
NGSolve numbers its vertices, edges and faces as in the original mesh and a stored dof vector
(:class:`StoredField`) applies unchanged. Numeric datasets carry Fletcher-32 checksums and the
scene text a SHA-256, so damaged data raises an error instead of being read silently.
"""
from __future__ import annotations

import contextlib
import hashlib
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

import h5py
import netgen.meshing as ngm
import ngsolve as ngs
import numpy as np

from .output import to_toml
from ..scene import Scene, SceneError

__all__ = ["IGNORED_KEYS", "LENGTH_UNIT", "MeshArrays", "ResultsError", "StoredField",
           "check_format", "error_reason", "read_hdf5", "read_scene", "scene_differences",
           "scene_from_toml", "scene_hash", "scene_text", "write_scene"]

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
    geometry_numbers : (len(boundaries),) int32
        The geometry's edge (2D) or face (3D) number of each boundary (edge or face
        descriptor), so that a rebuilt mesh given its geometry again can be curved again
        (:meth:`ngfrac.geometry.cad.OccDomain.curve`); empty when unknown (files written before).
    """

    coordinates: np.ndarray
    cells: np.ndarray
    cell_index: np.ndarray
    materials: tuple[str, ...]
    facets: np.ndarray
    facet_index: np.ndarray
    boundaries: tuple[str, ...]
    facet_domains: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int32))
    geometry_numbers: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))

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
            numbers = [ng.EdgeDescriptor(i + 1).edgenr for i in range(ng.GetNED())]
        elif dim == 3:
            # Surface elements refer to face descriptors, which carry name and neighbours.
            cells, facets = ng.Elements3D().NumPy(), ng.Elements2D().NumPy()
            descriptors = list(ng.FaceDescriptors())
            boundaries = tuple(fd.bcname for fd in descriptors)
            domains = np.array([(fd.domin, fd.domout) for fd in descriptors],
                               dtype=np.int32).reshape(-1, 2)
            numbers = [fd.surfnr for fd in descriptors]
        else:
            raise ResultsError(f"cannot store a {dim}D mesh; only 2D and 3D meshes are supported")
        return cls(coordinates=np.array(ng.Coordinates(), dtype=np.float64)[:, :dim],
                   cells=_simplices(cells["nodes"], dim + 1, "cells"),
                   cell_index=np.asarray(cells["index"], dtype=np.int32),
                   materials=tuple(mesh.GetMaterials()),
                   facets=_simplices(facets["nodes"], dim, "boundary elements"),
                   facet_index=np.asarray(facets["index"], dtype=np.int32),
                   boundaries=boundaries, facet_domains=domains,
                   geometry_numbers=np.array(numbers if len(numbers) == len(boundaries) else [],
                                             dtype=np.int32))

    def to_mesh(self) -> ngs.Mesh:
        """Rebuild the mesh: same vertex and element order, so NGSolve numbers alike."""
        dim = self.dim
        ng = ngm.Mesh(dim=dim)
        ng.AddPoints(np.ascontiguousarray(self.coordinates, dtype=np.float64))
        for name in self.materials:
            ng.AddRegion(name, dim=dim)
        numbers = (self.geometry_numbers.tolist() if len(self.geometry_numbers)
                   else list(range(1, len(self.boundaries) + 1)))
        if dim == 2:
            for i, name in enumerate(self.boundaries):
                ng.AddRegion(name, dim=1)
                if len(self.geometry_numbers):  # the edge of the geometry it lies on
                    ng.EdgeDescriptor(i + 1).edgenr = numbers[i]
        else:
            for i, (name, (inside, outside)) in enumerate(zip(self.boundaries, self.facet_domains)):
                ng.Add(ngm.FaceDescriptor(surfnr=numbers[i], domin=int(inside),
                                          domout=int(outside), bc=i + 1))
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
                                     "facet_index", "facet_domains", "geometry_numbers")))

    def write(self, group: h5py.Group) -> None:
        """Store the arrays in an (empty) HDF5 group."""
        group.attrs["dim"] = self.dim
        for name in ("coordinates", "cells", "cell_index", "facets", "facet_index", "facet_domains"):
            group.create_dataset(name, data=getattr(self, name), fletcher32=True)
        if len(self.geometry_numbers):
            group.create_dataset("geometry_numbers", data=self.geometry_numbers, fletcher32=True)
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
                     facet_domains=group["facet_domains"][()],
                     geometry_numbers=(group["geometry_numbers"][()] if "geometry_numbers" in group
                                       else np.zeros(0, dtype=np.int32)))
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
        elif len(self.geometry_numbers) not in (0, len(self.boundaries)):
            problems.append("geometry numbers do not match the boundaries")
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
                               f"({error_reason(err)})") from None
        if not self.matches(fes):
            raise ResultsError(f"field {name!r} is {self.describe()}, but that space on the "
                               f"stored mesh has {fes.ndof} dofs")
        gf = ngs.GridFunction(fes, name)
        gf.vec.FV().NumPy()[:] = self.values
        return gf

    def vertex_values(self, nv: int) -> np.ndarray | None:
        """Values at the vertices when the dofs hold them directly (scalar hierarchical H1)."""
        return self.values[:nv].copy() if self.kind == "h1ho" and self.dim == 1 else None


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
                    f"({error_reason(err)})") from None
    try:
        with handle:
            yield handle
    except KeyError as err:
        raise error(f"{kind} {str(path)!r} lacks {error_reason(err)}: it is incomplete or not "
                    "written by ngfrac") from None
    except (OSError, ValueError, TypeError) as err:
        raise error(f"{kind} {str(path)!r} is truncated or corrupt ({error_reason(err)})") from None


def error_reason(err: BaseException) -> str:
    """The first line of an exception's message (its type name when it has none)."""
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


def scene_from_toml(text: str, path: Path, error: type[RuntimeError],
                    folder: Path | None = None) -> Scene:
    """The Scene stored as TOML text in a results or checkpoint file (a relative
    ``geometry.file`` found in ``folder`` is read from there)."""
    from .output import resolve_scene_file

    try:
        data = tomllib.loads(text)
        return Scene.from_dict(data if folder is None else resolve_scene_file(data, folder))
    except (tomllib.TOMLDecodeError, SceneError) as err:
        raise error(f"{str(path)!r} holds a scene that does not load ({err})") from None


def scene_text(scene: Scene, folder: Path | None = None) -> str:
    """The resolved scene as the TOML text stored in files (in ``folder``: a CAD file copied
    there named relative to it)."""
    from .output import portable_scene_dict

    data = scene.to_dict()
    return to_toml(data if folder is None else portable_scene_dict(data, folder))


def write_scene(handle: h5py.File, scene: Scene) -> None:
    """Store the scene as TOML text with a checksum (text datasets have no checksum filter).

    A ``geometry.file`` copied into the file's folder (a run folder) is stored by its name,
    relative to that folder (:func:`~ngfrac.io.output.portable_scene_dict`)."""
    text = scene_text(scene, Path(handle.filename).parent)
    handle.create_dataset("scene", data=text, dtype=h5py.string_dtype())
    handle["scene"].attrs["sha256"] = hashlib.sha256(text.encode()).hexdigest()


def read_scene(handle: h5py.File, path: Path, error: type[RuntimeError]) -> tuple[Scene, str]:
    """The stored scene and its TOML text; a changed text raises ``error``."""
    dset = handle["scene"]
    text = dset.asstr()[()]
    if hashlib.sha256(text.encode()).hexdigest() != dset.attrs.get("sha256"):
        raise error(f"{str(path)!r} is corrupt: its scene text does not match its checksum")
    return scene_from_toml(text, path, error, Path(path).parent), text


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
