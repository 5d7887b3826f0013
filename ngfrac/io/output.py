"""Run folders: history.csv, VTK snapshots with a .pvd series, the resolved scene, the
manifest of what ngfrac wrote, and the run's metadata (``run.json``).

VTK files are written with NGSolve's ``VTKOutput`` (no GUI), one ``.vtu`` per snapshot, so
the series stays valid when the mesh changes between snapshots; ``fields.pvd`` is rewritten
atomically after each snapshot and opens in ParaView as a time series.

Every file and folder ngfrac creates in a run folder is listed in ``manifest.json`` before it
is written (:class:`Manifest`); ``overwrite`` removes exactly those and never anything else.
"""
from __future__ import annotations

import contextlib
import csv
import datetime
import hashlib
import json
import logging
import math
import os
import platform
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any, Iterable, Iterator, TextIO
from xml.sax.saxutils import quoteattr

import ngsolve as ngs

log = logging.getLogger(__name__)

MANIFEST = "manifest.json"
"""The manifest's file name in a run folder."""
MANIFEST_FORMAT = "ngfrac-manifest"
RUN_JSON = "run.json"
RUN_FORMAT = "ngfrac-run"

LEGACY = ("history.csv", "scene.toml", "history.png", "crack.png", "results.h5",
          "checkpoint.h5", "checkpoint.tmp", "force_displacement.png", "vtk/fields.pvd",
          "vtk/fields_[0-9][0-9][0-9][0-9][0-9].vtu", "plots/history.png",
          "plots/force_displacement.png", "plots/z_t*.png")
"""The files (glob patterns) an ngfrac before manifests wrote. A folder without a manifest
counts as a run when it holds one of them; ``overwrite`` then removes those files (and
``vtk/``, ``plots/`` when they are left empty) and nothing else."""
OWNED = LEGACY + (RUN_JSON, "crack_path.csv", "results.xdmf", "results_mesh_[0-9][0-9][0-9].xdmf")
"""The names ngfrac writes: a user's file at one of them is never replaced."""
LEGACY_FOLDERS = ("plots/", "vtk/")

LARGE_SNAPSHOT = 50_000_000
"""Bytes of one VTK file above which :meth:`VTKSeries.write` warns."""


class OutputError(RuntimeError):
    """The output folder cannot be used as asked."""


def _reason(err: OSError) -> str:
    return err.strerror or str(err).splitlines()[0]


# -- the manifest -----------------------------------------------------------------------------
class Manifest:
    """The files and folders ngfrac created in a run folder, kept in ``manifest.json``.

    Names are relative to the folder, folders end with ``/``. A name is added (and the
    manifest saved, atomically) *before* its file is written, so a run killed at any moment
    leaves no file of its own unlisted; :meth:`writing` drops names whose file was not made.

    Parameters
    ----------
    folder : Path
        The run folder.
    entries : iterable of str, optional
        Names already listed.
    """

    def __init__(self, folder: str | Path, entries: Iterable[str] = ()) -> None:
        self.folder = Path(folder)
        self.entries: list[str] = list(dict.fromkeys(entries))

    @property
    def path(self) -> Path:
        return self.folder / MANIFEST

    @classmethod
    def load(cls, folder: str | Path) -> "Manifest | None":
        """The manifest of ``folder``, or None when it has none."""
        data = _read_own_json(Path(folder) / MANIFEST, MANIFEST_FORMAT,
                              "; remove it by hand if the folder's files are yours",
                              "; rename it or choose another --out")
        return None if data is None else cls(folder, [str(name) for name in data.get("files", [])])

    @classmethod
    def adopt(cls, folder: str | Path) -> "Manifest":
        """A manifest listing the ngfrac files present in a folder that has none (older runs)."""
        folder = Path(folder)
        found = _legacy_files(folder)
        found += [name for name in LEGACY_FOLDERS if any(f.startswith(name) for f in found)]
        return cls(folder, found)

    def owns(self, name: str) -> bool:
        """Whether ``name`` (relative to the folder) is listed."""
        return name in self.entries or name.rstrip("/") + "/" in self.entries

    def foreign(self, under: str = "") -> list[str]:
        """Files at names ngfrac writes (:data:`OWNED`) under ``under`` that are not listed."""
        return [name for name in _legacy_files(self.folder, OWNED)
                if name.startswith(under) and not self.owns(name)]

    def save(self) -> None:
        """Write the manifest atomically."""
        text = json.dumps({"format": MANIFEST_FORMAT, "format_version": 1,
                           "files": self.entries}, indent=1) + "\n"
        atomic_write_text(self.path, text)

    def add(self, *names: str) -> None:
        """List ``names`` (saved at once when one is new)."""
        new = [name for name in names if name not in self.entries]
        if new:
            self.entries += new
            self.save()

    @contextlib.contextmanager
    def writing(self, *names: str) -> Iterator[None]:
        """List ``names`` while they are written; afterwards keep only those that exist.

        A folder (``"vtk/"``) is listed only when ngfrac creates it. A file that exists and
        is not listed is a user's: :class:`OutputError`, and nothing is written.
        """
        new = []
        for name in names:
            target = self.folder / name
            if self.owns(name):
                continue
            if name.endswith("/"):
                if not target.exists():
                    new.append(name)
            elif target.exists():
                raise OutputError(f"{str(target)!r} exists and was not written by ngfrac; "
                                  "move it or choose another --out")
            else:
                new.append(name)
        self.add(*new)
        try:
            yield
        finally:
            made = [name for name in new if (self.folder / name).exists()]
            if len(made) < len(new):
                self.entries = [e for e in self.entries if e not in new or e in made]
                self.save()

    def remove_listed(self) -> list[str]:
        """Remove the listed files, then the listed folders left empty; returns folders kept."""
        files = [name for name in self.entries if not name.endswith("/")]
        folders = sorted((name for name in self.entries if name.endswith("/")),
                         key=lambda name: -name.count("/"))
        for name in files:
            target = self.folder / name
            if target.is_file() or target.is_symlink():
                target.unlink()
        kept = []
        for name in folders:
            target = self.folder / name
            if target.is_dir():
                if any(target.iterdir()):
                    kept.append(name)
                else:
                    target.rmdir()
        self.entries = kept
        self.save()
        return kept


