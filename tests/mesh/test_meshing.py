"""Mesh change by regeneration: size fields, coarsening, the vertex cap (ngfrac.mesh.remesh)."""
from __future__ import annotations

import logging

import numpy as np
import ngsolve as ngs
import pytest

from ngfrac.mesh import remesh as meshing
from ngfrac.physics.cracks import distance_to_polylines
from ngfrac.geometry.domains import build_mesh, netgen_geometry
from ngfrac.mesh.remesh import (
    ElementGeometry,
    SizeFloor,
    VertexDensity,
    adapt_mesh,
    cap_vertices,
    grade_sizes,
    predict_vertices,
    remesh,
    sample_size_field,
    size_field_from_indicator,
)
from ngfrac.scene import Geometry

SQUARE = Geometry(width=1.0, height=1.0)
HMAX = 0.1


def disc_sizes(centroids: np.ndarray, centre: tuple[float, float], radius: float, h: float,
               hmax: float = HMAX) -> np.ndarray:
    """h inside a disc, hmax outside (a sharp feature)."""
    inside = np.linalg.norm(centroids - np.asarray(centre), axis=1) < radius
    return np.where(inside, h, hmax)


def adapt_to(mesh: ngs.Mesh, field, *, times: int = 2, max_vertices: int = 10**6,
             hmax: float = HMAX) -> ngs.Mesh:
    """Adapt ``times`` times, re-evaluating ``field(centroids)`` on each new mesh."""
    for _ in range(times):
        sizes = field(ElementGeometry.of(mesh).centroids)
        mesh = adapt_mesh(mesh, SQUARE, sizes, hmax=hmax, max_vertices=max_vertices)
    return mesh


def test_element_geometry_follows_ngsolve_element_order():
    mesh = build_mesh(SQUARE, 0.2)
    geom = ElementGeometry.of(mesh)
    for el in mesh.Elements(ngs.VOL):
        assert sorted(v.nr for v in el.vertices) == sorted(geom.vertices[el.nr])
    assert geom.measures.sum() == pytest.approx(1.0, rel=1e-12)
    assert np.all(geom.diameters >= geom.radii)


def test_remesh_honours_size_field_and_keeps_boundary_names():
    centre, radius, h = (0.5, 0.5), 0.15, 0.01
    mesh = adapt_to(build_mesh(SQUARE, 0.05), lambda c: disc_sizes(c, centre, radius, h))
    assert set(mesh.GetBoundaries()) == set(Geometry.BOUNDARIES)
    coords = np.array(mesh.ngmesh.Coordinates())
    sides = {"bottom": (1, 0.0), "right": (0, 1.0), "top": (1, 1.0), "left": (0, 0.0)}
    for el in mesh.Elements(ngs.BND):
        axis, value = sides[el.mat]
        assert all(abs(coords[v.nr, axis] - value) < 1e-12 for v in el.vertices), el.mat

    geom = ElementGeometry.of(mesh)
    r = np.linalg.norm(geom.centroids - np.asarray(centre), axis=1)
    ratio = geom.diameters[r < radius - 2 * h] / h
    assert 0.5 < ratio.min() and ratio.max() < 2.0, (ratio.min(), ratio.max())
    assert 0.7 < np.median(ratio) < 1.4
    far = geom.diameters[r > radius + 0.3]  # beyond the graded halo: the background size
    assert 0.5 < np.median(far) / HMAX < 2.0


def test_coarsening_follows_a_moving_feature():
    radius, h = 0.1, 0.01

    def vertices_near(mesh, point):
        coords = np.array(mesh.ngmesh.Coordinates())[:, :2]
        return int(np.count_nonzero(np.linalg.norm(coords - point, axis=1) < radius))

    start = np.array([0.2, 0.5])
    background = build_mesh(SQUARE, HMAX)
    mesh = adapt_to(build_mesh(SQUARE, 0.05), lambda c: disc_sizes(c, start, radius, h))
    refined_count, totals = vertices_near(mesh, start), [mesh.nv]
    for x in (0.4, 0.6, 0.8):  # each step moves the disc by a full diameter
        mesh = adapt_to(mesh, lambda c: disc_sizes(c, (x, 0.5), radius, h), times=1)
        totals.append(mesh.nv)
    left = vertices_near(mesh, start)
    assert refined_count > 200, refined_count
    assert left <= 2 * vertices_near(background, start) + 5, (left, refined_count)
    assert max(totals) < 1.5 * min(totals), totals
    assert vertices_near(mesh, np.array([0.8, 0.5])) > 0.7 * refined_count


