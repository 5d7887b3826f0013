"""Figures of a run, written to files without a GUI.

Figures are ``matplotlib.figure.Figure`` objects saved through the Agg canvas; pyplot is never
imported, so matplotlib's backend and pyplot's figures in the user's session stay as they are
(and importing this module does not import matplotlib at all).
"""
from __future__ import annotations

import csv
import logging
from pathlib import Path
from typing import Any

import numpy as np

log = logging.getLogger(__name__)


def new_figure(**kwargs: Any) -> Any:
    """A matplotlib Figure that draws with Agg (PNG files), outside pyplot."""
    from matplotlib.figure import Figure

    return Figure(**kwargs)


def read_history(path: str | Path) -> dict[str, np.ndarray]:
    """history.csv as a dict of float columns."""
    with Path(path).open(newline="") as handle:
        rows = list(csv.reader(handle))
    if not rows:
        raise ValueError(f"{path} is empty")
    header, body = rows[0], rows[1:]
    data = np.array(body, dtype=float).reshape(len(body), len(header))
    return {name: data[:, i] for i, name in enumerate(header)}


def plot_history(history_csv: str | Path, png: str | Path, units: str = "scene units") -> Path:
    """Energies, crack length and tip position, and mesh size over time, in one figure.

    The crack panel shows the geometric length first (2D: ``path_length``), then the
    Gamma-functional ``crack_length`` (which also counts diffuse damage), named as such;
    axes carry the units of the scene's unit system ``units``
    (:data:`ngfrac.scene.units.UNIT_SYSTEMS`; 2D energies are per unit thickness).
    """
    history_figure(read_history(history_csv), units).savefig(png, dpi=110)
    return Path(png)


def history_figure(h: dict[str, np.ndarray], units: str = "scene units") -> Any:
    """The Figure of :func:`plot_history` for a history (:func:`read_history`)."""
    from ..scene.units import unit_system

    system, dim = unit_system(units), 3 if "tip_z" in h else 2
    fig = new_figure(figsize=(10, 7), constrained_layout=True)
    axes = fig.subplots(2, 2)
    ax = axes[0, 0]
    for key in ("E_el", "E_surf", "E_total"):
        ax.plot(h["t"], h[key], label=key)
    ax.set(xlabel="t", ylabel=system.label("energy", system.energy(dim)), title="Energies")
    ax.legend()
    ax = axes[0, 1]
    measure = "area" if dim == 3 else "length"
    if "path_length" in h and np.any(np.isfinite(h["path_length"])):
        ax.plot(h["t"], h["path_length"], lw=2, label="crack path length (geometric)")
    ax.plot(h["t"], h["crack_length"], "--",
            label=f"Γ-functional crack {measure} ½∫(ε|∇z|² + z²/ε)")
    ax.plot(h["t"], h["tip_x"], ":", label="tip x")
    ax.set(xlabel="t", ylabel=system.label(f"crack {measure}, tip x",
                                           system.crack_measure(dim) if dim == 2 else ""),
           title=f"Crack {measure} and tip")
    ax.legend(fontsize="small")
    ax = axes[1, 0]
    ax.semilogy(h["t"], h["hmin"], label="h min")
    ax.semilogy(h["t"], h["hmax"], label="h max")
    ax.set(xlabel="t", ylabel=system.label("element size", system.length), title="Mesh size")
    ax.legend()
    ax = axes[1, 1]
    ax.plot(h["t"], h["nv"])
    ax.set(xlabel="t", ylabel="vertices", title="Number of vertices")
    return fig


def plot_phase_field(mesh, z_vertex_values: np.ndarray, png: str | Path, title: str = "",
                     show_mesh: bool = False, path: np.ndarray | None = None) -> Path:
    """The phase field z on the mesh (vertex values, linear per triangle).

    ``mesh`` is an NGSolve mesh or a pair (coordinates, triangles); ``path`` an optional
    (n, 2) array of tip positions drawn on top. A 3D NGSolve mesh gives the two panels of
    :func:`ngfrac.io.plotting3d.plot_phase_field_3d` (``path`` may then have a z column).
    """
    if not isinstance(mesh, tuple) and mesh.dim == 3:
        from .plotting3d import plot_phase_field_3d

        return plot_phase_field_3d(mesh, z_vertex_values, png, title=title, path=path)
    if isinstance(mesh, tuple):
        coords, triangles = np.asarray(mesh[0]), np.asarray(mesh[1])
    else:
        coords = np.array(mesh.ngmesh.Coordinates())
        triangles = mesh.ngmesh.Elements2D().NumPy()["nodes"][:, :3].astype(int) - 1
    fig = new_figure(figsize=(6, 5.2), constrained_layout=True)
    ax = fig.subplots()
    image = ax.tripcolor(coords[:, 0], coords[:, 1], triangles, z_vertex_values,
                         shading="gouraud", cmap="inferno_r", vmin=0, vmax=1)
    if show_mesh:
        ax.triplot(coords[:, 0], coords[:, 1], triangles, color="0.6", lw=0.15)
    if path is not None and len(path):
        ax.plot(path[:, 0], path[:, 1], "c.-", lw=1, ms=3, label="tip path")
        ax.legend(loc="upper left")
    fig.colorbar(image, ax=ax, label="z")
    ax.set_aspect("equal")
    ax.set(xlabel="x", ylabel="y", title=title)
    fig.savefig(png, dpi=130)
    return Path(png)


