"""Worlds from map_server maps: occupied cells merged into boxes, the start checked, and a map
checked against an arena."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import drake_sim.worlds.map_world as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from drake_sim.base.resources import cache_dir, config_dir
from drake_sim.worlds.arena import arena_footprints, arena_grid, load_arena


def coverage(rectangles, shape) -> np.ndarray:
    count = np.zeros(shape, dtype=int)
    for row, col, rows, cols in rectangles:
        count[row : row + rows, col : col + cols] += 1
    return count


@settings(max_examples=60, deadline=None)
@given(hnp.arrays(bool, st.tuples(st.integers(1, 12), st.integers(1, 12))))
def test_rectangles_cover_every_occupied_cell_once_and_nothing_else(occupied):
    rectangles = mut.occupied_rectangles(occupied)
    assert np.array_equal(coverage(rectangles, occupied.shape), occupied.astype(int))


def test_a_wall_is_one_box_and_an_l_two():
    grid = np.zeros((6, 5), dtype=bool)
    grid[:, 2] = True  # a wall along a column
    assert mut.occupied_rectangles(grid).tolist() == [[0, 2, 6, 1]]
    grid[5, :] = True  # and a row under it: an L
    assert len(mut.occupied_rectangles(grid)) == 2


def small_map(yaw: float = 0.0) -> OccupancyMap:
    """2 x 1.5 m at 0.1 m: a wall along the left edge, a post, an unknown corner."""
    cells = np.full((15, 20), FREE, dtype=np.int8)
    cells[:, 0] = OCCUPIED
    cells[6:8, 10:12] = OCCUPIED
    cells[13:, 17:] = UNKNOWN
    return OccupancyMap(cells, 0.1, (1.0, -0.5, yaw))


def test_the_arena_of_a_map_has_its_walls_where_its_cells_are():
    grid = small_map()
    arena = mut.map_arena(grid, (1.5, 0.0, 0.3))
    boxes = [o.box for o in arena.obstacles]
    assert len(boxes) == 2 and all(b.size[2] == mut.WALL_HEIGHT for b in boxes)
    post = next(b for b in boxes if b.size[:2] == pytest.approx([0.2, 0.2]))
    assert post.position == pytest.approx([1.0 + 1.1, -0.5 + 0.7])
    assert arena.start_pose() == pytest.approx((1.5, 0.0, 0.3))
    # The arena's walls hold the whole map.
    assert arena.size[0] / 2 >= 3.0 and arena.size[1] / 2 >= 1.0
    # The boxes hold exactly the occupied cells' centres.
    centres = grid.to_world(np.stack(np.meshgrid(np.arange(20) + 0.5, np.arange(15) + 0.5), -1))
    boxes = arena_footprints(arena)[4:]  # after the four outer walls
    inside = np.zeros(grid.cells.shape, dtype=bool)
    for footprint in boxes:
        inside |= footprint.signed_distance(centres) < 0
    assert np.array_equal(inside, grid.cells == OCCUPIED)


def test_a_turned_map_turns_its_boxes_about_its_origin():
    arena = mut.map_arena(small_map(yaw=math.pi / 2), (0.5, 1.0, 0.0))
    post = next(o.box for o in arena.obstacles if o.box.size[:2] == pytest.approx([0.2, 0.2]))
    assert post.position == pytest.approx([1.0 - 0.7, -0.5 + 1.1])
    assert post.yaw == pytest.approx(90.0)


@pytest.mark.parametrize(
    "start, needle",
    [
        ((9.0, 0.0, 0.0), "outside the map"),
        ((1.05, 0.0, 0.0), "not on a free cell"),
        ((2.85, 0.85, 0.0), "not on a free cell"),  # the unknown corner
        ((1.2, 0.0, 0.0), "the robot needs"),  # free, but next to the wall
        ((math.nan, 0.0, 0.0), "not finite"),
    ],
)
def test_a_start_off_the_free_cells_is_refused(start, needle):
    with pytest.raises(ConfigError, match=needle):
        mut.map_arena(small_map(), start, where="small.yaml")


def test_rectangles_are_cached_by_content():
    grid = small_map()
    first = mut.cached_rectangles(grid)
    files = list((cache_dir() / "map_worlds").glob("*.npy"))
    assert any(np.array_equal(np.load(f), first) for f in files)
    assert np.array_equal(mut.cached_rectangles(grid), first)


def arena_file(name: str):
    return config_dir() / "arenas" / f"{name}.yaml"


def test_a_map_agrees_with_its_own_arena_and_not_with_another():
    room = load_arena(arena_file("room"))
    truth = arena_grid(room, 0.05)
    start = room.start_pose()[:2]
    mut.check_map_agrees(room, truth, [start], "room")
    maze = arena_grid(load_arena(arena_file("maze")), 0.05)
    with pytest.raises(ConfigError, match="room: the map and the arena do not agree"):
        mut.check_map_agrees(room, maze, [start], "room")
    with pytest.raises(ConfigError, match=r"goal 1 \(50, 0\) is outside the map"):
        mut.check_map_agrees(room, truth, [start, (50.0, 0.0)], "room")
    wall = truth.to_world(np.array([[0.5, 0.5]]) + np.argwhere(truth.cells == OCCUPIED)[0, ::-1])
    mut.check_map_agrees(room, truth, [start, wall[0]], "room")  # a goal on a wall: unreachable
    with pytest.raises(ConfigError, match=r"the start .* is on a wall of the map"):
        mut.check_map_agrees(room, truth, [wall[0]], "room")
    assert len(arena_footprints(room)) > 4