def test_cap_vertices_keeps_the_finest_sizes():
    rng = np.random.default_rng(1)
    sizes = np.exp(rng.uniform(np.log(1e-3), np.log(HMAX), 2000))
    weights = np.full(2000, 1.0 / 2000)
    wanted = predict_vertices(sizes, weights)
    for cap in (wanted / 3, wanted / 100, wanted / 1e4):
        capped = cap_vertices(sizes, weights, cap, hmax=HMAX)
        assert predict_vertices(capped, weights) <= cap * (1 + 1e-9)
        order = np.argsort(sizes)
        assert np.all(np.diff(capped[order]) >= -1e-15), "the order of sizes must be kept"
        assert np.all(capped >= sizes * (1 - 1e-12)), "the cap only coarsens"
    mild = cap_vertices(sizes, weights, wanted / 3, hmax=HMAX)
    assert mild.min() == pytest.approx(sizes.min()), "stage 1 keeps the finest size"
    assert np.array_equal(cap_vertices(sizes, weights, 2 * wanted, hmax=HMAX), sizes)


def test_cap_vertices_scaling_keeps_the_shape_of_the_field():
    """keep_finest=False (``adaptivity.size_field = "equidistributed"``): every size grows by
    the same factor (up to hmax), the least one whose prediction fits."""
    rng = np.random.default_rng(2)
    sizes = np.exp(rng.uniform(np.log(1e-3), np.log(HMAX), 2000))
    weights = np.full(2000, 1.0 / 2000)
    wanted = predict_vertices(sizes, weights)
    for cap in (wanted / 3, wanted / 100):
        capped = cap_vertices(sizes, weights, cap, hmax=HMAX, keep_finest=False)
        factor = capped.min() / sizes.min()
        below = capped < HMAX * (1 - 1e-12)
        assert factor > 1
        assert np.allclose(capped[below], factor * sizes[below], rtol=1e-12)
        assert np.all(capped[~below] == pytest.approx(HMAX))
        assert predict_vertices(capped, weights) <= cap * (1 + 1e-9)
        # the least factor (bisection to 0.1 %): 0.2 % less would not fit
        assert predict_vertices(np.minimum(factor / 1.002 * sizes, HMAX), weights) > cap
    assert np.array_equal(cap_vertices(sizes, weights, 2 * wanted, hmax=HMAX, keep_finest=False), sizes)


@pytest.mark.xfail(strict=True, reason=(
    "known defect (issue #13): when the finest sizes alone exceed the cap, stage 2 of "
    "cap_vertices scales the {h_lo, hmax} field of stage 1 at lambda = 8, so a region asked for "
    "at 1.5 h_lo (the crack core next to hmin-floored estimator spots) ends at hmax"))
def test_cap_keeps_the_core_finer_than_the_far_field_when_the_finest_sizes_overflow():
    # 1 % of the area asks for h_lo (spots), 5 % for 1.5 h_lo (the core), the rest for hmax;
    # the spots alone predict 4x the cap
    h_lo, hmax = 1e-3, 0.1
    weights = np.full(100, 0.01)
    sizes = np.full(100, hmax)
    sizes[0], sizes[1:6] = h_lo, 1.5 * h_lo
    spots_alone = predict_vertices(np.where(sizes == h_lo, h_lo, np.inf), weights)
    capped = cap_vertices(sizes, weights, spots_alone / 4, hmax=hmax)
    assert capped[1:6].max() <= 2 * capped[0], (capped[0], capped[1:6].max(), capped[-1])


def test_vertex_cap_is_never_exceeded_and_keeps_the_tip_finest():
    mesh = build_mesh(SQUARE, 0.04)
    geom = ElementGeometry.of(mesh)
    tip = np.array([0.6, 0.5])
    eta = np.exp(-np.linalg.norm(geom.centroids - tip, axis=1) / 0.05)  # largest at the tip
    sizes = size_field_from_indicator(mesh, eta, target_h=5e-4, hmin=5e-4, hmax=HMAX)
    assert predict_vertices(sizes, geom.measures) > 20 * 1500  # far more than the cap
    new = adapt_mesh(mesh, SQUARE, sizes, hmax=HMAX, max_vertices=1500)
    assert new.nv <= 1500
    assert new.nv > 1000, "the cap should be used, not wasted"
    new_geom = ElementGeometry.of(new)
    distance = np.linalg.norm(new_geom.centroids - tip, axis=1)
    near, far = new_geom.diameters[distance < 0.02], new_geom.diameters[distance > 0.3]
    assert near.max() < np.median(far) / 5, (near.max(), np.median(far))


