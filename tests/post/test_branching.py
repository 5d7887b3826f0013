"""Branch counting on synthetic phase fields: the crack set z >= 1/2 and its Reeb graph."""
from __future__ import annotations

import ngsolve as ngs
import numpy as np
import pytest
from netgen.geom2d import unit_square

from ngfrac.post.branching import crack_topology, crack_topology_of
from ngfrac.post.crackset import NodeGraph
from ngfrac.physics.cracks import distance_to_polylines, optimal_profile
from ngfrac.fem.nodal import LagrangeNodes

EPS = 0.02
CRACKS = {
    "straight": [[(0.1, 0.5), (0.9, 0.5)]],
    "wiggling": [[(0.0, 0.5), (0.2, 0.45), (0.4, 0.55), (0.6, 0.45), (0.8, 0.55), (1.0, 0.5)]],
    "Y": [[(0.1, 0.5), (0.5, 0.5), (0.9, 0.8)], [(0.5, 0.5), (0.9, 0.2)]],
    "two": [[(0.1, 0.3), (0.9, 0.3)], [(0.1, 0.7), (0.9, 0.7)]],
    "X": [[(0.1, 0.1), (0.9, 0.9)], [(0.1, 0.9), (0.9, 0.1)]],
}
EXPECTED = {  # (components, endpoints, branch points)
    "straight": (1, 2, 0), "wiggling": (1, 2, 0), "Y": (1, 3, 1), "two": (2, 4, 0), "X": (1, 4, 2),
}


@pytest.fixture(scope="module")
def mesh():
    return ngs.Mesh(unit_square.GenerateMesh(maxh=0.02))


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("name", sorted(CRACKS))
def test_counts_of_synthetic_cracks(mesh, order, name):
    # z is the optimal AT2 profile exp(-d/eps) around the polylines: a band 1.4 eps wide at
    # z >= 1/2, as a converged crack has; the counts are exact integers, no tolerance.
    fes = ngs.H1(mesh, order=order)
    z, nodes = ngs.GridFunction(fes), LagrangeNodes(fes)
    nodes.assign(z, optimal_profile(distance_to_polylines(nodes.points, CRACKS[name]), EPS))
    found = crack_topology_of(z, spacing=2 * EPS)
    assert (found.components, found.endpoints, found.branch_points) == EXPECTED[name], found


def test_the_fork_is_found_where_the_arms_meet(mesh):
    fes = ngs.H1(mesh, order=2)
    z, nodes = ngs.GridFunction(fes), LagrangeNodes(fes)
    nodes.assign(z, optimal_profile(distance_to_polylines(nodes.points, CRACKS["Y"]), EPS))
    found = crack_topology_of(z, spacing=2 * EPS)
    # the shell that splits lies within a shell width (2 eps) plus the band of the junction
    assert np.linalg.norm(found.forks[0] - (0.5, 0.5)) < 4 * EPS, found.forks


def test_a_short_spur_on_the_band_is_no_branch(mesh):
    # a side arm shorter than min_length (3 spacings = 6 eps) is a lump of the band
    spur = CRACKS["straight"] + [[(0.5, 0.5), (0.5, 0.5 + 3 * EPS)]]
    longer = CRACKS["straight"] + [[(0.5, 0.5), (0.5, 0.5 + 12 * EPS)]]
    fes = ngs.H1(mesh, order=1)
    z, nodes = ngs.GridFunction(fes), LagrangeNodes(fes)
    counts = []
    for lines in (spur, longer):
        nodes.assign(z, optimal_profile(distance_to_polylines(nodes.points, lines), EPS))
        counts.append(crack_topology_of(z, spacing=2 * EPS).branch_points)
    assert counts == [0, 1]


def test_no_damage_and_isolated_spots():
    points = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    edges = np.array([[0, 1], [1, 2]])
    empty = crack_topology(points, edges, np.zeros(3), spacing=0.5)
    assert (empty.components, empty.endpoints, empty.branch_points) == (0, 0, 0)
    spot = crack_topology(points, edges, np.array([0.0, 1.0, 0.0]), spacing=0.5)
    assert spot.components == 0  # a single node is shorter than min_length
    with pytest.raises(ValueError, match="spacing"):
        crack_topology(points, edges, np.zeros(3), spacing=0.0)


def test_sub_simplex_graph_of_p2_joins_the_midpoints(mesh):
    fes = ngs.H1(mesh, order=2)
    nodes = LagrangeNodes(fes)
    edges = NodeGraph(mesh, nodes, joined="sub-simplices").edges
    # each mesh edge in two halves plus three midpoint edges per triangle: the P2 lattice
    assert len(edges) == 2 * len(nodes.edge_vertices) + 3 * mesh.ne
