"""Task geometry: the box overlap test (against an exact LP oracle), top-down grasp frames and
the angle between rotations."""

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.solvers import MathematicalProgram, Solve

import planning.task.geometry as mut


def depth(size_a, X_WA, size_b, X_WB) -> float:
    """The largest t such that a point lies t inside both boxes (negative: the boxes are apart),
    as a linear program: the exact answer the separating-axis test must agree with."""
    prog = MathematicalProgram()
    x = prog.NewContinuousVariables(4, "x")  # the point p, then t
    rows, bounds = [], []
    for size, X in ((size_a, X_WA), (size_b, X_WB)):
        R, c, half = X.rotation().matrix(), X.translation(), 0.5 * np.asarray(size)
        for i in range(3):  # |R_i . (p - c)| + t <= half_i
            for sign in (1.0, -1.0):
                a = sign * R[:, i]
                rows.append([*a, 1.0])
                bounds.append(half[i] + a @ c)
    prog.AddLinearConstraint(np.array(rows), np.full(len(rows), -np.inf), np.array(bounds), x)
    prog.AddBoundingBoxConstraint(-10.0, 10.0, x[3])
    prog.AddLinearCost([0.0, 0.0, 0.0, -1.0], x)
    result = Solve(prog)
    assert result.is_success()
    return float(result.GetSolution(x[3]))


def test_simple_cases():
    X = RigidTransform()
    cube = [1.0, 1.0, 1.0]
    assert mut.boxes_overlap(cube, X, cube, X)
    assert mut.boxes_overlap(cube, X, [0.1, 0.1, 0.1], RigidTransform([0.2, 0.2, 0.2]))  # inside
    assert not mut.boxes_overlap(cube, X, cube, RigidTransform([1.01, 0.0, 0.0]))
    assert mut.boxes_overlap(cube, X, cube, RigidTransform([1.0, 0.0, 0.0]))  # touching
    # A cube turned 45 degrees reaches 0.707 m along x: in contact at 1.2 m, clear at 1.25 m.
    turned = RollPitchYaw(0.0, 0.0, np.pi / 4)
    assert mut.boxes_overlap(cube, X, cube, RigidTransform(turned, [1.2, 0.0, 0.0]))
    assert not mut.boxes_overlap(cube, X, cube, RigidTransform(turned, [1.25, 0.0, 0.0]))


def test_crossed_bars_need_the_edge_axes():
    """Two bars turned 45 degrees about their own long axes, crossing one above the other: no
    face normal separates them, only the cross product of their long axes (z)."""
    X_A = RigidTransform(RollPitchYaw(np.pi / 4, 0.0, 0.0), [0.0, 0.0, 0.0])
    bar_a, bar_b = [2.0, 0.1, 0.1], [0.1, 2.0, 0.1]
    # Each bar reaches 0.1 * cos(45 deg) = 0.0707 m up or down from its axis.
    for z, overlap in ((0.13, True), (0.15, False)):
        X_B = RigidTransform(RollPitchYaw(0.0, np.pi / 4, 0.0), [0.0, 0.0, z])
        assert mut.boxes_overlap(bar_a, X_A, bar_b, X_B) is overlap
        assert (depth(bar_a, X_A, bar_b, X_B) >= 0) is overlap


def test_margin_grows_each_box_by_half_of_it():
    cube, X = [0.1, 0.1, 0.1], RigidTransform()
    X_B = RigidTransform([0.12, 0.0, 0.0])  # 2 cm apart
    assert not mut.boxes_overlap(cube, X, cube, X_B)
    assert not mut.boxes_overlap(cube, X, cube, X_B, margin=0.019)
    assert mut.boxes_overlap(cube, X, cube, X_B, margin=0.021)
    assert mut.boxes_overlap(cube, X, cube, X_B, margin=0.021) == mut.boxes_overlap(
        cube, X_B, cube, X, margin=0.021
    )


def random_box(rng):
    size = rng.uniform(0.02, 0.3, size=3)
    X = RigidTransform(RollPitchYaw(*rng.uniform(-np.pi, np.pi, size=3)), rng.uniform(-0.2, 0.2, 3))
    return size, X


def test_agrees_with_the_exact_answer_on_random_boxes():
    rng = np.random.default_rng(5)
    decided = {True: 0, False: 0}
    for _ in range(300):
        (size_a, X_A), (size_b, X_B) = random_box(rng), random_box(rng)
        margin = float(rng.choice([0.0, 0.03]))
        t = depth(size_a + margin, X_A, size_b + margin, X_B)
        if abs(t) < 1e-6:
            continue  # touching: either answer
        overlap = mut.boxes_overlap(size_a, X_A, size_b, X_B, margin)
        assert overlap == (t > 0), (size_a, X_A, size_b, X_B, margin, t)
        decided[overlap] += 1
    assert min(decided.values()) > 50  # both answers were tested


def test_top_down_grasps_of_a_small_box():
    X_WO = RigidTransform(RollPitchYaw(0.0, 0.0, 0.3), [0.5, -0.2, 0.04])
    grasps = mut.top_down_grasps(X_WO, [0.04, 0.05, 0.08], max_width=0.075)
    assert len(grasps) == 4
    R_WO = X_WO.rotation()
    for k, X_WG in enumerate(grasps):
        np.testing.assert_array_equal(X_WG.translation(), X_WO.translation())
        R = X_WG.rotation().matrix()
        np.testing.assert_allclose(R[:, 2], [0, 0, -1], atol=1e-12)  # pointing down
        assert np.linalg.det(R) == pytest.approx(1.0)
        # The fingers close along the object's y axis, then x, y, x, a quarter turn apart.
        closing = R_WO.col(1) if k % 2 == 0 else R_WO.col(0)
        assert abs(R[:, 1] @ closing) == pytest.approx(1.0)
    for a, b in zip(grasps, grasps[1:], strict=False):
        assert mut.rotation_distance(a.rotation(), b.rotation()) == pytest.approx(np.pi / 2)


def test_top_down_grasps_skip_sides_too_wide():
    X_WO = RigidTransform([0.5, 0.0, 0.05])
    narrow_y = mut.top_down_grasps(X_WO, [0.1, 0.04, 0.1], max_width=0.075)
    assert len(narrow_y) == 2
    for X_WG in narrow_y:
        np.testing.assert_allclose(np.abs(X_WG.rotation().col(1)), [0, 1, 0], atol=1e-12)
    assert mut.top_down_grasps(X_WO, [0.1, 0.1, 0.02], max_width=0.075) == []
    assert len(mut.top_down_grasps(X_WO, [0.075, 0.075, 0.1], max_width=0.075)) == 4  # at most


def test_rotation_distance():
    R = RotationMatrix(RollPitchYaw(0.1, -0.2, 0.3))
    assert mut.rotation_distance(R, R) == pytest.approx(0.0, abs=1e-7)
    turned = R @ RotationMatrix.MakeZRotation(0.4)
    assert mut.rotation_distance(R, turned) == pytest.approx(0.4)
    assert mut.rotation_distance(turned, R) == pytest.approx(0.4)
    flipped = RotationMatrix.MakeXRotation(np.pi)
    assert mut.rotation_distance(RotationMatrix(), flipped) == pytest.approx(np.pi)
    assert isinstance(mut.rotation_distance(R, turned), float)
