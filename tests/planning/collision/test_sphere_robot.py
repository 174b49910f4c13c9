"""Sphere models of robot geometry (planning.collision.sphere_robot): shape_polytope describes each
Drake shape by a polytope containing it (or a sphere's radius); cover_shape covers a posed shape,
inner balls only where they lie inside it; robot_spheres covers every collision geometry of the
given bodies in their frames and caches the covers on disk, keyed by the geometry."""

import numpy as np
import pytest
from pydrake.geometry import Box, Capsule, Convex, Cylinder, Sphere
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.tree import BodyIndex

import planning.collision.sphere_robot as mut
from planning import PlanningScene

X_BG = RigidTransform(RollPitchYaw(0.3, -0.2, 0.5), [0.1, -0.05, 0.2])


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


def covered(points, cover, tolerance=1e-9):
    d = np.linalg.norm(points[:, None] - cover.p_BS[None], axis=2)
    return (d <= cover.radius + tolerance).any(axis=1)


def test_shape_polytope_of_each_shape(tmp_path):
    v, polygons, radius, has_inner = mut.shape_polytope(Sphere(0.07))
    assert v is None and polygons is None and radius == 0.07 and has_inner
    v, polygons, radius, has_inner = mut.shape_polytope(Box(0.1, 0.2, 0.3))
    assert v.shape == (8, 3) and len(polygons) == 6 and radius is None and has_inner
    np.testing.assert_allclose(np.ptp(v, axis=0), [0.1, 0.2, 0.3])
    v, polygons, radius, has_inner = mut.shape_polytope(Cylinder(0.05, 0.2))
    assert radius is None and not has_inner  # the prism's inner balls may leave the cylinder
    assert np.min(np.linalg.norm(v[:, :2], axis=1)) >= 0.05
    # A mesh is described by its convex hull: a tetrahedron's four corners, inner point dropped.
    obj = tmp_path / "tetra.obj"
    corners = [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1], [0.01, 0.01, 0.01]]
    faces = ["f 1 3 2", "f 1 2 4", "f 2 3 4", "f 1 4 3"]
    obj.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in corners) + "\n".join(faces) + "\n")
    v, polygons, radius, has_inner = mut.shape_polytope(Convex(str(obj)))
    assert len(v) == 4 and radius is None and has_inner
    assert sorted(map(tuple, np.round(v, 9))) == sorted(map(tuple, np.array(corners[:4], float)))
    assert len(polygons) == 4 and all(len(p) == 3 for p in polygons)
    with pytest.raises(NotImplementedError, match="Capsule"):
        mut.shape_polytope(Capsule(0.05, 0.2))


def test_cover_shape_of_a_posed_box_contains_it_in_the_body_frame():
    size = np.array([0.06, 0.04, 0.1])
    cover = mut.cover_shape(Box(*size), X_BG, slack=0.01)
    rng = np.random.default_rng(0)
    p_G = rng.uniform(-0.5, 0.5, (3000, 3)) * size
    axis = rng.integers(0, 3, 3000)
    p_G[np.arange(3000), axis] = np.sign(p_G[np.arange(3000), axis]) * size[axis] / 2  # faces
    p_B = X_BG.multiply(p_G.T).T
    assert covered(p_B, cover).all()
    # Inner balls are inside the box (in its own frame G).
    p_GS = X_BG.inverse().multiply(cover.p_BS.T).T
    assert np.all(np.abs(p_GS) + cover.inner[:, None] <= size / 2 + 1e-9)
    assert np.any(cover.inner > 0)


def test_cover_shape_of_spheres_and_cylinders():
    ball = mut.cover_shape(Sphere(0.05), X_BG, slack=0.01)
    np.testing.assert_allclose(ball.p_BS, [X_BG.translation()])
    np.testing.assert_array_equal(ball.radius, [0.05])
    np.testing.assert_array_equal(ball.inner, [0.05])  # exact
    rod = mut.cover_shape(Cylinder(0.02, 0.15), X_BG, slack=0.01)
    np.testing.assert_array_equal(rod.inner, 0.0)
    angle = np.linspace(0.0, 2 * np.pi, 400)
    z = np.linspace(-0.075, 0.075, 400)
    rim = np.column_stack([0.02 * np.cos(angle), 0.02 * np.sin(angle), z])
    assert covered(X_BG.multiply(rim.T).T, rod).all()


def test_scaled_covers_of_large_boxes_with_far_corners():
    """A large held box, its grid scaled to 4 cm: the grid is not centred in the box, so some
    corners are farther from every grid point than its depth plus the slack (this raised
    "sphere cover did not converge" before); the cover still contains the box."""
    size = np.array([0.6, 0.3, 0.4])
    cover = mut.cover_shape(Box(*size), RigidTransform(), slack=0.015, scaled=True)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * size / 2
    rng = np.random.default_rng(1)
    faces = rng.uniform(-0.5, 0.5, (3000, 3)) * size
    axis = rng.integers(0, 3, 3000)
    faces[np.arange(3000), axis] = np.sign(faces[np.arange(3000), axis]) * size[axis] / 2
    inside = rng.uniform(-0.5, 0.5, (2000, 3)) * size
    assert covered(np.vstack([corners, faces, inside]), cover).all()
    assert np.all(np.abs(cover.p_BS) + cover.inner[:, None] <= size / 2 + 1e-9)