def _legacy_files(folder: Path, patterns: tuple[str, ...] = LEGACY) -> list[str]:
    found: list[str] = []
    for pattern in patterns:
        found += sorted(str(p.relative_to(folder)) for p in folder.glob(pattern) if p.is_file())
    return list(dict.fromkeys(found))


def prepare_output_dir(path: str | Path, overwrite: bool = False) -> Manifest:
    """Create or reuse a run folder; returns its (new) manifest.

    A folder that holds an earlier run (its manifest lists files, or, without a manifest,
    it holds files of :data:`LEGACY`) is refused unless ``overwrite``; with it, only the files
    ngfrac wrote are removed: those its manifest lists, or without one the :data:`LEGACY`
    files. A user's file is never removed, and a user's file at a name the run writes is
    refused before anything is removed. Raises :class:`OutputError` with one line.
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputError(f"output path {str(path)!r} exists and is not a folder")
    manifest = Manifest.load(path) if path.is_dir() else None
    if manifest is None:
        manifest = Manifest.adopt(path) if path.is_dir() else Manifest(path)
    previous = [name for name in manifest.entries if (path / name).exists()
                and not name.endswith("/")]
    if previous and not overwrite:
        raise OutputError(f"output folder {str(path)!r} already holds a run ({previous[0]}); "
                          "choose another --out or pass --overwrite")
    foreign = [name for name in manifest.foreign() if not name.startswith("plots/")]
    if foreign:
        raise OutputError(f"output folder {str(path)!r} holds {foreign[0]}, which ngfrac did not "
                          "write (it is not in manifest.json); move it or choose another --out")
    try:
        path.mkdir(parents=True, exist_ok=True)
        manifest.save()  # also the check that the folder is writable, before anything goes
        if previous:
            log.info("removing the earlier run's files in %s: %s", path, ", ".join(previous))
        manifest.remove_listed()
    except OSError as err:
        raise OutputError(f"cannot write into output folder {str(path)!r} ({_reason(err)}); "
                          "choose another --out or make it writable") from None
    return manifest


def atomic_write_text(path: Path, text: str) -> None:
    """Write a text file via a temporary name and a rename, so readers never see half a file."""
    tmp = path.with_name(path.name + ".tmp")
    try:
        tmp.write_text(text)
        os.replace(tmp, path)
    except OSError as err:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write {str(path)!r} ({_reason(err)}); choose another --out "
                          "or make the folder writable") from None


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
    folder : str or Path
        Where ``fields_00000.vtu``, ... and ``fields.pvd`` go.
    subdivision : int
        Subdivisions per element (order - 1 shows P2 fields faithfully); ``layout =
        "subdivided"`` only.

    manifest : Manifest, optional
        Where each file is listed before it is written (``folder`` must be inside its folder).
    large : int
        Warn once when a snapshot's estimated size exceeds this many bytes.
    layout : {"subdivided", "vertices"}
        ``"subdivided"``: NGSolve's ``VTKOutput`` (ASCII, every element on its own, refined
        ``subdivision`` times). ``"vertices"``: compressed binary, one point per vertex,
        continuous fields at the vertices and the others at the element centroids
        (:mod:`ngfrac.io.vtu`); a distributed mesh is written subdivided.
    """

    LAYOUTS = ("subdivided", "vertices")

    def __init__(self, folder: str | Path, subdivision: int, stem: str = "fields",
                 manifest: Manifest | None = None, large: int = LARGE_SNAPSHOT,
                 layout: str = "subdivided") -> None:
        if layout not in self.LAYOUTS:
            raise ValueError(f"layout = {layout!r}: choose one of {', '.join(self.LAYOUTS)}")
        self.layout = layout
        folder = Path(folder)
        self.folder = folder
        self.large = large
        self.subdivision = subdivision
        self.stem = stem
        self.manifest = manifest
        self.entries: list[tuple[float, str]] = []
        self._count = 0
        """Snapshots written (entries has one per part of a distributed mesh)."""
        self._warned = False
        with self._writing(""):
            folder.mkdir(parents=True, exist_ok=True)

    def _writing(self, *names: str) -> contextlib.AbstractContextManager[None]:
        """The manifest's :meth:`Manifest.writing` for files of the series ("": the folder)."""
        if self.manifest is None:
            return contextlib.nullcontext()
        relative = [(self.folder / name).relative_to(self.manifest.folder).as_posix()
                    for name in names]
        return self.manifest.writing(*(path + "/" if not name else path
                                       for name, path in zip(names, relative)))

    def resume(self, t: float, write: bool = True) -> None:
        """Keep the snapshots of an earlier run up to time ``t`` (for a restart); ``write``:
        rewrite the collection (False: only read it, for the count that names the next files,
        as every rank of an MPI job does after rank 0 rewrote it)."""
        import re

        collection = self.folder / f"{self.stem}.pvd"
        if not collection.exists():
            return
        pattern = re.compile(r'timestep="([^"]+)"[^>]*file="([^"]+)"')
        entries = [(float(m.group(1)), m.group(2)) for m in pattern.finditer(collection.read_text())]
        self.entries = [(time_, file) for time_, file in entries if time_ <= t * (1 + 1e-12) + 1e-300]
        # a snapshot of a distributed run has one entry per part (NAME_procR.vtu)
        self._count = len({file.rsplit("_proc", 1)[0] for _, file in self.entries})
        if write:
            self._write_collection()

    def estimate_bytes(self, mesh: ngs.Mesh, n_components: int) -> int:
        """The size of one ``.vtu`` of ``mesh`` with fields of ``n_components`` values in all.

        NGSolve writes every element on its own, refined ``subdivision`` times (2^s
        intervals per edge): (n+1)(n+2)/2 points per triangle, (n+1)(n+2)(n+3)/6 per
        tetrahedron, each with 3 coordinates and the field values as float64, plus about
        8 dim bytes of cell connectivity per point (its accuracy: docs/user-guide.md, "VTK
        snapshots").
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
        if self.layout == "vertices" and mesh.comm.size == 1:
            return self._write_vertices(mesh, fields, t)
        size = self.estimate_bytes(mesh, sum(cf.dim for cf in fields.values()))
        if size > self.large and not self._warned:
            self._warned = True  # once per series: adaptive meshes change the size every time
            warnings.warn(f"a VTK snapshot of {mesh.ne} elements at subdivision "
                          f"{self.subdivision} will take about {size / 1e6:.0f} MB per file; "
                          "lower output.vtk_subdivision (each step down divides it by ~4 in 2D, "
                          "~8 in 3D) or raise output.vtk_every", stacklevel=2)
        name = self._next_name()
        output = ngs.VTKOutput(ma=mesh, coefs=list(fields.values()), names=list(fields),
                               filename=str(self.folder / name), subdivision=self.subdivision)
        if mesh.comm.size > 1:
            return self._write_parts(mesh.comm, output, name, t)
        with self._writing(name + ".vtu"):
            output.Do()
        return self._listed(name + ".vtu", t)

    def _write_vertices(self, mesh: ngs.Mesh, fields: dict[str, Any], t: float) -> Path:
        """One snapshot as a compressed binary ``.vtu`` of the mesh's vertices
        (:func:`ngfrac.io.vtu.write_vtu`)."""
        from .vtu import snapshot_arrays, write_vtu

        name = self._next_name() + ".vtu"
        points, cells, point_data, cell_data = snapshot_arrays(mesh, fields)
        with self._writing(name):
            write_vtu(self.folder / name, points, cells, point_data, cell_data)
        return self._listed(name, t)

    def _next_name(self) -> str:
        """The stem of the next snapshot's file(s)."""
        return f"{self.stem}_{self._count:05d}"

    def _listed(self, file: str, t: float) -> Path:
        """Count a written one-file snapshot and list it in the collection."""
        self.entries.append((t, file))
        self._count += 1
        self._write_collection()
        return self.folder / file

    @property
    def n_snapshots(self) -> int:
        """Snapshots in the series (of a distributed mesh, each has one entry per part)."""
        return self._count

    def _write_parts(self, comm: Any, output: Any, name: str, t: float) -> Path:
        """A snapshot of a distributed mesh: NGSolve writes ``NAME_procR.vtu`` on each rank
        R >= 1 (rank 0 holds no elements) and ``NAME.pvd`` of them on rank 0; the series
        lists every part at time t (``part="R"``). Only rank 0 lists files and writes the
        collection (the other ranks have no manifest)."""
        parts = [f"{name}_proc{rank}.vtu" for rank in range(1, comm.size)]
        writing = self._writing(name + ".pvd", *parts) if comm.rank == 0 else contextlib.nullcontext()
        with writing:
            comm.Barrier()  # rank 0 has listed the parts (and checked that none is a user's)
            output.Do()
            comm.Barrier()  # every part on disk before the manifest checks what exists
        self.entries += [(t, part) for part in parts]
        self._count += 1
        if comm.rank == 0:
            self._write_collection()
        return self.folder / (name + ".pvd")

    def _write_collection(self) -> None:
        lines = ['<?xml version="1.0"?>',
                 '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
                 "  <Collection>"]
        for t, file in self.entries:
            part = file.rsplit("_proc", 1)[1][:-len(".vtu")] if "_proc" in file else "0"
            lines.append(f'    <DataSet timestep="{t!r}" group="" part="{part}" '
                         f'file={quoteattr(file)}/>')
        lines += ["  </Collection>", "</VTKFile>", ""]
        with self._writing(f"{self.stem}.pvd"):
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
    if isinstance(value, dict):  # an inline table: geometry.shapes, geometry.boundaries
        return "{" + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {value!r} as TOML")


