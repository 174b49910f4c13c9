"""planning.io.moveit_shapes: cones, prisms and planes as shapes the planner checks, each
containing (or bounding) what MoveIt checks."""

import numpy as np
import pytest
from pydrake.math import RigidTransform

from planning.io import moveit_shapes as mut


def test_a_cone_hull_contains_the_cone():
    points = mut.cone_points(radius=0.1, length=0.4)
    assert points[-1].tolist() == [0.0, 0.0, 0.2]  # the apex
    base = points[:-1]
    assert np.allclose(base[:, 2], -0.2)
    # Every point of the base circle lies inside the circumscribed polygon.
    sides = len(base)
    inner = np.linalg.norm(base[:, :2], axis=1).min() * np.cos(np.pi / sides)
    assert inner == pytest.approx(0.1)


def test_a_prism_needs_a_polygon():
    points = mut.prism_points([[0, 0], [1, 0], [0, 1]], 0.2)
    assert points.shape == (6, 3) and sorted(set(points[:, 2])) == [-0.1, 0.1]
    with pytest.raises(mut.UnrepresentableError, match="3 points"):
        mut.prism_points([[0, 0], [1, 0]], 0.2)


def test_hull_vertices_drop_inner_points_and_refuse_a_line():
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    vertices = mut.hull_vertices(np.vstack([cube, [[0.5, 0.5, 0.5]]]))
    assert len(vertices) == 8
    with pytest.raises(mut.UnrepresentableError):
        mut.hull_vertices([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]])


def test_a_plane_is_the_box_behind_it():
    piece = mut.plane([0, 0, 1, -0.5], RigidTransform(), [0, 0, 0], "plane")
    assert piece.shape == "box"
    top = piece.X_OS.translation()[2] + piece.size[2] / 2
    assert top == pytest.approx(0.5)  # the box's face lies on z = 0.5, the box below it
    with pytest.raises(ValueError, match="normal"):
        mut.plane([0, 0, 0, 1], RigidTransform(), [0, 0, 0], "plane")