def force_displacement_curves(history: dict[str, np.ndarray]) -> list[tuple[str, str]]:
    """The (x, force) column pairs of force_displacement.png.

    Each force column ``F<c>_<boundary>`` that is not zero throughout, against the mean
    displacement ``u<c>_<boundary>`` of a boundary that moves; when no loaded boundary
    moves (a held boundary's reaction, loads by tractions), against ``t``. A held boundary's
    displacement is 0 at every row: its reaction is drawn against t, or, when another
    boundary moves, not at all (its force is the moving one's, opposite).
    """
    forces = [name for name in history
              if name.startswith("F") and "_" in name and "u" + name[1:] in history
              and np.any(history[name] != 0)]
    moving = [(f"u{name[1:]}", name) for name in forces if np.any(history["u" + name[1:]] != 0)]
    return moving or [("t", name) for name in forces]


def plot_force_displacement(history: dict[str, np.ndarray], png: str | Path,
                            units: str = "scene units") -> Path | None:
    """Reaction force against the mean displacement of each loaded boundary that moves
    (:func:`force_displacement_curves`; against t when none moves), with the units of the
    scene's unit system (2D forces per unit thickness).

    Returns None when the history has no nonzero force column.
    """
    fig = force_displacement_figure(history, units)
    if fig is None:
        return None
    fig.savefig(png, dpi=110)
    return Path(png)


def force_displacement_figure(history: dict[str, np.ndarray],
                              units: str = "scene units") -> Any | None:
    """The Figure of :func:`plot_force_displacement` (None without a nonzero force)."""
    from ..scene.units import unit_system

    curves = force_displacement_curves(history)
    if not curves:
        return None
    system, dim = unit_system(units), 3 if "tip_z" in history else 2
    fig = new_figure(figsize=(6, 4.5), constrained_layout=True)
    ax = fig.subplots()
    for x, force in curves:
        ax.plot(history[x], history[force], label=f"{force} against {x}")
    xlabel = ("t (load parameter)" if curves[0][0] == "t"
              else system.label("mean displacement of the boundary", system.length))
    ax.set(xlabel=xlabel, ylabel=system.label("reaction force", system.force(dim)),
           title="Force-displacement")
    ax.legend()
    return fig


def plot_mesh(coordinates: np.ndarray, cells: np.ndarray, png: str | Path, title: str = "",
              facets: np.ndarray | None = None) -> Path:
    """The elements of a mesh: triangles drawn in 2D; in 3D the boundary and crack faces
    (``facets``, triangles) seen from above the front face.

    Parameters
    ----------
    coordinates : (nv, 2 or 3) vertex coordinates
    cells : (ne, 3) triangles (2D; vertex numbers from 0), or the tetrahedra in 3D (counted only)
    facets : (nf, 3) boundary triangles, needed in 3D
    """
    coordinates, cells = np.asarray(coordinates), np.asarray(cells)
    fig = new_figure(figsize=(6, 5.2), constrained_layout=True)
    label = f"{len(coordinates)} vertices, {len(cells)} elements"
    if coordinates.shape[1] == 2:
        ax = fig.subplots()
        ax.triplot(coordinates[:, 0], coordinates[:, 1], cells, color="0.2", lw=0.2)
        ax.set_aspect("equal")
        ax.set(xlabel="x", ylabel="y")
    else:
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        ax = fig.add_subplot(projection="3d")
        faces = coordinates[np.asarray(facets)]
        ax.add_collection3d(Poly3DCollection(faces, facecolor="0.85", edgecolor="0.2",
                                             linewidth=0.15))
        lo, hi = coordinates.min(axis=0), coordinates.max(axis=0)
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]),
               xlabel="x", ylabel="y", zlabel="z")
        ax.set_box_aspect(hi - lo)
    ax.set_title(f"{title}\n{label}" if title else label)
    fig.savefig(png, dpi=150)
    return Path(png)


