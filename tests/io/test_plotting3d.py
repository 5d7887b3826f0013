"""The 3D plot's grid sampler (ngfrac.io.plotting3d.sample_on_grid) gives the P1 values that
NGSolve's point location (located_values, the plot's earlier sampler) gives at every grid
point, NaN outside the domain."""
from __future__ import annotations

import numpy as np
import ngsolve as ngs
from netgen.occ import Box, OCCGeometry, Pnt

from ngfrac.io.plotting3d import sample_on_grid

ROUND_OFF = 1e-12
INSET = 1e-9
"""The plot's grid ends are moved inwards by about this (of the box's size)."""
NGSOLVE_SLACK = 1e-4
"""How far outside an element (in barycentric coordinates) NGSolve's point location may
evaluate it."""


def located_values(mesh, vertex_values, points):
    """The P1 interpolant of vertex values at (n, 3) points by NGSolve's point location (NaN
    outside)."""
    gf = ngs.GridFunction(ngs.H1(mesh, order=1))
    gf.vec.FV().NumPy()[:] = vertex_values
    located = mesh(*np.asarray(points, dtype=float).T)
    inside = located["nr"] >= 0
    values = np.full(len(points), np.nan)
    values[inside] = np.asarray(gf(located[inside]), dtype=float).reshape(-1)
    return values


def test_grid_sampler_equals_point_location_inside_and_nan_outside():
    # a block with a notch cut from a corner: grid points in the notch are outside
    shape = Box(Pnt(0, 0, 0), Pnt(1, 1, 1)) - Box(Pnt(0.5, 0.5, -1), Pnt(2, 2, 2))
    mesh = ngs.Mesh(OCCGeometry(shape).GenerateMesh(maxh=0.25))
    values = np.random.default_rng(1).random(mesh.nv)
    # grid points on inner faces, edges and vertices of the mesh, and INSET off the boundary
    axes = [np.clip(np.linspace(0.0, 1.0, n), INSET, 1 - INSET) for n in (9, 11, 5)]
    grid = sample_on_grid(mesh, values, axes)
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    located = located_values(mesh, values, np.column_stack([X.ravel(), Y.ravel(), Z.ravel()]))
    located = located.reshape(grid.shape)
    notch = (X > 0.5 + INSET) & (Y > 0.5 + INSET)
    assert np.isnan(grid[notch]).all()
    assert not np.isnan(grid[~notch]).any()
    # NGSolve's point location accepts an element in which a point's barycentric coordinates
    # are down to about -1e-4 (measured: -9.6e-5 on a 100,000-tet cube) and extrapolates
    # there; the sampler takes the element that holds the point. Values in [0, 1] differ by
    # at most 4 such coordinates' share of the largest difference, 4e-4
    np.testing.assert_allclose(grid[~notch], located[~notch], rtol=0, atol=4 * NGSOLVE_SLACK)
    # a linear field is exact at every point, on the faces, edges and vertices of the mesh too
    x, y, z = (np.array(v) for v in mesh.ngmesh.Coordinates().T)
    grid = sample_on_grid(mesh, 1 + 2 * x - y + 3 * z, axes)
    np.testing.assert_allclose(grid[~notch], (1 + 2 * X - Y + 3 * Z)[~notch], rtol=0,
                               atol=ROUND_OFF)


def test_a_slice_is_a_grid_with_one_value_on_an_axis():
    mesh = ngs.Mesh(OCCGeometry(Box(Pnt(0, 0, 0), Pnt(1, 2, 1))).GenerateMesh(maxh=0.4))
    x, y, z = (np.array(v) for v in mesh.ngmesh.Coordinates().T)
    values = 1 + 2 * x - y + 3 * z  # linear: every P1 interpolant is exact
    axes = [np.linspace(0, 1, 7), np.linspace(0, 2, 13), np.array([0.37])]
    grid = sample_on_grid(mesh, values, axes)
    X, Y = np.meshgrid(axes[0], axes[1], indexing="ij")
    np.testing.assert_allclose(grid[:, :, 0], 1 + 2 * X - Y + 3 * 0.37, rtol=0, atol=ROUND_OFF)
