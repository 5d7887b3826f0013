"""Compact VTU snapshots (ngfrac.io.vtu, ``output.vtk_format = "vertices"``): meshio reads
them back with u and z at the vertices as the stepper has them and the other fields at the
element centroids."""
from __future__ import annotations

import meshio
import numpy as np
import ngsolve as ngs
import pytest
from netgen.csg import unit_cube

from ngfrac import PhaseFieldStepper, SceneError
from ngfrac.fem.elements import ElementGeometry
from ngfrac.io.output import VTKSeries
from ngfrac.io.vtu import snapshot_arrays, write_vtu
from ngfrac.io.writers import write_snapshot
from ngfrac.post.fields import snapshot_fields
from ngfrac.testing.scenes import quick_slit

ROUND_OFF = 1e-12


@pytest.fixture(scope="module")
def stepper():
    stepper = PhaseFieldStepper(quick_slit("geometry.mesh_size=0.05", "time.t_end=0.02"))
    for _ in stepper.run():
        pass
    return stepper


def test_a_snapshot_reads_back_with_the_stepper_values(stepper, tmp_path):
    series = VTKSeries(tmp_path / "vtk", 1, layout="vertices")
    write_snapshot(series, stepper)
    grid = meshio.read(tmp_path / "vtk" / "fields_00000.vtu")
    mesh = stepper.mesh
    assert grid.points.shape == (mesh.nv, 3) and grid.cells[0].type == "triangle"
    assert len(grid.cells[0].data) == mesh.ne
    # z and u at the vertices are the GridFunctions' vertex values
    vertex_z = stepper.z_node_values()[:mesh.nv]  # vertices come first among z's nodes
    assert np.abs(grid.point_data["z"].ravel() - vertex_z).max() <= ROUND_OFF
    u = stepper.u(mesh(grid.points[:, 0], grid.points[:, 1])).ravel()
    assert np.abs(grid.point_data["u"].ravel() - u).max() <= ROUND_OFF * max(1.0, np.abs(u).max())
    # the other fields at the centroids, element by element in the mesh's order
    geometry = ElementGeometry.of(mesh)
    assert np.allclose(grid.cell_data["h"][0].ravel(), geometry.diameters)
    density = snapshot_fields(stepper)["energy_density"]
    sample = np.arange(0, mesh.ne, max(1, mesh.ne // 40))
    expected = [density(mesh(*geometry.centroids[i])) for i in sample]
    written = grid.cell_data["energy_density"][0].ravel()[sample]
    assert np.allclose(written, expected, rtol=1e-12, atol=1e-14 * max(expected))


def test_a_3d_grid_of_tetrahedra(tmp_path):
    mesh = ngs.Mesh(unit_cube.GenerateMesh(maxh=0.5))
    u = ngs.GridFunction(ngs.VectorH1(mesh, order=1))
    u.Set(ngs.CF((ngs.x, 2 * ngs.y, 3 * ngs.z)))  # linear: P1 holds it exactly
    points, cells, point_data, cell_data = snapshot_arrays(mesh, {"u": u, "strain": ngs.Sym(ngs.grad(u))})
    write_vtu(tmp_path / "box.vtu", points, cells, point_data, cell_data)
    grid = meshio.read(tmp_path / "box.vtu")
    assert grid.cells[0].type == "tetra" and len(grid.cells[0].data) == mesh.ne
    assert np.allclose(grid.point_data["u"], grid.points * [1, 2, 3], atol=1e-12)
    assert np.allclose(grid.cell_data["strain"][0], [1, 0, 0, 0, 2, 0, 0, 0, 3], atol=1e-12)
    assert grid.cell_data["strain"][0].shape == (mesh.ne, 9)


def test_compiled_3d_principal_stresses_equal_the_uncompiled_tree():
    """snapshot_arrays compiles each centroid field (the closed-form 3D eigenvalues were 92x
    slower uncompiled, docs/benchmarks.md): the values are those of the tree as given."""
    from ngfrac.post.fields import principal_stresses

    mesh = ngs.Mesh(unit_cube.GenerateMesh(maxh=0.4))
    u = ngs.GridFunction(ngs.VectorH1(mesh, order=2))
    u.Set(ngs.CF((ngs.x * ngs.y, ngs.y * ngs.z + ngs.x, ngs.z * ngs.x ** 2)))
    principal = principal_stresses(ngs.Sym(ngs.grad(u)), 3)
    cell_data = snapshot_arrays(mesh, {"principal": principal})[3]
    centroids = ElementGeometry.of(mesh).centroids
    expected = np.array([principal(mesh(*c)) for c in centroids]).reshape(mesh.ne, 3)
    assert np.abs(cell_data["principal"] - expected).max() <= ROUND_OFF * np.abs(expected).max()


def test_the_format_key_is_checked():
    with pytest.raises(SceneError, match="output.vtk_format = 'binary'.*'vertices'"):
        quick_slit("output.vtk_format=\"binary\"")
