"""Sphere covers of convex shapes (planning.collision.sphere_cover): the outer spheres of a cover
contain the whole polytope (surface and inside), each inner ball lies inside it, a larger slack
needs fewer spheres; the box and prism polytopes and the fan triangulation are what they say;
SphereSet concatenates and changes frames."""

import numpy as np
import pytest

import planning.collision.sphere_cover as mut

HALF = np.array([0.05, 0.02, 0.1])  # half sizes of the test box, m


def box_surface_points(half, n, rng):
    """n random points on the faces of the box with these half sizes (centred at the origin)."""
    points = rng.uniform(-1.0, 1.0, (n, 3)) * half
    axis = rng.integers(0, 3, n)
    rows = np.arange(n)
    points[rows, axis] = np.where(points[rows, axis] >= 0, 1.0, -1.0) * half[axis]
    return points


def covered(points, cover, tolerance=0.0):
    d = np.linalg.norm(points[:, None] - cover.p_BS[None], axis=2)
    return (d <= cover.radius + tolerance).any(axis=1)


def depth(points, vertices, polygons):
    """Distance of each point inside the convex polytope to its boundary (negative outside:
    minus the largest distance beyond a face plane)."""
    tri = mut.polytope_triangles(vertices, polygons)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    n[np.einsum("ij,ij->i", n, vertices.mean(axis=0) - tri[:, 0]) > 0] *= -1  # outward
    offset = np.einsum("ij,ij->i", n, tri[:, 0])
    return -(points @ n.T - offset).max(axis=1)


@pytest.fixture(scope="module")
def box_cover():
    v, faces = mut.box_polytope(2 * HALF)
    return mut.cover_polytope(v, faces, slack=0.01, spacing=0.01, dense_spacing=0.002)


def test_cover_of_a_box_is_conservative_and_inner_balls_inside(box_cover):
    rng = np.random.default_rng(0)
    v, _ = mut.box_polytope(2 * HALF)
    surface = np.vstack([box_surface_points(HALF, 4000, rng), v])
    interior = rng.uniform(-1.0, 1.0, (2000, 3)) * HALF
    assert covered(surface, box_cover).all()
    assert covered(interior, box_cover).all()
    # Inner balls lie inside the box.
    reach = np.abs(box_cover.p_BS) + box_cover.inner[:, None]
    assert np.all(reach <= HALF + 1e-9)
    assert np.all(box_cover.inner <= box_cover.radius)
    assert np.all(box_cover.inner > 0)
    assert len(box_cover.radius) < 100
    # Each outer sphere bulges at most the slack (plus the grid's bound) beyond the box.
    bulge = np.linalg.norm(
        np.maximum(np.abs(box_cover.p_BS) + box_cover.radius[:, None] - HALF, 0), axis=1
    )
    assert bulge.max() < 0.02


def test_a_larger_slack_needs_fewer_spheres(box_cover):
    v, faces = mut.box_polytope(2 * HALF)
    loose = mut.cover_polytope(v, faces, slack=0.03, spacing=0.01, dense_spacing=0.002)
    assert len(loose.radius) < len(box_cover.radius)
    assert covered(
        np.vstack([box_surface_points(HALF, 2000, np.random.default_rng(1)), v]), loose
    ).all()


def test_cover_of_a_tilted_tetrahedron():
    vertices = np.array([[0.0, 0.0, 0.0], [0.12, 0.0, 0.01], [0.02, 0.08, 0.0], [0.03, 0.02, 0.1]])
    polygons = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]
    dut = mut.cover_polytope(vertices, polygons, slack=0.01, spacing=0.01, dense_spacing=0.002)
    rng = np.random.default_rng(2)
    weights = rng.dirichlet(np.ones(3), 3000)  # points on each face
    tri = mut.polytope_triangles(vertices, polygons)
    faces = np.einsum("nk,tkj->tnj", weights, tri).reshape(-1, 3)
    inside = rng.dirichlet(np.ones(4), 2000) @ vertices
    assert covered(np.vstack([faces, inside, vertices]), dut).all()
    # Each inner ball lies inside: its centre at least ``inner`` from every face plane.
    assert np.all(depth(dut.p_BS, vertices, polygons) >= dut.inner - 1e-12)
    assert np.any(dut.inner > 0)


def test_box_polytope():
    v, faces = mut.box_polytope([0.2, 0.4, 0.6])
    assert v.shape == (8, 3) and len(faces) == 6
    np.testing.assert_allclose(np.abs(v), np.broadcast_to([0.1, 0.2, 0.3], (8, 3)))
    assert len({tuple(x) for x in v}) == 8
    for face in faces:  # each face: 4 corners sharing one coordinate
        corners = v[face]
        assert np.any(np.ptp(corners, axis=0) == 0)
    tri = mut.polytope_triangles(v, faces)
    assert tri.shape == (12, 3, 3)
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    assert area.sum() == pytest.approx(2 * (0.2 * 0.4 + 0.2 * 0.6 + 0.4 * 0.6))


def test_cylinder_prism_contains_the_cylinder():
    radius, length, sides = 0.05, 0.2, 16
    v, faces = mut.cylinder_polytope(radius, length, sides=sides)
    assert v.shape == (2 * sides, 3) and len(faces) == sides + 2
    apothem = np.linalg.norm(v[:2, :2].mean(axis=0))
    assert apothem == pytest.approx(radius)  # each side touches the cylinder
    np.testing.assert_allclose(np.unique(v[:, 2]), [-length / 2, length / 2])
    # Points on the cylinder's surface are inside the prism.
    angle = np.random.default_rng(3).uniform(0, 2 * np.pi, 500)
    z = np.linspace(-length / 2, length / 2, 500)
    rim = np.column_stack([radius * np.cos(angle), radius * np.sin(angle), z])
    assert np.all(depth(rim, v, faces) >= -1e-12)


def test_sphere_sets_concatenate_and_change_frames():
    a = mut.SphereSet(np.array([[0.0, 0.0, 0.0]]), np.array([0.1]), np.array([0.05]))
    b = mut.SphereSet(
        np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), np.array([0.2, 0.3]), np.zeros(2)
    )
    both = mut.SphereSet.concat([a, b])
    assert both.p_BS.shape == (3, 3)
    np.testing.assert_array_equal(both.radius, [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(both.inner, [0.05, 0.0, 0.0])
    empty = mut.SphereSet.concat([])
    assert empty.p_BS.shape == (0, 3) and empty.radius.shape == (0,)
    R_AB = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90 deg about z
    moved = both.transformed(R_AB, np.array([0.0, 0.0, 2.0]))
    np.testing.assert_allclose(moved.p_BS, [[0, 0, 2], [0, 1, 2], [-1, 0, 2]], atol=1e-12)
    np.testing.assert_array_equal(moved.radius, both.radius)
    moved.radius[0] = 9.0  # a copy: the original keeps its radii
    assert both.radius[0] == 0.1
