"""The crack set: the tip is a point of the crack itself, never stray damage elsewhere."""
import math

import numpy as np
import ngsolve as ngs
import pytest
from netgen.geom2d import unit_square
from netgen.occ import Box, OCCGeometry, Pnt

from ngfrac.physics.cracks import distance_to_polygons, distance_to_polylines, optimal_profile
from ngfrac.post.crackset import NodeGraph, _joined_pairs, find_crack
from ngfrac.fem.nodal import LagrangeNodes

EPS = 0.02
H = 0.01
SLIT = [[0.0, 0.5], [0.3, 0.5]]
BAND = EPS * math.log(2.0) + H


@pytest.fixture(scope="module", params=[1, 2], ids=["P1", "P2"])
def square(request):
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=H))
    nodes = LagrangeNodes(ngs.H1(mesh, order=request.param))
    return nodes, NodeGraph(mesh, nodes)


def crack_to(points, end):
    """z of a straight crack from the slit's mouth to ``end`` (the optimal profile)."""
    return optimal_profile(distance_to_polylines(points, [[SLIT[0], end]]), EPS)


def stray_damage(points):
    """Damage a crack model leaves where it should not be taken for the crack: a clamped
    corner (z = 1 near (1, 0)) and a loaded face (z = 0.8 along the top edge)."""
    corner = np.linalg.norm(points - [1.0, 0.0], axis=1) < 0.06
    face = points[:, 1] > 0.97
    return np.where(corner, 1.0, np.where(face, 0.8, 0.0))


def test_the_tip_stays_on_the_crack_with_stray_damage(square):
    nodes, graph = square
    z = np.maximum(crack_to(nodes.points, [0.6, 0.5]), stray_damage(nodes.points))
    found = find_crack(graph, z, [SLIT], np.array(SLIT[-1]), BAND, bin_width=2 * EPS)
    # the z = 1/2 contour ends eps ln 2 ahead of the ridge's end, within one element
    assert found.tip == pytest.approx([0.6 + EPS * math.log(2.0), 0.5], abs=H)
    assert found.n_damage_zones == 2
    # the grown ridge: from the slit's tip (0.3) to the tip, to within an element
    assert found.grown_length == pytest.approx(0.3 + EPS * math.log(2.0), abs=H)


def test_without_stray_damage_no_zone_is_counted(square):
    nodes, graph = square
    found = find_crack(graph, crack_to(nodes.points, [0.6, 0.5]), [SLIT], np.array(SLIT[-1]),
                       BAND, bin_width=2 * EPS)
    assert found.n_damage_zones == 0


def test_a_crack_that_cut_the_plate_ends_on_its_ridge(square):
    """Near the far edge the damaged band widens (|y - 0.5| < 0.06, z >= 1/2 there): its
    corners are farther from the slit than the ridge, but the tip is on the ridge y = 0.5."""
    nodes, graph = square
    points = nodes.points
    z = crack_to(points, [1.0, 0.5])
    widened = (points[:, 0] > 0.9) & (np.abs(points[:, 1] - 0.5) < 0.06)
    z = np.where(widened, np.maximum(z, 0.5 + 0.5 * (1 - np.abs(points[:, 1] - 0.5) / 0.06)), z)
    found = find_crack(graph, z, [SLIT], np.array(SLIT[-1]), BAND, bin_width=2 * EPS)
    assert found.tip[0] == pytest.approx(1.0, abs=1e-12)
    assert abs(found.tip[1] - 0.5) <= H / 2, found.tip  # the ridge node (the corners: 0.06 off)
    assert found.grown_length == pytest.approx(0.7, abs=H)


def test_before_growth_the_tip_is_the_initial_tip(square):
    nodes, graph = square
    z = optimal_profile(distance_to_polylines(nodes.points, [SLIT]), EPS)
    found = find_crack(graph, z, [SLIT], np.array(SLIT[-1]), BAND, bin_width=2 * EPS)
    assert found.tip == pytest.approx(SLIT[-1])
    assert found.grown_length == 0.0