def test_cap_holds_when_the_prediction_is_badly_calibrated():
    field = sample_size_field(build_mesh(SQUARE, 0.05), np.full(
        len(ElementGeometry.of(build_mesh(SQUARE, 0.05)).measures), 0.01))
    density = VertexDensity(0.3, measured=True)  # predicts ~5x too few vertices
    new = remesh(SQUARE, field.points, field.sizes, weights=field.weights, hmax=HMAX,
                 max_vertices=800, density=density)
    assert new.nv <= 800
    assert density.measured and density.value > 1.0  # re-measured on the meshes made


def test_learned_density_makes_one_mesh_per_change(caplog):
    """A crack whose tip moves across the square under a binding cap. Netgen's vertex constant
    for such fields is not the default 1.45 (measured here: 5 meshes took 9 Netgen calls with
    it); with the run's learned constant every change after the first is one call, and the cap
    is used, not wasted."""
    cap, density, attempts = 1500, VertexDensity(), []
    background = build_mesh(SQUARE, 0.02)
    centroids = ElementGeometry.of(background).centroids
    for tip_x in (0.3, 0.4, 0.5, 0.6, 0.7):
        tip = np.array([tip_x, 0.5])
        distance = np.where(centroids[:, 0] < tip_x, np.abs(centroids[:, 1] - 0.5),
                            np.linalg.norm(centroids - tip, axis=1))
        sizes = np.clip(0.001 + 0.5 * distance, 0.001, HMAX)
        caplog.clear()
        with caplog.at_level(logging.INFO, logger="ngfrac.mesh.remesh"):
            mesh = adapt_mesh(background, SQUARE, sizes, hmax=HMAX, max_vertices=cap,
                              density=density)
        attempts.append(sum("remesh attempt" in r.getMessage() for r in caplog.records))
        assert 0.8 * cap <= mesh.nv <= cap, mesh.nv
    assert attempts[1:] == [1, 1, 1, 1], attempts


def test_hmin_is_a_floor_of_the_delivered_mesh():
    # A crack band at hmin graded outwards: asked for nothing below hmin, Netgen's smallest
    # longest edge was 0.86 hmin (measured); with the learned floor none is below hmin.
    hmin = 2e-3
    cracks = [[(0.0, 0.5), (0.3, 0.5)]]
    mesh = build_mesh(SQUARE, 0.02, cracks)
    c = ElementGeometry.of(mesh).centroids
    distance = np.where(c[:, 0] < 0.6, np.abs(c[:, 1] - 0.5), np.hypot(c[:, 0] - 0.6, c[:, 1] - 0.5))
    sizes = np.clip(hmin + 0.3 * distance, hmin, HMAX)
    floor = SizeFloor()
    new = adapt_mesh(mesh, netgen_geometry(SQUARE, cracks), sizes, hmax=HMAX,
                     max_vertices=20000, hmin=hmin, floor=floor)
    delivered = ElementGeometry.of(new).diameters
    assert delivered.min() >= hmin, (delivered.min(), floor)
    # the floor costs little: the band is still made of elements near hmin (median of the
    # finest percent within 1.6 hmin, Netgen's spread on a constant band, module docstring)
    assert np.quantile(delivered, 0.01) < 1.6 * hmin / floor.ratio


def test_a_feature_below_hmin_leaves_the_floor_and_the_requested_mesh_alone():
    # A slit 0.001 wide (hmin/2) cut out of the unit square: Netgen meshes its end with edges
    # near its width whatever it is asked, so no floor cures the shortfall. The learned floor used to rise
    # anyway (here its ratio fell to 0.137 in this one call), and over a run's mesh changes it
    # coarsened what was asked for: three-point bending with a 2 um slit and hmin = 3 um, the
    # tip disc asked for 7.5 um had elements up to 15.5 um after the first change (measured).
    hmin = 2e-3
    plate = Geometry(kind="occ", shapes=[
        {"type": "rectangle", "corner": [0, 0], "size": [1, 1]},
        {"type": "rectangle", "corner": [-0.01, 0.4995], "size": [0.31, 0.001], "op": "cut"}])
    domain = plate.domain()
    mesh = domain.build_mesh(0.05)
    c = ElementGeometry.of(mesh).centroids
    sizes = np.clip(hmin + 0.3 * np.hypot(c[:, 0] - 0.3, c[:, 1] - 0.5), hmin, HMAX)
    floor = SizeFloor()
    with pytest.warns(UserWarning, match="below hmin"):
        new = adapt_mesh(mesh, domain.netgen_geometry(), sizes, hmax=HMAX, max_vertices=20000,
                         hmin=hmin, floor=floor)
    assert floor.ratio == 1.0
    geom = ElementGeometry.of(new)
    ring = np.abs(np.hypot(geom.centroids[:, 0] - 0.3, geom.centroids[:, 1] - 0.5) - 0.01) < 0.003
    # asked there: 2-3 hmin (hmin + 0.3 d); measured 2.91 hmin at most, 4.06 with the old
    # floor, whose last attempt was sized with the ratio already lowered three times
    assert ring.any() and geom.diameters[ring].max() < 3.5 * hmin


