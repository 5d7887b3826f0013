"""A picture of a 3D phase field: a slice at mid-depth and the crack seen through the block.

ParaView (the VTK series) is the tool for 3D fields; this PNG is a quick look that the run
folder always has. Left: z on the plane at mid-depth (an x-y slice). Right: the largest z
along each line parallel to y, as a map over (x, z), which shows the cracked area of a crack
that runs in a plane y = const, and its front.
"""
from __future__ import annotations

import warnings
from pathlib import Path
from typing import Sequence

import numpy as np
import ngsolve as ngs

from ..fem.elements import ElementGeometry


GRID_CHUNK = 4_000_000
"""Candidate grid points per chunk of :func:`sample_on_grid` (bounds its memory, ~0.5 GB)."""
BARYCENTRIC_SLACK = 1e-10
"""A grid point belongs to an element when no barycentric coordinate is below -this (a point
on a face belongs to both elements, which give it the same value)."""


def sample_on_grid(mesh: ngs.Mesh, vertex_values: np.ndarray,
                   axes: Sequence[np.ndarray]) -> np.ndarray:
    """The P1 interpolant of vertex values at the nodes of a tensor grid (NaN outside).

    The values at ``np.meshgrid(*axes, indexing="ij")``, found element by element instead of
    locating each point in the mesh (NGSolve's ``mesh(xs, ys, zs)``, one search per point,
    which made most of a 3D run's plotting time: docs/benchmarks.md, section 16): the grid
    points in each tetrahedron's bounding box are tested with its barycentric coordinates.

    Parameters
    ----------
    mesh : ngsolve.Mesh
        A 3D mesh of tetrahedra.
    vertex_values : (nv,) array
    axes : three increasing, evenly spaced 1D arrays (the ends may be moved inwards by
        round-off; an axis may have one value)

    Returns
    -------
    (len(axes[0]), len(axes[1]), len(axes[2])) array
    """
    geometry = ElementGeometry.of(mesh)
    tets, coords = geometry.vertices, geometry.coordinates
    values = np.asarray(vertex_values, dtype=float)
    axes = [np.asarray(a, dtype=float) for a in axes]
    shape = np.array([len(a) for a in axes])
    start = np.array([a[0] for a in axes])
    spacing = np.array([(a[-1] - a[0]) / (len(a) - 1) if len(a) > 1 else 1.0 for a in axes])
    corners = coords[tets]  # (ne, 4, 3)
    slack = 1e-6  # of a grid spacing: the moved ends, and points on a face
    first = np.ceil((corners.min(axis=1) - start) / spacing - slack).astype(np.int64)
    last = np.floor((corners.max(axis=1) - start) / spacing + slack).astype(np.int64)
    first, last = np.maximum(first, 0), np.minimum(last, shape - 1)
    extent = np.maximum(last - first + 1, 0)  # (ne, 3)
    counts = extent.prod(axis=1)
    edges = corners[:, 1:, :] - corners[:, :1, :]  # (ne, 3, 3): rows e1, e2, e3
    to_barycentric = np.linalg.inv(np.transpose(edges, (0, 2, 1)))
    out = np.full(tuple(shape), np.nan)
    ends = np.cumsum(counts)
    starts = ends - counts
    begin = 0
    while begin < len(tets):  # chunks of whole elements, about GRID_CHUNK candidates each
        stop = max(int(np.searchsorted(ends, starts[begin] + GRID_CHUNK, side="right")), begin + 1)
        ids = np.repeat(np.arange(begin, stop), counts[begin:stop])
        local = np.arange(len(ids)) - np.repeat(starts[begin:stop] - starts[begin], counts[begin:stop])
        ext = extent[ids]
        i = first[ids, 0] + local // (ext[:, 1] * ext[:, 2])
        j = first[ids, 1] + (local // ext[:, 2]) % ext[:, 1]
        k = first[ids, 2] + local % ext[:, 2]
        x = np.column_stack([axes[0][i], axes[1][j], axes[2][k]])
        lam = np.einsum("nij,nj->ni", to_barycentric[ids], x - corners[ids, 0])
        lam = np.column_stack([1.0 - lam.sum(axis=1), lam])
        inside = np.all(lam >= -BARYCENTRIC_SLACK, axis=1)
        value = np.einsum("ni,ni->n", lam[inside], values[tets[ids[inside]]])
        out[i[inside], j[inside], k[inside]] = value
        begin = stop
    return out


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
    middle = 0.5 * (lo[2] + hi[2])
    slice_values = sample_on_grid(mesh, z_vertex_values, [inset[0], inset[1], np.array([middle])])
    cube = sample_on_grid(mesh, z_vertex_values, inset)
    with warnings.catch_warnings():  # lines along y that miss a domain which is no box
        warnings.simplefilter("ignore", RuntimeWarning)
        through = np.nanmax(cube, axis=1)  # (x, z)

    fig = new_figure(figsize=(11, 4.8), constrained_layout=True)
    left, right = fig.subplots(1, 2)
    image = left.pcolormesh(axes[0], axes[1], slice_values[:, :, 0].T, shading="gouraud",
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