# -- run metadata -----------------------------------------------------------------------------
def ngfrac_version() -> str:
    """ngfrac's version, from the installed package metadata (set in setup.cfg)."""
    from importlib import metadata

    try:
        return metadata.version("ngfrac")
    except metadata.PackageNotFoundError:
        return "0+unknown"


def git_revision() -> tuple[str | None, bool | None]:
    """The commit ngfrac's source checkout is at and whether it has uncommitted changes.

    ``(None, None)`` when ngfrac is not run from a git checkout of itself or git is missing.
    """
    root = Path(__file__).resolve().parents[2]  # ngfrac/io/output.py -> the checkout
    if not (root / "setup.cfg").exists():
        return None, None  # an installed copy, not a checkout

    def git(*args: str) -> str | None:
        try:
            done = subprocess.run(["git", "-C", str(root), *args], capture_output=True,
                                  text=True, timeout=30)
        except (OSError, subprocess.SubprocessError):
            return None
        return done.stdout if done.returncode == 0 else None

    top = git("rev-parse", "--show-toplevel", "HEAD")
    if top is None or len(top.split()) != 2 or Path(top.split()[0]).resolve() != root:
        return None, None
    status = git("status", "--porcelain", "--untracked-files=no")
    return top.split()[1], None if status is None else bool(status.strip())


