"""Figures of a run, drawn with matplotlib's file-only Agg backend (no GUI)."""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def read_history(path: str | Path) -> dict[str, np.ndarray]:
    """history.csv as a dict of float columns."""
    with Path(path).open(newline="") as handle:
        rows = list(csv.reader(handle))
    if not rows:
        raise ValueError(f"{path} is empty")
    header, body = rows[0], rows[1:]
    data = np.array(body, dtype=float).reshape(len(body), len(header))
    return {name: data[:, i] for i, name in enumerate(header)}


def plot_history(history_csv: str | Path, png: str | Path) -> Path:
    """Energies, crack length and tip position, and mesh size over time, in one figure."""
    h = read_history(history_csv)
    plt = _pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), constrained_layout=True)
    ax = axes[0, 0]
    for key in ("E_el", "E_surf", "E_total"):
        ax.plot(h["t"], h[key], label=key)
    ax.set(xlabel="t", ylabel="energy", title="Energies")
    ax.legend()
    ax = axes[0, 1]
    ax.plot(h["t"], h["crack_length"], label="crack length")
    ax.plot(h["t"], h["tip_x"], label="tip x")
    ax.set(xlabel="t", title="Crack length and tip")
    ax.legend()
    ax = axes[1, 0]
    ax.semilogy(h["t"], h["hmin"], label="h min")
    ax.semilogy(h["t"], h["hmax"], label="h max")
    ax.set(xlabel="t", ylabel="element size", title="Mesh size")
    ax.legend()
    ax = axes[1, 1]
    ax.plot(h["t"], h["nv"])
    ax.set(xlabel="t", ylabel="vertices", title="Number of vertices")
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return Path(png)


def plot_phase_field(mesh, z_vertex_values: np.ndarray, png: str | Path, title: str = "",
                     show_mesh: bool = False, path: np.ndarray | None = None) -> Path:
    """The phase field z on the mesh (vertex values, linear per triangle).

    ``mesh`` is an NGSolve mesh or a pair (coordinates, triangles); ``path`` an optional
    (n, 2) array of tip positions drawn on top. A 3D NGSolve mesh gives the two panels of
    :func:`ngfrac.plotting3d.plot_phase_field_3d` (``path`` may then have a z column).
    """
    if not isinstance(mesh, tuple) and mesh.dim == 3:
        from .plotting3d import plot_phase_field_3d

        return plot_phase_field_3d(mesh, z_vertex_values, png, title=title, path=path)
    plt = _pyplot()
    if isinstance(mesh, tuple):
        coords, triangles = np.asarray(mesh[0]), np.asarray(mesh[1])
    else:
        coords = np.array(mesh.ngmesh.Coordinates())
        triangles = mesh.ngmesh.Elements2D().NumPy()["nodes"][:, :3].astype(int) - 1
    fig, ax = plt.subplots(figsize=(6, 5.2), constrained_layout=True)
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
    plt.close(fig)
    return Path(png)


def plot_force_displacement(history: dict[str, np.ndarray], png: str | Path) -> Path | None:
    """Reaction force against the boundary's mean displacement, one curve per loaded component.

    Returns None when the history has no force columns.
    """
    curves = [(name, "u" + name[1:]) for name in history
              if name.startswith("F") and "_" in name and "u" + name[1:] in history]
    curves = [(f, u) for f, u in curves if np.any(history[f] != 0)]
    if not curves:
        return None
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.5), constrained_layout=True)
    for force, displacement in curves:
        ax.plot(history[displacement], history[force], label=f"{force} against {displacement}")
    ax.set(xlabel="imposed displacement", ylabel="reaction force", title="Force-displacement")
    ax.legend()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return Path(png)


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
    written = [plot_history(folder / "history.csv", out / "history.png")]
    history = read_history(folder / "history.csv")
    fd = plot_force_displacement(history, out / "force_displacement.png")
    if fd is not None:
        written.append(fd)
    results_file = folder / "results.h5"
    if results_file.exists():
        results = open_results(results_file)
        available = results.snapshot_times()
        if len(available):
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
