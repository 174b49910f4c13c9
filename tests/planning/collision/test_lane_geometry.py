"""``lane_geometry``: each lane's point, gate and distance equal the scalar kernel's
(``sphere_kernel._point``, ``_distance2``) for that lane's values, to the last bit."""

import numpy as np
import pytest

from planning.collision import lane_geometry as mut
from planning.collision import sphere_kernel

LANES = 5


def _transforms(rng, steps: int) -> np.ndarray:
    """Random X_WC (steps, 3, 4) for each lane: (lanes, steps, 3, 4)."""
    return rng.normal(size=(LANES, steps, 3, 4))


def _by_lane(T: np.ndarray) -> np.ndarray:
    """The batch layout of transforms: (steps, 12, lanes), 3x4 row-major."""
    return np.ascontiguousarray(T.reshape(LANES, T.shape[1], 12).transpose(1, 2, 0))


def test_points_are_the_scalar_points_of_each_lane():
    rng = np.random.default_rng(0)
    T = _transforms(rng, 3)
    p_B = rng.normal(size=(4, 3))
    out = np.zeros((4, 3, LANES))
    mut.points(_by_lane(T), 2, p_B, 1, out, 3, LANES)
    for lane in range(LANES):
        expected = np.zeros((4, 3))
        sphere_kernel._point(T[lane], 2, p_B, 1, expected, 3)
        np.testing.assert_array_equal(out[3, :, lane], expected[3])


def test_centre_once_computes_a_centre_once_per_batch():
    rng = np.random.default_rng(1)
    T = _by_lane(_transforms(rng, 2))
    p_B = rng.normal(size=(2, 3))
    steps = np.array([0, 1])
    seen = np.zeros(2, dtype=np.int64)
    out = np.zeros((2, 3, LANES))
    mut.centre_once(T, steps, p_B, 1, out, seen, 7, LANES)
    expected = np.zeros((2, 3, LANES))
    mut.points(T, 1, p_B, 1, expected, 1, LANES)
    np.testing.assert_array_equal(out[1], expected[1])
    assert seen.tolist() == [0, 7]
    out[1] = -1.0  # seen in this batch: left alone
    mut.centre_once(T, steps, p_B, 1, out, seen, 7, LANES)
    assert np.all(out[1] == -1.0)
    mut.centre_once(T, steps, p_B, 1, out, seen, 8, LANES)  # a new batch computes it again
    np.testing.assert_array_equal(out[1], expected[1])


def test_within_gates_the_lanes_nearer_than_the_reach():
    p = np.zeros((3, 4))
    r = np.zeros((3, 4))
    r[0] = [0.5, 1.5, 0.5, 0.5]
    gate = np.array([1.0, 1.0, 0.0, 1.0])
    out = np.full(4, -1.0)
    assert mut.within(p, r, 1.0, gate, out, 4)
    np.testing.assert_array_equal(out, [1.0, 0.0, 0.0, 1.0])
    assert not mut.within(p, r, 0.1, gate, out, 4)
    np.testing.assert_array_equal(out, 0.0)


def _object_row(kind: int, rng) -> np.ndarray:
    """A kernel object row (``sphere_kernel.OBJ_*``) of a kind, randomly posed."""
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    p = rng.normal(size=3) * 0.3
    row = np.zeros(sphere_kernel.OBJ_COLUMNS)
    row[sphere_kernel.OBJ_KIND] = kind
    row[sphere_kernel.OBJ_W : sphere_kernel.OBJ_W + 9] = R.T.ravel()
    row[sphere_kernel.OBJ_OFFSET : sphere_kernel.OBJ_OFFSET + 3] = R.T @ p
    row[sphere_kernel.OBJ_SIZE : sphere_kernel.OBJ_SIZE + 3] = [0.2, 0.1, 0.15]
    return row


@pytest.mark.parametrize("kind", [0, 1, 2], ids=["box", "cylinder", "sphere"])
def test_min_distance2_is_the_scalar_distance_of_each_lane(kind):
    rng = np.random.default_rng(kind)
    obj = _object_row(kind, rng)
    p = rng.normal(size=(3, LANES)) * 0.4
    best = np.full(LANES, np.inf)
    best[0] = 0.0  # a smaller value stays
    mut.min_distance2(p, obj, best, LANES)
    assert best[0] == 0.0
    for lane in range(1, LANES):
        assert best[lane] == sphere_kernel._distance2(*p[:, lane], obj)