def test_without_an_initial_crack_the_first_damage_is_the_crack(square):
    """A nucleated crack from (0.2, 0.5) to (0.7, 0.5) and stray damage at a corner: the
    nucleus picks the crack; its tip is the ridge end farthest from the nucleus."""
    nodes, graph = square
    z = optimal_profile(distance_to_polylines(nodes.points, [[[0.2, 0.5], [0.7, 0.5]]]), EPS)
    z = np.maximum(z, stray_damage(nodes.points))
    found = find_crack(graph, z, [], None, BAND, bin_width=2 * EPS, nucleus=np.array([0.25, 0.5]))
    assert found.tip == pytest.approx([0.7 + EPS * math.log(2.0), 0.5], abs=H)
    assert found.n_damage_zones == 2
    nothing = find_crack(graph, np.zeros(len(z)), [], None, BAND, bin_width=2 * EPS)
    assert np.all(np.isnan(nothing.tip))


def test_in_3d_the_tip_is_on_the_crack_plane_not_on_a_damaged_face():
    """The box3d failure on a fresh clone: damage on a loaded face (y = 1) was taken for the
    tip. The crack plane y = 0.5 runs from x = 0 to the front at x = 0.3 (grown to 0.6)."""
    box = Box(Pnt(0, 0, 0), Pnt(1, 1, 0.1))
    mesh = ngs.Mesh(OCCGeometry(box).GenerateMesh(maxh=0.05))
    nodes = LagrangeNodes(ngs.H1(mesh, order=1))
    graph = NodeGraph(mesh, nodes)
    initial = [[0, 0.5, 0], [0.3, 0.5, 0], [0.3, 0.5, 0.1], [0, 0.5, 0.1]]
    grown = [[0, 0.5, 0], [0.6, 0.5, 0], [0.6, 0.5, 0.1], [0, 0.5, 0.1]]
    points = nodes.points
    z = optimal_profile(distance_to_polygons(points, [grown]), 0.04)
    z = np.maximum(z, np.where(points[:, 1] > 0.97, 0.9, 0.0))
    found = find_crack(graph, z, [initial], np.array([0.3, 0.5, 0.05]), band=0.08, bin_width=0.04)
    assert abs(found.tip[1] - 0.5) < 0.05, found.tip
    assert 0.6 <= found.tip[0] <= 0.6 + 0.04 * math.log(2.0) + 0.05
    assert found.n_damage_zones == 1


def test_the_tip_never_moves_back_along_the_crack(square):
    """z never decreases, so the tip found before is still on the crack: a new front estimate
    behind it (in the direction of growth) keeps the old tip."""
    nodes, graph = square
    z = crack_to(nodes.points, [0.6, 0.5])
    ahead = np.array([0.63, 0.5])
    found = find_crack(graph, z, [SLIT], np.array(SLIT[-1]), BAND, bin_width=2 * EPS,
                       previous_tip=ahead)
    assert found.tip == pytest.approx(ahead)
    behind = np.array([0.5, 0.5])
    found = find_crack(graph, z, [SLIT], np.array(SLIT[-1]), BAND, bin_width=2 * EPS,
                       previous_tip=behind)
    assert found.tip[0] > 0.6


def test_node_graph_joins_by_element_or_by_sub_simplex(square):
    nodes, graph = square
    mesh = nodes.fes.mesh
    lattice = NodeGraph(mesh, nodes, joined="sub-simplices")
    if nodes.order == 1:  # both are the mesh edges
        np.testing.assert_array_equal(graph.edges, lattice.edges)
    else:  # an element joins all its nodes: the sub-simplex edges and more
        assert len(graph.edges) > len(lattice.edges)
        both = {tuple(e) for e in graph.edges}
        assert all(tuple(e) in both for e in lattice.edges)
    assert len(graph.edges) == graph.graph.nnz // 2
    for joined, made in (("element", graph), ("sub-simplices", lattice)):
        # the pairs each element lists, every pair once, smaller number first, sorted
        rows, cols = _joined_pairs(mesh, nodes, joined)
        listed = np.unique(np.sort(np.column_stack([rows, cols]), axis=1), axis=0)
        np.testing.assert_array_equal(made.edges, listed)
    with pytest.raises(ValueError, match="joined"):
        NodeGraph(mesh, nodes, joined="faces")
