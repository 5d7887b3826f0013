"""Run folders: history.csv, VTK snapshots with a .pvd series, the resolved scene.

VTK files are written with NGSolve's ``VTKOutput`` (no GUI), one ``.vtu`` per snapshot, so
the series stays valid when the mesh changes between snapshots; ``fields.pvd`` is rewritten
atomically after each snapshot and opens in ParaView as a time series.
"""
from __future__ import annotations

import csv
import math
import os
import shutil
import warnings
from pathlib import Path
from typing import Any, Iterable, TextIO
from xml.sax.saxutils import quoteattr

import ngsolve as ngs

OWNED = ("history.csv", "scene.toml", "vtk", "history.png", "crack.png", "results.h5",
         "checkpoint.h5", "checkpoint.tmp", "force_displacement.png", "plots",
         "crack_path.csv", "results.xdmf")
"""What ngfrac writes into a run folder (and may remove with ``overwrite``)."""

LARGE_SNAPSHOT = 50_000_000
"""Bytes of one VTK file above which :meth:`VTKSeries.write` warns."""


class OutputError(RuntimeError):
    """The output folder cannot be used as asked."""


def prepare_output_dir(path: str | Path, overwrite: bool = False) -> Path:
    """Create the run folder, refusing to mix with an earlier run unless ``overwrite``.

    With ``overwrite`` only the files ngfrac writes are removed; anything else stays.
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputError(f"output path {str(path)!r} exists and is not a folder")
    previous = [name for name in OWNED if (path / name).exists()]
    if previous and not overwrite:
        raise OutputError(f"output folder {str(path)!r} already holds a run ({previous[0]}); "
                          "choose another --out or pass --overwrite")
    for name in previous:
        target = path / name
        shutil.rmtree(target) if target.is_dir() else target.unlink()
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise OutputError(f"cannot create output folder {str(path)!r}: {err.strerror}") from None
    return path


def atomic_write_text(path: Path, text: str) -> None:
    """Write a text file via a temporary name and a rename, so readers never see half a file."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


class HistoryWriter:
    """Appends one CSV row per diagnosed step; flushed each row so a killed run keeps its rows.

    With ``resume_after=k`` an existing file is kept up to step k (rows written after the
    checkpoint a restart continues from are dropped) and new rows are appended.
    """

    def __init__(self, path: Path, columns: list[str], resume_after: int | None = None) -> None:
        self.path = path
        self.columns = columns
        if resume_after is not None and path.exists():
            with path.open(newline="") as handle:
                rows = list(csv.reader(handle))
            if not rows or rows[0] != columns:
                raise OutputError(f"{str(path)!r} does not have the columns of this run; "
                                  "restart into the folder the run wrote")
            kept = [rows[0]] + [row for row in rows[1:] if row and int(row[0]) <= resume_after]
            atomic_write_text(path, "".join(",".join(row) + "\n" for row in kept))
            self._handle: TextIO = path.open("a", newline="")
            self._writer = csv.writer(self._handle)
            return
        self._handle = path.open("w", newline="")
        self._writer = csv.writer(self._handle)
        self._writer.writerow(columns)

    def write(self, row: Iterable[Any]) -> None:
        self._writer.writerow([_format(v) for v in row])
        self._handle.flush()

    def close(self) -> None:
        self._handle.close()

    def __enter__(self) -> "HistoryWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _format(value: Any) -> str:
    if isinstance(value, float):
        return "nan" if math.isnan(value) else repr(value)
    return str(value)


