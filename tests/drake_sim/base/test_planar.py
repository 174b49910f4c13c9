"""drake_sim.base.planar: one wrap convention, compose and relative_pose inverse of each other."""

import math

import numpy as np
import pytest

import drake_sim.base.planar as mut


def _poses(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform(-1, 1, (n, 3)) * [5.0, 5.0, 4 * math.pi]


def test_wrap_range_and_period():
    angles = np.linspace(-20.0, 20.0, 4001)
    wrapped = mut.wrap_angle(angles)
    assert np.all(wrapped >= -math.pi) and np.all(wrapped < math.pi)
    # Wrapping moves by whole turns only.
    turns = (angles - wrapped) / (2 * math.pi)
    np.testing.assert_allclose(turns, np.round(turns), atol=1e-9)


def test_wrap_ends_of_the_range():
    assert mut.wrap_angle(math.pi) == -math.pi  # [-pi, pi): +pi maps to -pi
    assert mut.wrap_angle(-math.pi) == -math.pi
    assert mut.wrap_angle(0.0) == 0.0
    assert mut.wrap_angle(3 * math.pi) == -math.pi


def test_wrap_scalars_and_arrays_agree():
    angles = np.linspace(-10.0, 10.0, 101)
    wrapped = mut.wrap_angle(angles)
    assert isinstance(wrapped, np.ndarray) and wrapped.shape == angles.shape
    for angle, expected in zip(angles, wrapped, strict=True):
        value = mut.wrap_angle(float(angle))
        assert type(value) is float and value == expected  # bit for bit
    assert isinstance(mut.wrap_angle(1), float)
    from_list = mut.wrap_angle([4.0, -4.0])
    assert from_list.shape == (2,)
    np.testing.assert_array_equal(from_list, mut.wrap_angle(np.array([4.0, -4.0])))


def test_compose_translates_then_turns():
    pose = mut.compose((1.0, 2.0, math.pi / 2), (1.0, 0.0, math.pi / 2))
    np.testing.assert_allclose(pose, (1.0, 3.0, -math.pi), atol=1e-12)  # yaw pi wraps to -pi
    np.testing.assert_allclose(mut.compose((1.0, 2.0, 0.3), (0, 0, 0)), (1.0, 2.0, 0.3), atol=1e-15)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_relative_pose_inverts_compose(seed):
    a, b = _poses(200, seed), _poses(200, seed + 10)
    for pa, pb in zip(a, b, strict=True):
        back = mut.compose(pa, mut.relative_pose(pa, pb))
        np.testing.assert_allclose(back[:2], pb[:2], atol=1e-12)
        assert abs(mut.wrap_angle(back[2] - pb[2])) < 1e-12
        again = mut.relative_pose(pa, mut.compose(pa, pb))
        np.testing.assert_allclose(again[:2], pb[:2], atol=1e-12)
        assert abs(mut.wrap_angle(again[2] - pb[2])) < 1e-12


def test_relative_pose_of_itself_is_identity():
    for pose in _poses(50):
        np.testing.assert_allclose(mut.relative_pose(pose, pose), 0.0, atol=1e-15)


def test_compose_is_associative():
    a, b, c = _poses(3, 7)
    left = mut.compose(mut.compose(a, b), c)
    right = mut.compose(a, mut.compose(b, c))
    np.testing.assert_allclose(left[:2], right[:2], atol=1e-12)
    assert abs(mut.wrap_angle(left[2] - right[2])) < 1e-12


def test_arrays_of_poses_equal_pose_by_pose():
    a, b = _poses(40, 3), _poses(40, 4)
    # One frame, many poses (the particle filter's use), bit for bit equal to one at a time.
    many = mut.compose(a[0], b)
    relative = mut.relative_pose(a[0], b)
    assert many.shape == relative.shape == (40, 3)
    for i in range(40):
        np.testing.assert_array_equal(many[i], mut.compose(a[0], b[i]))
        np.testing.assert_array_equal(relative[i], mut.relative_pose(a[0], b[i]))
    # Many frames, many poses, row by row.
    rows = mut.compose(a, b)
    for i in range(40):
        np.testing.assert_allclose(rows[i], mut.compose(a[i], b[i]), atol=1e-12)
    assert np.all(rows[:, 2] >= -math.pi) and np.all(rows[:, 2] < math.pi)


def test_wrap_exact_is_remainder_in_the_same_range():
    rng = np.random.default_rng(1)
    angles = np.concatenate([rng.uniform(-4, 4, 2000), rng.uniform(-100, 100, 2000)])
    exact = mut.wrap_angle_exact(angles)
    assert np.all(exact >= -math.pi) and np.all(exact < math.pi)
    for angle, value in zip(angles, exact, strict=True):
        assert value == math.remainder(angle, 2 * math.pi)  # no tie among these
        assert mut.wrap_angle_exact(float(angle)) == value
    # Angles in range come back unchanged (wrap_angle rounds them by up to half an ulp of pi).
    inside = rng.uniform(-math.pi, math.pi, 1000)
    np.testing.assert_array_equal(mut.wrap_angle_exact(inside), inside)
    np.testing.assert_allclose(mut.wrap_angle(inside), inside, rtol=0, atol=1e-15)
    # The ends: pi maps to -pi, as with wrap_angle.
    assert mut.wrap_angle_exact(math.pi) == mut.wrap_angle_exact(-math.pi) == -math.pi
    assert mut.wrap_angle_exact(3 * math.pi) == -math.pi
    assert isinstance(mut.wrap_angle_exact(1), float)


def test_same_pose_within_a_distance_and_an_angle():
    a = np.array([1.0, 2.0, math.pi - 0.001])
    assert mut.same_pose(a, a + [0.01, -0.01, 0.0])
    assert mut.same_pose(a, [1.0, 2.0, -math.pi + 0.005])  # across the wrap
    assert not mut.same_pose(a, a + [0.03, 0.0, 0.0])
    assert not mut.same_pose(a, a - [0.0, 0.0, 0.02])
    assert mut.same_pose(a, a + [0.1, 0.0, 0.0], distance=0.2)
