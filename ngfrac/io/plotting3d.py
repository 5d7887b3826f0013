"""A picture of a 3D phase field: a slice at mid-depth and the crack seen through the block.

ParaView (the VTK series) is the tool for 3D fields; this PNG is a quick look that the run
folder always has. Left: z on the plane at mid-depth (an x-y slice). Right: the largest z
along each line parallel to y, as a map over (x, z), which shows the cracked area of a crack
that runs in a plane y = const, and its front.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import ngsolve as ngs


def sample_vertex_field(mesh: ngs.Mesh, vertex_values: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The P1 interpolant of vertex values at (n, 3) points of the mesh (NaN outside)."""
    gf = ngs.GridFunction(ngs.H1(mesh, order=1))
    gf.vec.FV().NumPy()[:] = np.asarray(vertex_values, dtype=float)
    located = mesh(*np.asarray(points, dtype=float).T)
    inside = located["nr"] >= 0  # NGSolve raises on a point outside (a domain that is no box)
    values = np.full(len(points), np.nan)
    if inside.any():
        values[inside] = np.asarray(gf(located[inside]), dtype=float).reshape(-1)
    return values


def plot_phase_field_3d(mesh: ngs.Mesh, z_vertex_values: np.ndarray, png: str | Path,
                        title: str = "", path: np.ndarray | None = None, n: int = 120) -> Path:
    """Two panels of z on a tetrahedral mesh (vertex values, linear per element).

    Parameters
    ----------
    mesh : ngsolve.Mesh
        A 3D mesh.
    z_vertex_values : (nv,) array
    png : str or Path
        The image file.
    title : str
    path : (m, 2 or 3) array, optional
        Tip positions, drawn on both panels.
    n : int
        Samples along the longest side.
    """
    from .plotting import new_figure

    coords = np.array(mesh.ngmesh.Coordinates())
    lo, hi = coords.min(axis=0), coords.max(axis=0)
    step = float((hi - lo).max()) / n
    axes = [np.linspace(lo[i], hi[i], max(2, int(round((hi[i] - lo[i]) / step)) + 1)) for i in range(3)]
    inset = [np.clip(a, lo[i] + 1e-9 * step, hi[i] - 1e-9 * step) for i, a in enumerate(axes)]
    xs, ys = np.meshgrid(inset[0], inset[1], indexing="ij")
    middle = 0.5 * (lo[2] + hi[2])
    slice_values = sample_vertex_field(mesh, z_vertex_values,
                                       np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, middle)]))
    X, Y, Z = np.meshgrid(*inset, indexing="ij")
    cube = sample_vertex_field(mesh, z_vertex_values, np.column_stack([X.ravel(), Y.ravel(), Z.ravel()]))
    with warnings.catch_warnings():  # lines along y that miss a domain which is no box
        warnings.simplefilter("ignore", RuntimeWarning)
        through = np.nanmax(cube.reshape(X.shape), axis=1)  # (x, z)

    fig = new_figure(figsize=(11, 4.8), constrained_layout=True)
    left, right = fig.subplots(1, 2)
    image = left.pcolormesh(axes[0], axes[1], slice_values.reshape(xs.shape).T, shading="gouraud",
                            cmap="inferno_r", vmin=0, vmax=1)
    left.set(xlabel="x", ylabel="y", title=f"z on the plane z = {middle:.3g}", aspect="equal")
    right.pcolormesh(axes[0], axes[2], through.T, shading="gouraud", cmap="inferno_r", vmin=0, vmax=1)
    right.set(xlabel="x", ylabel="z", title="largest z along y", aspect="equal")
    if path is not None and len(path):
        path = np.asarray(path)
        left.plot(path[:, 0], path[:, 1], "c.-", lw=1, ms=3, label="tip path")
        if path.shape[1] > 2:
            right.plot(path[:, 0], path[:, 2], "c.-", lw=1, ms=3)
        left.legend(loc="upper left")
    fig.colorbar(image, ax=[left, right], label="z")
    if title:
        fig.suptitle(title)
    fig.savefig(png, dpi=110)
    return Path(png)