def robot_geometry(scene, names):
    plant = scene.plant
    inspector = scene.checker.MakeStandaloneModelContext().GetQueryObject().inspector()
    bodies = [int(plant.GetBodyByName(n, scene.model.instance).index()) for n in names]
    return plant, inspector, bodies


def test_robot_spheres_cover_every_collision_geometry_and_are_cached(scene, tmp_path, monkeypatch):
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(tmp_path))
    names = ["panda_link7", "panda_hand", "panda_leftfinger"]  # meshes and boxes
    plant, inspector, bodies = robot_geometry(scene, names)
    dut = mut.robot_spheres(plant, inspector, bodies, 0.015)
    assert sorted(dut) == sorted(bodies)
    for body in bodies:
        spheres = dut[body]
        assert np.all(spheres.radius >= spheres.inner)
        geometries = plant.GetCollisionGeometriesForBody(plant.get_body(BodyIndex(body)))
        assert geometries
        for g in geometries:
            v, polygons, _, _ = mut.shape_polytope(inspector.GetShape(g))
            points = np.vstack([v] + [v[f].mean(axis=0, keepdims=True) for f in polygons])
            p_B = inspector.GetPoseInFrame(g).multiply(points.T).T
            assert covered(p_B, spheres).all(), plant.get_body(BodyIndex(body)).name()
    assert len(list((tmp_path / "spheres").glob("*.npy"))) == 1
    # Read back from the cache: nothing is covered again.
    monkeypatch.setattr(mut, "cover_shape", lambda *args, **kwargs: pytest.fail("covered again"))
    again = mut.robot_spheres(plant, inspector, bodies, 0.015)
    for body in bodies:
        np.testing.assert_array_equal(again[body].p_BS, dut[body].p_BS)
        np.testing.assert_array_equal(again[body].radius, dut[body].radius)
        np.testing.assert_array_equal(again[body].inner, dut[body].inner)
    # Other bodies or another slack: another cache entry.
    monkeypatch.undo()
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(tmp_path))
    finger = mut.robot_spheres(plant, inspector, bodies[2:], 0.015)
    np.testing.assert_array_equal(finger[bodies[2]].radius, dut[bodies[2]].radius)
    looser = mut.robot_spheres(plant, inspector, bodies[2:], 0.03)
    assert len(looser[bodies[2]].radius) <= len(dut[bodies[2]].radius)
    assert len(list((tmp_path / "spheres").glob("*.npy"))) == 3


def test_held_covers_are_the_scaled_covers_and_are_cached(tmp_path, monkeypatch):
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(tmp_path))
    box = Box(0.04, 0.05, 0.12)
    dut = mut.held_cover(box, 0.015)
    expected = mut.cover_shape(box, RigidTransform(), 0.015, scaled=True)
    for a, b in ((dut.p_BS, expected.p_BS), (dut.radius, expected.radius)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(dut.inner, expected.inner)
    assert len(list((tmp_path / "spheres").glob("held-*.npy"))) == 1
    monkeypatch.setattr(mut, "cover_shape", lambda *args, **kwargs: pytest.fail("covered again"))
    again = mut.held_cover(Box(0.04, 0.05, 0.12), 0.015)
    np.testing.assert_array_equal(again.radius, dut.radius)
    monkeypatch.undo()
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(tmp_path))
    # Another size, shape or slack: another entry; a sphere needs no cover file.
    mut.held_cover(Box(0.04, 0.05, 0.13), 0.015)
    mut.held_cover(Cylinder(0.03, 0.1), 0.015)
    mut.held_cover(Box(0.04, 0.05, 0.12), 0.03)
    assert len(list((tmp_path / "spheres").glob("held-*.npy"))) == 4


def test_a_large_shape_gets_a_coarser_grid_and_is_still_covered():
    """A pedestal-sized box (0.9 x 0.8 x 0.3 m: 216,000 cells at 1 cm) is covered on a coarser
    grid, within memory, and the cover still holds every point of its surface."""
    size = np.array([0.9, 0.8, 0.3])
    cover = mut.cover_shape(Box(*size), RigidTransform(), slack=0.015)
    rng = np.random.default_rng(0)
    points = rng.uniform(-size / 2, size / 2, (4000, 3))
    axis = rng.integers(0, 3, len(points))
    points[np.arange(len(points)), axis] = np.sign(rng.uniform(-1, 1, len(points))) * size[axis] / 2
    gaps = np.linalg.norm(points[:, None] - cover.p_BS[None], axis=2) - cover.radius[None]
    assert (gaps.min(axis=1) <= 1e-9).all()
    assert len(cover.radius) < 2000
