"""Frontiers on a map: which cells, which frontier is chosen, reachability, blacklist."""

import numpy as np
import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from drake_sim.navigation.frontiers import (
    FrontierConfig,
    check_frontier_config,
    find_frontiers,
    frontier_mask,
)

RES = 0.05


def _room(rows=60, cols=100):
    """A walled room 2.5 m x 2 m (cells 10..59 x 10..49) seen whole, in a sea of unknown."""
    cells = np.full((rows, cols), UNKNOWN, np.int8)
    cells[10:50, 10:60] = FREE
    cells[10:50, [10, 59]] = OCCUPIED
    cells[[10, 49], 10:60] = OCCUPIED
    return cells


def test_a_closed_room_seen_whole_has_no_frontier():
    grid = OccupancyMap(_room(), RES)
    assert not frontier_mask(grid).any()
    assert find_frontiers(grid, [1.0, 1.5], FrontierConfig()) == []


def test_a_doorway_is_a_frontier_and_its_goal_is_reachable_and_inside():
    cells = _room()
    cells[22:38, 59] = FREE  # a 0.8 m doorway in the east wall, unknown beyond
    grid = OccupancyMap(cells, RES)
    (door,) = find_frontiers(grid, [1.0, 1.5], FrontierConfig())
    # The doorway's cells, but for those beside the wall's ends (their unknown neighbours touch
    # the wall: no frontier, as the inside of an obstacle is none).
    assert door.size_m == pytest.approx(14 * RES)
    assert np.allclose(door.cells[:, 0], 59.5 * RES)
    # The goal sees the doorway from within `approach`, on known free cells clear of walls.
    assert np.min(np.hypot(*(door.cells - door.goal).T)) <= 0.6
    assert door.goal[0] < 59.5 * RES and 1.1 < door.goal[1] < 1.9
    assert door.distance_m == pytest.approx(np.hypot(*(door.goal - [1.0, 1.5])), rel=0.1)


def test_the_inside_of_an_obstacle_is_no_frontier():
    cells = _room()
    # A diamond whose outline steps diagonally: free cells touch its unseen inside.
    rows, cols = np.mgrid[0:60, 0:100]
    ring = np.abs(rows - 30) + np.abs(cols - 35)
    cells[ring == 6] = OCCUPIED
    cells[ring < 6] = UNKNOWN
    grid = OccupancyMap(cells, RES)
    touching = (ring == 7) & (cells == FREE)
    assert touching.sum() > 20  # free cells 4-beside the outline, some beside the inside
    assert not frontier_mask(grid).any()
    assert find_frontiers(grid, [1.0, 1.5], FrontierConfig()) == []


def test_the_cheaper_frontier_wins_and_unreachable_ones_are_dropped():
    cells = _room(cols=140)
    cells[22:38, 59] = FREE  # a doorway east, near the robot at x = 2.5
    cells[10, 12:22] = FREE  # a 0.5 m gap in the south wall, far west
    cells[12:48, 90:130] = FREE  # an open area beyond a wall the robot cannot cross
    cells[12:48, 89] = OCCUPIED
    grid = OccupancyMap(cells, RES)
    found = find_frontiers(grid, [2.5, 1.5], FrontierConfig(min_frontier_size=0.25))
    assert [f.cost for f in found] == sorted(f.cost for f in found)
    assert found[0].goal[0] > 2.0  # the doorway, nearer
    assert all(f.goal[0] < 89 * RES for f in found)  # nothing beyond the wall
    # A longer frontier is worth a longer drive: weighting the gain more can change the order.
    gains = find_frontiers(grid, [1.0, 1.5], FrontierConfig(gain_scale=0.0))
    assert gains[0].goal[0] < 2.0  # from the west the gap is the nearer


def test_short_frontiers_are_noise_and_the_blacklist_removes_one():
    cells = _room()
    cells[22:38, 59] = FREE
    grid = OccupancyMap(cells, RES)
    assert find_frontiers(grid, [1.0, 1.5], FrontierConfig(min_frontier_size=1.0)) == []
    (door,) = find_frontiers(grid, [1.0, 1.5], FrontierConfig())
    seen = door.seen_from_goal(FrontierConfig())
    assert 0 < len(seen) <= len(door.cells)
    assert np.all(np.hypot(*(seen - door.goal).T) <= 0.6 + 1e-9)
    # What the goal was to reveal is blacklisted: what is left of the doorway is too short.
    assert find_frontiers(grid, [1.0, 1.5], FrontierConfig(), blacklist=seen) == []
    assert find_frontiers(grid, [1.0, 1.5], FrontierConfig(), blacklist=[[0.0, 0.0]]) != []


def test_paths_start_from_an_open_cell_near_the_robot_only():
    cells = _room(cols=140)
    cells[22:38, 59] = FREE  # the doorway
    cells[12:48, 90:130] = FREE  # a room beyond a wall the robot is in
    grid = OccupancyMap(cells, RES)
    # Beyond the wall: its own edges are frontiers, the doorway is out of reach.
    beyond = find_frontiers(grid, [5.5, 1.5], FrontierConfig())
    assert beyond and all(f.goal[0] > 89 * RES for f in beyond)
    # Standing 0.1 m from the west wall (its own cell not open): paths start beside it.
    (door,) = find_frontiers(grid, [0.65, 1.5], FrontierConfig())
    assert door.distance_m > 1.5
    # Far from any open cell (the unknown outside): nothing is reachable.
    assert find_frontiers(grid, [0.05, 0.05], FrontierConfig()) == []


def test_no_open_cell_means_no_frontier():
    cells = _room()
    cells[22:38, 59] = FREE
    grid = OccupancyMap(cells, RES)
    # The room is narrower than twice the clearance: the robot has nowhere to drive.
    assert find_frontiers(grid, [1.0, 1.5], FrontierConfig(clearance=1.5)) == []


@pytest.mark.parametrize(
    ("key", "value"),
    [("replan_period", 0.0), ("clearance", -0.1), ("gain_scale", float("nan")), ("approach", 0)],
)
def test_bad_values_are_named(key, value):
    with pytest.raises(ConfigError, match=key):
        check_frontier_config(FrontierConfig(**{key: value}))