class VTKSeries:
    """Numbered VTK snapshots in ``folder`` and a ``.pvd`` collection listing them.

    Parameters
    ----------
    folder : Path
        Where ``fields_00000.vtu``, ... and ``fields.pvd`` go.
    subdivision : int
        Subdivisions per element (order - 1 shows P2 fields faithfully).
    """

    def __init__(self, folder: Path, subdivision: int, stem: str = "fields") -> None:
        self.folder = folder
        self.subdivision = subdivision
        self.stem = stem
        self.entries: list[tuple[float, str]] = []
        self._warned = False
        folder.mkdir(parents=True, exist_ok=True)

    def resume(self, t: float) -> None:
        """Keep the snapshots of an earlier run up to time ``t`` (for a restart)."""
        import re

        collection = self.folder / f"{self.stem}.pvd"
        if not collection.exists():
            return
        pattern = re.compile(r'timestep="([^"]+)"[^>]*file="([^"]+)"')
        entries = [(float(m.group(1)), m.group(2)) for m in pattern.finditer(collection.read_text())]
        self.entries = [(time_, file) for time_, file in entries if time_ <= t * (1 + 1e-12) + 1e-300]
        self._write_collection()

    def estimate_bytes(self, mesh: ngs.Mesh, n_components: int) -> int:
        """The size of one ``.vtu`` of ``mesh`` with fields of ``n_components`` values in all.

        NGSolve writes every element on its own, refined ``subdivision`` times (2^s
        intervals per edge): (n+1)(n+2)/2 points per triangle, (n+1)(n+2)(n+3)/6 per
        tetrahedron, each with 3 coordinates and the field values as float64, plus about
        8 dim bytes of cell connectivity per point (measured against NGSolve 6.2 files:
        within 10 % for subdivision 0 to 3).
        """
        n = 2 ** self.subdivision
        points = ((n + 1) * (n + 2) // 2 if mesh.dim == 2
                  else (n + 1) * (n + 2) * (n + 3) // 6) * mesh.ne
        return points * (8 * (3 + n_components) + 8 * mesh.dim)

    def write(self, mesh: ngs.Mesh, fields: dict[str, Any], t: float) -> Path:
        """Write one snapshot of the named CoefficientFunctions on ``mesh`` at time ``t``.

        Warns (a UserWarning naming ``output.vtk_subdivision``, once per series) before
        writing a file that :meth:`estimate_bytes` puts above :data:`LARGE_SNAPSHOT` bytes.
        """
        size = self.estimate_bytes(mesh, sum(cf.dim for cf in fields.values()))
        if size > LARGE_SNAPSHOT and not self._warned:
            self._warned = True  # once per series: adaptive meshes change the size every time
            warnings.warn(f"a VTK snapshot of {mesh.ne} elements at subdivision "
                          f"{self.subdivision} will take about {size / 1e6:.0f} MB per file; "
                          "lower output.vtk_subdivision (each step down divides it by ~4 in 2D, "
                          "~8 in 3D) or raise output.vtk_every", stacklevel=2)
        name = f"{self.stem}_{len(self.entries):05d}"
        output = ngs.VTKOutput(ma=mesh, coefs=list(fields.values()), names=list(fields),
                               filename=str(self.folder / name), subdivision=self.subdivision)
        output.Do()
        self.entries.append((t, name + ".vtu"))
        self._write_collection()
        return self.folder / (name + ".vtu")

    def _write_collection(self) -> None:
        lines = ['<?xml version="1.0"?>',
                 '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
                 "  <Collection>"]
        for t, file in self.entries:
            lines.append(f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(file)}/>')
        lines += ["  </Collection>", "</VTKFile>", ""]
        atomic_write_text(self.folder / f"{self.stem}.pvd", "\n".join(lines))


def to_toml(data: dict[str, Any]) -> str:
    """Serialise a scene dictionary (tables, arrays of tables, scalars, lists) as TOML."""
    scalars = {k: v for k, v in data.items() if not isinstance(v, (dict, list)) or _is_value_list(v)}
    lines = [f"{k} = {_toml_value(v)}" for k, v in scalars.items()]
    for key, value in data.items():
        if isinstance(value, dict):
            lines += ["", f"[{key}]"] + [f"{k} = {_toml_value(v)}" for k, v in value.items()]
        elif isinstance(value, list) and not _is_value_list(value):
            for item in value:
                lines += ["", f"[[{key}]]"] + [f"{k} = {_toml_value(v)}" for k, v in item.items()]
    return "\n".join(lines) + "\n"


def _is_value_list(value: Any) -> bool:
    return isinstance(value, list) and not any(isinstance(v, dict) for v in value)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} as TOML")