def ngsolve_threads() -> int:
    """The number of threads NGSolve's ``TaskManager`` runs with (``NGFRAC_THREADS`` caps it)."""
    with ngs.TaskManager():
        return int(ngs.GetNumThreads())


def run_metadata(argv: list[str] | None = None) -> dict[str, Any]:
    """What a run folder records about the run's environment (``run.json``, results.h5).

    A flat dict of JSON values; callers may add fields before writing it.

    Parameters
    ----------
    argv : list of str, optional
        The command line; default ``sys.argv``.

    Returns
    -------
    dict
        ``ngfrac_version``, ``git_commit`` and ``git_dirty`` (None outside a git checkout),
        ``ngsolve_version``, ``netgen_version``, ``python_version``, ``threads``,
        ``command_line`` (list of str) and ``started`` (UTC, ISO 8601).
    """
    import netgen

    commit, dirty = git_revision()
    return {"ngfrac_version": ngfrac_version(), "git_commit": commit, "git_dirty": dirty,
            "ngsolve_version": str(ngs.__version__), "netgen_version": str(netgen.__version__),
            "python_version": platform.python_version(), "threads": ngsolve_threads(),
            "command_line": [str(a) for a in (sys.argv if argv is None else argv)],
            "started": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}


def read_run_json(folder: str | Path) -> dict[str, Any] | None:
    """The ``run.json`` of a run folder, or None when there is none."""
    return _read_own_json(Path(folder) / RUN_JSON, RUN_FORMAT)