def test_size_floor_learns_the_shortfall():
    floor = SizeFloor()
    assert floor.floor(1.0) == 1.0 and not floor.update(1.2, 1.0)
    assert floor.update(0.8, 1.0) and floor.floor(1.0) == pytest.approx(1.25)
    assert floor.remeshes == 1


def test_remesh_without_weights_and_impossible_caps():
    points = np.array([[0.5, 0.5], [0.25, 0.25]])
    new = remesh(SQUARE, points, np.array([0.01, 0.02]), hmax=0.2, max_vertices=10**5)
    coords = np.array(new.ngmesh.Coordinates())[:, :2]
    assert np.min(np.linalg.norm(coords - points[0], axis=1)) < 0.02
    with pytest.raises(RuntimeError, match="max_vertices"):
        remesh(SQUARE, points, np.array([0.01, 0.02]), hmax=0.2, max_vertices=3, max_attempts=2)


def test_size_field_from_indicator_equidistributes():
    mesh = build_mesh(SQUARE, 0.05)
    geom = ElementGeometry.of(mesh)
    # eta_T = h_T^2 * |D^2 u| for P1 in 2D: a second derivative 100x larger on the left half
    curvature = np.where(geom.centroids[:, 0] < 0.5, 100.0, 1.0)
    eta = geom.diameters ** 2 * curvature
    sizes = size_field_from_indicator(mesh, eta, target_h=0.01, hmin=1e-3, hmax=1.0, order=1)
    worst = np.argmax(eta)
    assert sizes[worst] == pytest.approx(0.01)
    left, right = sizes[geom.centroids[:, 0] < 0.5], sizes[geom.centroids[:, 0] >= 0.5]
    # h^2 |D^2 u| = tol everywhere: sizes differ by sqrt(100) = 10 between the halves
    assert np.median(right) / np.median(left) == pytest.approx(10.0, rel=0.05)
    clipped = size_field_from_indicator(mesh, eta, target_h=0.01, hmin=0.02, hmax=0.05)
    assert clipped.min() == 0.02 and clipped.max() == 0.05
    assert np.all(size_field_from_indicator(mesh, 0 * eta, target_h=0.01, hmin=0.01,
                                            hmax=0.05) == 0.05)
    with pytest.raises(ValueError, match="elements"):
        size_field_from_indicator(mesh, eta[:-1], target_h=0.01, hmin=0.01, hmax=0.05)


def test_grade_sizes_is_lipschitz():
    mesh = build_mesh(SQUARE, 0.05)
    geom = ElementGeometry.of(mesh)
    sizes = np.full(len(geom.measures), HMAX)
    sizes[0] = 1e-3
    graded = grade_sizes(mesh, sizes, grading=0.3)
    assert np.all(graded <= sizes) and graded[0] == 1e-3
    reach = 1e-3 + 0.3 * np.linalg.norm(geom.centroids - geom.centroids[0], axis=1)
    assert np.all(graded >= np.minimum(reach, HMAX) - 1e-12), "paths are never shorter"
    assert np.all(graded <= np.minimum(1.2 * reach, HMAX) + 0.3 * 0.1), "but nearly straight"


def test_sample_size_field_weights_and_density():
    mesh = build_mesh(SQUARE, 0.1)
    geom = ElementGeometry.of(mesh)
    field = sample_size_field(mesh, np.full(len(geom.measures), 0.02))
    assert field.weights.sum() == pytest.approx(1.0)
    assert len(field.sizes) > 10 * len(geom.measures)  # lattices inside the coarse elements
    spacing = np.median(np.sort(np.linalg.norm(field.points[:200, None] - field.points[None],
                                               axis=2), axis=1)[:, 1])
    assert spacing < 0.02
