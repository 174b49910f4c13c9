"""drake_sim.systems.estimation.correlative_search: branch and bound returns the exhaustive
search's best pose, and finds a room's scan where it was taken."""

import math

import numpy as np
import pytest

import drake_sim.systems.estimation.correlative_search as mut
from drake_sim.base.planar import relative_pose
from drake_sim.systems.estimation.scan_matcher import transform_points


def room_outline(step=0.02):
    """Points on the walls of an 8 m x 6 m room with a 2 m wall stub inside."""
    t = np.arange(0.0, 1.0, step / 8.0)
    walls = [
        np.stack([8 * t, 0 * t], 1),
        np.stack([8 * t, 0 * t + 6], 1),
        np.stack([0 * t, 6 * t], 1),
        np.stack([0 * t + 8, 6 * t], 1),
        np.stack([3 + 0 * t, 2 + 2 * t], 1)[t < 1.0],
    ]
    return np.concatenate(walls)


def brute_force(table, points, center, window_xy, window_yaw, yaw_step):
    steps = math.floor(window_xy / table.resolution)
    n = math.floor(window_yaw / yaw_step)
    best = (-1.0, None)
    for k in range(-n, n + 1):
        cells = mut._cells(
            *table.origin, table.resolution, points, center[0], center[1], center[2] + k * yaw_step
        )
        for dx in range(-steps, steps + 1):
            for dy in range(-steps, steps + 1):
                value = mut._score(table.fine, cells, dx, dy)
                if value > best[0]:
                    best = (value, (k, dx, dy))
    return best


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_branch_and_bound_scores_as_the_exhaustive_search(seed):
    rng = np.random.default_rng(seed)
    table = mut.make_table(rng.uniform(0, 4, (60, 2)), 0.05, sigma=0.1, margin=1.0, block=4)
    points = rng.uniform(-1.5, 1.5, (40, 2))
    center = np.array([2.0, 2.0, 0.3])
    window = (0.4, math.radians(4), math.radians(1))
    found = mut.search(
        table, points, center, window_xy=window[0], window_yaw=window[1], yaw_step=window[2]
    )
    best, _ = brute_force(table, points, center, *window)
    assert found.score == pytest.approx(best, abs=1e-12)
    # the pose returned scores what was said
    offset = np.round((found.pose[:2] - center[:2]) / table.resolution).astype(int)
    cells = mut._cells(*table.origin, table.resolution, points, center[0], center[1], found.pose[2])
    assert mut._score(table.fine, cells, *offset) == pytest.approx(found.score, abs=1e-12)


def test_a_scan_is_found_where_it_was_taken_from_half_a_metre_away():
    walls = room_outline()
    table = mut.make_table(walls, 0.05, sigma=0.08, margin=1.5)
    truth = np.array([4.0, 3.0, 0.3])
    scan = transform_points(relative_pose(truth, np.zeros(3)), walls[::4])  # base frame
    start = truth + [0.45, -0.35, math.radians(6.0)]
    found = mut.search(
        table, scan, start, window_xy=1.0, window_yaw=math.radians(10), yaw_step=math.radians(0.5)
    )
    error = relative_pose(truth, found.pose)
    assert np.hypot(*error[:2]) < 0.06 and abs(error[2]) < math.radians(0.5)
    assert found.score > 0.9


def test_the_coarse_table_bounds_every_block_of_the_fine_one():
    rng = np.random.default_rng(3)
    table = mut.make_table(rng.uniform(0, 3, (30, 2)), 0.05, sigma=0.1, margin=0.5, block=8)
    rows, cols = table.fine.shape
    for i, j in rng.integers(0, [rows, cols], (200, 2)):
        assert table.coarse[i, j] >= table.fine[i : i + 8, j : j + 8].max()


def test_no_points_leave_the_pose_where_it_was_and_no_hits_make_no_table():
    table = mut.make_table(np.zeros((1, 2)), 0.05, sigma=0.1, margin=0.5)
    found = mut.search(
        table, np.zeros((0, 2)), [1.0, 2.0, 0.5], window_xy=0.5, window_yaw=0.1, yaw_step=0.05
    )
    np.testing.assert_array_equal(found.pose, [1.0, 2.0, 0.5])
    assert found.score == 0.0
    with pytest.raises(ValueError, match="at least one point"):
        mut.make_table(np.zeros((0, 2)), 0.05, sigma=0.1, margin=0.5)


def test_occupied_points_are_the_centres_of_positive_cells_in_the_box():
    log_odds = np.zeros((4, 5), np.float32)
    log_odds[1, 2] = 2.0  # row 1 (y), column 2 (x)
    log_odds[3, 4] = 0.5
    log_odds[0, 0] = -1.0  # free
    points = mut.occupied_points(log_odds, 0.5, (10.0, 20.0), (10.0, 20.0), (12.5, 22.0))
    np.testing.assert_allclose(points, [[11.25, 20.75], [12.25, 21.75]])
    inside = mut.occupied_points(log_odds, 0.5, (10.0, 20.0), (10.9, 20.4), (11.6, 21.1))
    np.testing.assert_allclose(inside, [[11.25, 20.75]])
    assert mut.occupied_points(log_odds, 0.5, (10.0, 20.0), (0.0, 0.0), (5.0, 5.0)).shape == (0, 2)


def test_a_pose_along_a_corridor_is_ambiguous_and_one_in_a_room_is_not():
    resolution = 0.05
    room = room_outline()
    pose = np.array([4.0, 3.0, 0.3])
    t = np.arange(-10.0, 10.0, 0.02)
    corridor = np.concatenate([np.stack([t, 0 * t - 0.6], 1), np.stack([t, 0 * t + 0.6], 1)])
    for walls, expected in [(room, False), (corridor, True)]:
        table = mut.make_table(walls, resolution, sigma=1.5 * resolution, margin=1.5)
        at = pose if walls is room else np.array([0.0, 0.0, 1.2])
        scan = transform_points(relative_pose(at, np.zeros(3)), walls[::4])
        scan = scan[np.hypot(*scan.T) < 4.0]  # what a short-range lidar sees
        found = mut.search(
            table, scan, at, window_xy=0.1, window_yaw=math.radians(2), yaw_step=math.radians(0.5)
        )
        result = mut.ambiguous(
            table, scan, found.pose, found.score, distance=0.3, max_ratio=0.9,
            yaw_step=math.radians(0.5),
        )  # fmt: skip
        assert result is expected, walls is room