def _read_own_json(path: Path, fmt: str, unreadable_hint: str = "",
                   foreign_hint: str = "") -> dict[str, Any] | None:
    """A JSON file ngfrac wrote (its ``format`` is ``fmt``), None when missing; one-line
    :class:`OutputError` when unreadable or not ngfrac's."""
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as err:
        reason = _reason(err) if isinstance(err, OSError) else "not valid JSON"
        raise OutputError(f"cannot read {str(path)!r} ({reason}){unreadable_hint}") from None
    if not isinstance(data, dict) or data.get("format") != fmt:
        raise OutputError(f"{str(path)!r} was not written by ngfrac{foreign_hint}")
    return data


def write_run_json(folder: str | Path, data: dict[str, Any],
                   manifest: Manifest | None = None) -> Path:
    """Write ``run.json`` atomically (strict JSON: a NaN raises ValueError)."""
    path = Path(folder) / RUN_JSON
    text = json.dumps({"format": RUN_FORMAT, "format_version": 1, **data}, indent=1,
                      allow_nan=False) + "\n"
    with manifest.writing(RUN_JSON) if manifest is not None else contextlib.nullcontext():
        atomic_write_text(path, text)
    return path


# -- the CAD file of a run --------------------------------------------------------------------
def file_sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes (hex)."""
    digest = hashlib.sha256()
    with Path(path).open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _cad_file(data: dict[str, Any]) -> str | None:
    """The scene dict's ``geometry.file``, None when the scene reads no CAD file."""
    geometry = data.get("geometry")
    file = geometry.get("file") if isinstance(geometry, dict) else None
    return file if isinstance(file, str) and file and not file.startswith("<") else None


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve() or (
            a.stat().st_size == b.stat().st_size and file_sha256(a) == file_sha256(b))
    except OSError:
        return False


def portable_scene_dict(data: dict[str, Any], folder: str | Path) -> dict[str, Any]:
    """A scene dict as a file in ``folder`` stores it: a ``geometry.file`` whose copy lies in
    ``folder`` (a run folder's, :func:`copy_cad_file`) is named by its bare name, relative to
    that folder, so the run folder reads back from any working directory."""
    file = _cad_file(data)
    if file is None:
        return data
    copy = Path(folder) / Path(file).name
    if Path(file) == Path(copy.name) or not copy.is_file() or not _same_file(Path(file), copy):
        return data
    return {**data, "geometry": {**data["geometry"], "file": copy.name}}


def resolve_scene_file(data: dict[str, Any], folder: str | Path) -> dict[str, Any]:
    """The inverse of :func:`portable_scene_dict` for a scene read from a file in ``folder``:
    a relative ``geometry.file`` found there is taken from there."""
    file = _cad_file(data)
    if file is None or Path(file).is_absolute() or not (Path(folder) / file).is_file():
        return data
    return {**data, "geometry": {**data["geometry"], "file": str(Path(folder) / file)}}


def copy_cad_file(data: dict[str, Any], folder: Path,
                  manifest: Manifest | None = None) -> dict[str, Any] | None:
    """Copy the scene's CAD file (``geometry.file``) into the run folder, so the folder is
    self-contained (a restart reads the copy); returns run.json's ``cad_file`` entry
    (``name`` in the folder, ``source`` as given, ``sha256``), None without a CAD file."""
    import shutil

    file = _cad_file(data)
    if file is None:
        return None
    source, copy = Path(file), folder / Path(file).name
    if not _same_file(source, copy) or not copy.exists():
        with manifest.writing(copy.name) if manifest is not None else contextlib.nullcontext():
            try:
                shutil.copyfile(source, copy)
            except OSError as err:
                raise OutputError(f"cannot copy geometry.file {file!r} into {str(folder)!r} "
                                  f"({_reason(err)}); choose another --out") from None
    return {"name": copy.name, "source": file, "sha256": file_sha256(copy)}
