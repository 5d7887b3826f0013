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
                     show_mesh: bool = False) -> Path:
    """The phase field z on the mesh (vertex values, linear per triangle)."""
    plt = _pyplot()
    coords = np.array(mesh.ngmesh.Coordinates())
    triangles = mesh.ngmesh.Elements2D().NumPy()["nodes"][:, :3].astype(int) - 1
    fig, ax = plt.subplots(figsize=(6, 5.2), constrained_layout=True)
    image = ax.tripcolor(coords[:, 0], coords[:, 1], triangles, z_vertex_values,
                         shading="gouraud", cmap="inferno_r", vmin=0, vmax=1)
    if show_mesh:
        ax.triplot(coords[:, 0], coords[:, 1], triangles, color="0.6", lw=0.15)
    fig.colorbar(image, ax=ax, label="z")
    ax.set_aspect("equal")
    ax.set(xlabel="x", ylabel="y", title=title)
    fig.savefig(png, dpi=130)
    plt.close(fig)
    return Path(png)