def plot_tip_path(history: dict[str, np.ndarray], png: str | Path,
                  outline: np.ndarray | None = None, title: str = "") -> Path | None:
    """The tip positions of a history (tip_x, tip_y) over the domain, colored by t.

    ``outline`` holds segments (k, 2, 2) of the domain's boundary in the x-y plane
    (:func:`boundary_outline`), drawn in grey. Returns None when no row has a tip.
    """
    points = np.column_stack([history["tip_x"], history["tip_y"], history["t"]])
    points = points[np.all(np.isfinite(points), axis=1)]
    if not len(points):
        return None
    fig = new_figure(figsize=(6, 5.2), constrained_layout=True)
    ax = fig.subplots()
    if outline is not None and len(outline):
        from matplotlib.collections import LineCollection

        ax.add_collection(LineCollection(outline, colors="0.3", linewidths=1))
    ax.plot(points[:, 0], points[:, 1], color="0.7", lw=0.6, zorder=1)
    dots = ax.scatter(points[:, 0], points[:, 1], c=points[:, 2], s=8, cmap="viridis", zorder=2)
    fig.colorbar(dots, ax=ax, label="t")
    ax.set_aspect("equal")
    ax.set(xlabel="x", ylabel="y", title=title or "tip path")
    fig.savefig(png, dpi=130)
    return Path(png)


def boundary_outline(coordinates: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """The boundary of a mesh as x-y segments (k, 2, 2): its boundary edges in 2D (any domain
    shape, the crack edges included), the edges of its boundary triangles seen from above in
    3D."""
    facets = np.asarray(facets)
    if facets.shape[1] == 3:  # 3D: the triangles' edges
        facets = np.unique(np.sort(np.concatenate([facets[:, [0, 1]], facets[:, [1, 2]],
                                                   facets[:, [0, 2]]]), axis=1), axis=0)
    return np.asarray(coordinates)[facets][:, :, :2]


def _scene_units(folder: Path) -> str:
    """The ``units`` of the run folder's scene.toml ("scene units" without one)."""
    import tomllib

    from ..scene.units import SCENE_UNITS, UNIT_SYSTEMS

    try:
        units = tomllib.loads((folder / "scene.toml").read_text()).get("units", SCENE_UNITS)
    except (OSError, ValueError):
        return SCENE_UNITS
    return units if units in UNIT_SYSTEMS else SCENE_UNITS


def plot_run(folder: str | Path, times: list[float] | None = None) -> list[Path]:
    """All figures of a run folder, into ``folder/plots``: history (energies, crack length and
    tip, mesh size and vertex count: the paper's Fig. 3), force-displacement where the scene
    has loads with reactions, and z with the tip path at chosen times (from results.h5)."""
    from .results import open_results

    folder = Path(folder)
    if not (folder / "history.csv").exists():
        raise ValueError(f"{str(folder)!r} is not a run folder (no history.csv)")
    out = folder / "plots"
    out.mkdir(exist_ok=True)
    units = _scene_units(folder)
    written = [plot_history(folder / "history.csv", out / "history.png", units)]
    history = read_history(folder / "history.csv")
    fd = plot_force_displacement(history, out / "force_displacement.png", units)
    if fd is not None:
        written.append(fd)
    results_file = folder / "results.h5"
    results = open_results(results_file) if results_file.exists() else None
    outline = None
    if results is not None and len(results.snapshot_times()):
        arrays = results.snapshot(-1).mesh_arrays
        outline = boundary_outline(arrays.coordinates, arrays.facets)
    tips = plot_tip_path(history, out / "tip_path.png", outline)
    if tips is not None:
        written.append(tips)
    if results is None:
        log.info("%s has no results.h5: no mesh or phase-field pictures", folder)
    else:
        available = results.snapshot_times()
        if len(available):
            last = results.snapshot(-1)
            written.append(plot_mesh(last.mesh_arrays.coordinates, last.mesh_arrays.cells,
                                     out / "mesh.png", f"mesh at t = {last.t:.4g}",
                                     facets=last.mesh_arrays.facets))
            chosen = times if times else sorted({available[0], available[len(available) // 2], available[-1]})
            tips = np.c_[history["tip_x"], history["tip_y"]]
            for t in chosen:
                snap = results.snapshot_at(t)
                arrays = snap.arrays()
                if arrays.coordinates.shape[1] != 2:
                    continue  # 3D: use the VTK files
                path = tips[(history["t"] <= snap.t) & np.all(np.isfinite(tips), axis=1)]
                png = out / f"z_t{snap.t:.5g}.png"
                plot_phase_field((arrays.coordinates, arrays.cells), arrays.values["z"], png,
                                 title=f"z at t = {snap.t:.4g}", path=path)
                written.append(png)
    return written
