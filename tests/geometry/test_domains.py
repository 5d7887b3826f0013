"""Domains as objects (ngfrac.geometry.domains): Rectangle and Box, and domain_of a scene geometry."""
import math

import numpy as np
import pytest

from ngfrac.geometry.domains import (CRACK_BOUNDARY, Box, Domain, MeshingError, Rectangle,
                                 build_mesh, domain_of)
from ngfrac.scene import Geometry

RECT = Rectangle(2.0, 0.5, origin=(-1.0, 0.25))
BOX = Box(1.0, 0.5, 0.25, origin=(0.0, -0.5, 1.0))


def test_both_are_domains_and_domain_of_builds_them():
    assert isinstance(RECT, Domain) and isinstance(BOX, Domain)
    assert not isinstance(Geometry(width=1.0, height=1.0), Domain)
    assert domain_of(Geometry(width=2.0, height=0.5, origin=(-1.0, 0.25))) == RECT
    box = domain_of(Geometry(kind="box", width=1.0, height=0.5, depth=0.25, origin=(0, -0.5, 1)))
    assert box == BOX and domain_of(box) is box
    with pytest.raises(TypeError, match="Geometry or a Domain"):
        domain_of("rectangle")


def test_sizes_and_names():
    assert (RECT.dim, BOX.dim) == (2, 3)
    assert RECT.measure == pytest.approx(1.0) and BOX.measure == pytest.approx(0.125)
    assert RECT.diameter == pytest.approx(math.hypot(2.0, 0.5))
    assert BOX.diameter == pytest.approx(math.sqrt(1 + 0.25 + 0.0625))
    assert (RECT.shortest_side, BOX.shortest_side) == (0.5, 0.25)
    assert RECT.upper == (1.0, 0.75) and BOX.upper == (1.0, 0.0, 1.25)
    assert RECT.boundary_names == Geometry(width=1, height=1).boundary_names
    assert BOX.boundary_names == Geometry(kind="box", width=1, height=1, depth=1).boundary_names
    assert RECT.sides() == {"left": (0, -1.0), "right": (0, 1.0), "bottom": (1, 0.25),
                            "top": (1, 0.75)}
    assert BOX.sides()["back"] == (2, 1.0) and BOX.sides()["front"] == (2, 1.25)


@pytest.mark.parametrize("domain", [RECT, BOX], ids=["rectangle", "box"])
def test_on_boundary_and_contains(domain):
    centre = 0.5 * (np.asarray(domain.origin) + np.asarray(domain.upper))
    assert domain.contains(centre) and not domain.on_boundary(centre)
    for name, (axis, coordinate) in domain.sides().items():
        outward = 1.0 if name in ("right", "top", "front") else -1.0
        point = centre.copy()
        point[axis] = coordinate
        assert domain.on_boundary(point) and domain.contains(point), name
        outside = point.copy()
        outside[axis] += outward * 1e-6
        assert not domain.contains(outside) and domain.contains(outside, tol=2e-6)
        near = point.copy()
        near[axis] -= outward * 1e-3
        assert not domain.on_boundary(near) and domain.on_boundary(near, tol=2e-3)
    # the default tolerance is relative to the longest side
    point = centre.copy()
    point[0] = domain.origin[0] + 0.5e-10 * domain.longest_side
    assert domain.on_boundary(point)
    points = np.array([centre, centre + 10.0])
    assert domain.contains(points).tolist() == [True, False]
    with pytest.raises(ValueError, match="dimension"):
        domain.contains(np.zeros(domain.dim + 1))


def test_a_2d_point_with_z_is_tested_in_the_plane():
    assert RECT.on_boundary([1.0, 0.5, 7.0]) and not RECT.on_boundary([0.0, 0.5, 7.0])


@pytest.mark.parametrize("domain", [RECT, BOX], ids=["rectangle", "box"])
def test_sample_points_cover_the_domain(domain):
    points = np.column_stack(domain.sample_points(5))
    assert points.shape == (5 ** domain.dim, domain.dim)
    assert np.all(domain.contains(points))
    assert np.allclose(points.min(axis=0), domain.origin)
    assert np.allclose(points.max(axis=0), domain.upper)
    default = domain.sample_points()
    assert len(default[0]) == (201 ** 2 if domain.dim == 2 else 41 ** 3)
    for name, (axis, coordinate) in domain.sides().items():
        face = np.column_stack(domain.boundary_points(name, 4))
        assert face.shape == (4 ** (domain.dim - 1), domain.dim)
        assert np.all(face[:, axis] == coordinate)
        assert all(domain.on_boundary(p) for p in face)
    with pytest.raises(ValueError, match="not a boundary"):
        domain.boundary_points("inside")


def test_the_section_describes_the_domain():
    """The scene section's domain() is the domain the stepper and the checks use."""
    geometry = Geometry(kind="box", width=1.0, height=0.5, depth=0.25, origin=(0, -0.5, 1))
    assert geometry.domain() == BOX
    for ours, theirs in zip(BOX.sample_points(6), geometry.domain().sample_points(6)):
        assert np.array_equal(ours, theirs)


def test_meshes_have_the_named_boundaries_and_the_crack():
    rect = RECT.build_mesh(0.1, [[(-1.0, 0.5), (0.0, 0.5)]])
    assert set(rect.GetBoundaries()) == {*RECT.boundary_names, CRACK_BOUNDARY}
    crack = [[0.0, -0.25, 1.0], [0.5, -0.25, 1.0], [0.5, -0.25, 1.25], [0.0, -0.25, 1.25]]
    box = BOX.build_mesh(0.2, [crack])
    assert set(box.GetBoundaries()) == {*BOX.boundary_names, CRACK_BOUNDARY}
    coordinates = np.array(box.ngmesh.Coordinates())
    assert np.allclose(coordinates.min(axis=0), BOX.origin)
    assert np.allclose(coordinates.max(axis=0), BOX.upper)
    with pytest.raises(ValueError, match="maxh"):
        RECT.build_mesh(0.0)
    with pytest.raises(MeshingError, match="zero length"):
        build_mesh(RECT, 0.1, [[(-1.0, 0.5), (0.0, 0.5), (0.0, 0.5)]])
