"""Compact VTU snapshots: one point per mesh vertex, binary and zlib-compressed.

NGSolve's ``VTKOutput`` writes ASCII and every element on its own (refined ``subdivision``
times), which shows P2 fields faithfully but is slow and large in 3D. This writer stores the
mesh once per file: the vertices, the simplices, the continuous fields (H1 GridFunctions: u,
z) at the vertices and every other field (stress, energy density, estimator, ...) at each
element's centroid. The files are VTK XML UnstructuredGrid with base64 binary arrays,
each compressed with zlib (``compressor="vtkZLibDataCompressor"``), which ParaView and meshio
read.
"""
from __future__ import annotations

import base64
import struct
import zlib
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import ngsolve as ngs

from ..fem.elements import ElementGeometry
from ..fem.nodal import vertex_dofs_first

__all__ = ["VTK_TRIANGLE", "VTK_TETRA", "snapshot_arrays", "write_vtu"]

VTK_TRIANGLE = 5
VTK_TETRA = 10

_TYPES = {np.dtype(np.float64): "Float64", np.dtype(np.int64): "Int64",
          np.dtype(np.uint8): "UInt8"}


def _encoded(array: np.ndarray, level: int) -> str:
    """One VTK compressed binary array: the UInt64 header (one block; its raw size as the
    block size and as the last block's; its compressed size) base64 encoded, then the zlib
    stream base64 encoded on its own (VTK's layout for inline compressed data)."""
    raw = np.ascontiguousarray(array).tobytes()
    packed = zlib.compress(raw, level)
    header = struct.pack("<4Q", 1, len(raw), len(raw), len(packed))
    return (base64.b64encode(header) + base64.b64encode(packed)).decode("ascii")


def _data_array(name: str, array: np.ndarray, level: int) -> str:
    array = np.asarray(array)
    components = "" if array.ndim == 1 else f' NumberOfComponents="{array.shape[1]}"'
    kind = _TYPES[array.dtype]
    return (f'<DataArray type="{kind}" Name="{name}"{components} format="binary">'
            f'{_encoded(array, level)}</DataArray>')


def write_vtu(path: str | Path, points: np.ndarray, cells: np.ndarray,
              point_data: Mapping[str, np.ndarray] | None = None,
              cell_data: Mapping[str, np.ndarray] | None = None, level: int = 1) -> Path:
    """Write an unstructured grid of simplices as a compressed binary ``.vtu``.

    Parameters
    ----------
    path : str or Path
        The file.
    points : (n, 2) or (n, 3) array
        Vertex coordinates (2D points get z = 0).
    cells : (m, 3) or (m, 4) int array
        Triangles or tetrahedra, vertex numbers from 0.
    point_data, cell_data : dict of name to array, optional
        One value (a row of components) per point, per cell.
    level : int
        zlib's compression level (1: fast, the default; 9: small).

    Returns
    -------
    Path
        ``path``.
    """
    points = np.asarray(points, dtype=np.float64)
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    cells = np.asarray(cells, dtype=np.int64)
    corners = cells.shape[1]
    kind = {3: VTK_TRIANGLE, 4: VTK_TETRA}[corners]
    offsets = np.arange(1, len(cells) + 1, dtype=np.int64) * corners
    types = np.full(len(cells), kind, dtype=np.uint8)

    def section(tag: str, data: Mapping[str, np.ndarray] | None) -> list[str]:
        arrays = [_data_array(name, np.asarray(values, dtype=np.float64), level)
                  for name, values in (data or {}).items()]
        return [f"<{tag}>", *arrays, f"</{tag}>"]

    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
             'header_type="UInt64" compressor="vtkZLibDataCompressor">',
             "<UnstructuredGrid>",
             f'<Piece NumberOfPoints="{len(points)}" NumberOfCells="{len(cells)}">',
             "<Points>", _data_array("Points", points, level), "</Points>",
             "<Cells>", _data_array("connectivity", cells.ravel(), level),
             _data_array("offsets", offsets, level), _data_array("types", types, level),
             "</Cells>",
             *section("PointData", point_data), *section("CellData", cell_data),
             "</Piece>", "</UnstructuredGrid>", "</VTKFile>", ""]
    path = Path(path)
    path.write_text("\n".join(lines))
    return path


def _is_continuous(cf: Any) -> bool:
    """A GridFunction of a continuous (H1 or VectorH1) space: its vertex values are exact."""
    return isinstance(cf, ngs.GridFunction) and type(cf.space).__name__ in ("H1", "VectorH1")


def _vertex_values(gf: ngs.GridFunction, nv: int) -> np.ndarray | None:
    """The values of an H1 (VectorH1) GridFunction at the mesh's vertices from its vertex dofs
    (the higher-order basis functions vanish at the vertices), or None where the vertex dofs
    are not the first nv in vertex order."""
    parts = gf.components if type(gf.space).__name__ == "VectorH1" else [gf]
    columns = []
    for part in parts:
        if not vertex_dofs_first(part.space):
            return None
        columns.append(part.vec.FV().NumPy()[:nv].copy())
    return columns[0] if len(columns) == 1 else np.column_stack(columns)


def snapshot_arrays(mesh: ngs.Mesh, fields: Mapping[str, Any]
                    ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Points, cells, point data and cell data of named CoefficientFunctions on ``mesh``.

    Continuous GridFunctions (H1, VectorH1: u, z) are given at the vertices (their vertex
    dofs); every other field at each element's centroid, one evaluation of the field at all
    centroids (the element average for fields linear on each element, such as the stress of
    P2 u). Each such field is compiled first (``CoefficientFunction.Compile``), which
    evaluates a subexpression its components share once rather than once per component.
    """
    geometry = ElementGeometry.of(mesh)
    points, cells = geometry.coordinates, geometry.vertices
    point_data: dict[str, np.ndarray] = {}
    cell_data: dict[str, np.ndarray] = {}
    centroids = None
    for name, cf in fields.items():
        if _is_continuous(cf):
            values = _vertex_values(cf, len(points))
            if values is not None:
                point_data[name] = values
                continue
            at = mesh(*(points[:, k] for k in range(mesh.dim)))
            values = np.asarray(cf(at), dtype=np.float64)
            point_data[name] = values.reshape(len(points), -1) if cf.dim > 1 else values.ravel()
            continue
        if centroids is None:
            element = ngs.TET if mesh.dim == 3 else ngs.TRIG
            centre = (0.25, 0.25, 0.25) if mesh.dim == 3 else (1 / 3, 1 / 3)
            rule = ngs.IntegrationRule([centre], [1.0])
            centroids = mesh.MapToAllElements({element: rule}, ngs.VOL)
        cf = ngs.CoefficientFunction(cf).Compile()
        values = np.asarray(cf(centroids), dtype=np.float64)
        cell_data[name] = values.reshape(len(cells), -1) if cf.dim > 1 else values.ravel()
    return points, cells, point_data, cell_data
