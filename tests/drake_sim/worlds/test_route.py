"""Routes and goals (drake_sim.worlds.route): loading, checks, and that the shipped routes are
safe to drive and let a lidar see the whole arena, and the shipped goals are reachable."""

import math

import numpy as np
import pytest
from scipy import ndimage

import drake_sim.worlds.route as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from drake_sim.worlds.arena import (
    arena_footprints,
    arena_grid,
    load_arena,
    shipped_arenas,
)
from drake_sim.worlds.footprints import cast_rays, clearance, occupied_boundary

SCAN_HEIGHT = 0.17  # m, the lidar's scan plane above the floor
LIDAR_RANGE = 3.5  # m, the TurtleBot3 LDS's
BEAMS = 360
ROUTE_LENGTHS = {"room": (20.0, 30.0), "maze": (30.0, 40.0), "warehouse": (45.0, 60.0)}

ARENA = """
size: [6.0, 5.0]
wall: {height: 0.3, thickness: 0.05}
obstacles:
  - {box: {size: [0.4, 0.4, 0.3], position: [1.0, 0.5], yaw: 30}}
  - {cylinder: {radius: 0.15, height: 0.3, position: [-1.2, 0.8]}}
  - {wall: {from: [0.0, -2.5], to: [0.0, 0.5]}}
start: {x: -2.0, y: -1.5, yaw: 0}
"""


@pytest.fixture
def arena(tmp_path):
    path = tmp_path / "arena.yaml"
    path.write_text(ARENA)
    return load_arena(path)


def _write(tmp_path, text, name="route.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_a_route_loads_and_measures(tmp_path, arena):
    route = mut.load_route(_write(tmp_path, "waypoints: [[-2.0, 1.5], [1.0, 1.5]]\n"), arena)
    assert route.waypoints == [[-2.0, 1.5], [1.0, 1.5]]
    np.testing.assert_array_equal(route.path((-2.0, -1.5)), [[-2, -1.5], [-2, 1.5], [1, 1.5]])
    assert route.length((-2.0, -1.5)) == pytest.approx(6.0)
    samples = route.sample((-2.0, -1.5), 0.25)
    assert len(samples) == 1 + 12 + 12
    assert np.all(np.linalg.norm(np.diff(samples, axis=0), axis=1) <= 0.25 + 1e-12)
    np.testing.assert_allclose(samples[[0, 12, -1]], [[-2, -1.5], [-2, 1.5], [1, 1.5]])
    # The nearest thing to it: the cylinder at (-1.2, 0.8), r 0.15, from the point (-1.2, 1.5).
    assert mut.route_clearance(route, arena) == pytest.approx(0.55, abs=1e-9)
    assert mut.load_route(_write(tmp_path, "waypoints: [[9, 9]]\n")).waypoints == [[9, 9]]


@pytest.mark.parametrize(
    "text, match",
    [
        ("waypoints: []\n", "'waypoints' is empty"),
        ("", "'waypoints' is empty"),
        ("waypoints: [[1.0, .nan]]\n", r"'waypoints\[0\]\[1\]' must be finite"),
        ("waypoints: [[-2, 1], [1.0, .inf]]\n", r"'waypoints\[1\]\[1\]' must be finite"),
        ("waypoints: [[1.0, 2.0, 3.0]]\n", r"'waypoints\[0\]' must be \[x, y\]"),
        ("waypoints: [[-2, 1], [4.0, 0.0]]\n", r"'waypoints\[1\]': \(4, 0\) lies outside the"),
        ("waypoints: [[-2, 1], [1.0, 0.5]]\n", r"'waypoints\[1\]'.* is inside 'obstacle_0'"),
        ("waypoints: [[-1.2, 1.1]]\n", r"'waypoints\[0\]'.* 0.150 m from 'obstacle_1'"),
        ("waypoints: [[-2, 0.2], [1.0, -1.5]]\n",
         r"'waypoints\[1\]': the segment from waypoints\[0\] passes 0.000 m from 'obstacle_2'"),
        ("waypoints: [[-2, 1.5], [2.0, 1.5], [2.0, 2.4]]\n", r"'waypoints\[2\]'.*'wall_north'"),
        ("waypoints: [[1.2, -1.5]]\n", r"'waypoints\[0\]': the segment from the start passes"),
        ("waypoint: [[0, 0]]\n", "unknown key 'waypoint'"),
        ("waypoints: [[0, 0]\n", "malformed YAML"),
        ("waypoints: 3\n", "'waypoints' must be a list"),
    ],
)  # fmt: skip
def test_bad_routes_name_the_file_and_waypoint(tmp_path, arena, text, match):
    with pytest.raises(ConfigError, match=match) as error:
        mut.load_route(_write(tmp_path, text), arena)
    assert "route.yaml" in str(error.value) and "\n" not in str(error.value)


def _seen(arena, route, resolution=0.05, spacing=0.25):
    """Casts a 360-beam scan every ``spacing`` m along the route; returns the grid and the
    masks of cells a beam ended in (grown by one cell) and cells beams passed through."""
    grid = arena_grid(arena, resolution, height=SCAN_HEIGHT)
    footprints = arena_footprints(arena, height=SCAN_HEIGHT)
    poses = route.sample(arena.start_pose()[:2], spacing)
    angles = -math.pi + np.arange(BEAMS) * 2 * math.pi / BEAMS
    u = np.stack([np.cos(angles), np.sin(angles)], axis=-1)
    ranges = cast_rays(footprints, poses, angles, LIDAR_RANGE)
    hit = np.zeros(grid.shape, dtype=bool)
    passed = np.zeros(grid.shape, dtype=bool)
    steps = np.arange(0.0, LIDAR_RANGE, resolution / 2)
    for p_WO, r in zip(poses, ranges, strict=True):
        ends = np.isfinite(r)
        hit[grid.cell_of(p_WO + r[ends, None] * u[ends])] = True
        reach = np.where(ends, r - 1e-6, LIDAR_RANGE)
        along = steps[None, :] < reach[:, None]
        points = p_WO + steps[None, :, None] * u[:, None, :]
        passed[grid.cell_of(points[along])] = True
    return grid, ndimage.binary_dilation(hit, np.ones((3, 3), bool)), passed


@pytest.mark.parametrize("path", shipped_arenas(), ids=lambda p: p.stem)
def test_each_shipped_route_is_safe_and_shows_the_lidar_the_whole_arena(path):
    arena = load_arena(path)
    route = mut.load_route(mut.default_route_file(path), arena)
    start = arena.start_pose()[:2]
    low, high = ROUTE_LENGTHS[path.stem]
    assert low <= route.length(start) <= high
    assert mut.route_clearance(route, arena) >= 0.3
    footprints = arena_footprints(arena)
    assert clearance(footprints, np.array(start)) >= 0.5
    assert clearance(footprints, np.array(route.waypoints[-1])) >= 0.5
    grid, near_hits, passed = _seen(arena, route)
    boundary = occupied_boundary(grid.cells)
    free = grid.cells == 0
    assert np.sum(near_hits & boundary) / np.sum(boundary) >= 0.97
    assert np.sum(passed & free) / np.sum(free) >= 0.97


def test_the_coverage_check_fails_for_a_route_that_stays_in_a_corner():
    path = config_dir() / "arenas" / "maze.yaml"
    arena = load_arena(path)
    first = mut.load_route(mut.default_route_file(path), arena).waypoints[0]
    grid, near_hits, passed = _seen(arena, mut.Route(waypoints=[first]))
    boundary = occupied_boundary(grid.cells)
    assert np.sum(near_hits & boundary) / np.sum(boundary) < 0.7
    assert np.sum(passed & (grid.cells == 0)) / np.sum(grid.cells == 0) < 0.5


@pytest.mark.parametrize("path", shipped_arenas(), ids=lambda p: p.stem)
def test_each_shipped_goals_file_is_reachable_with_room_to_spare(path):
    arena = load_arena(path)
    goals = mut.load_goals(mut.default_goals_file(path), arena)
    assert 3 <= len(goals) <= 4
    footprints = arena_footprints(arena)
    # Where the centre of a robot 0.3 m wide can be: free cells at least 0.15 m from anything.
    grid = arena_grid(arena, 0.025)
    room = ndimage.distance_transform_edt(grid.cells == 0) * grid.resolution >= 0.15 + 0.025
    regions, _ = ndimage.label(room)
    start_region = regions[grid.cell_of(np.array(arena.start_pose()[:2]))]
    assert start_region > 0
    for goal in goals:
        assert clearance(footprints, np.array([goal.x, goal.y])) >= 0.35, goal
        assert regions[grid.cell_of(np.array([goal.x, goal.y]))] == start_region, goal
        assert math.isfinite(goal.yaw)


def test_goals_load_and_convert_yaw(tmp_path, arena):
    goals = mut.load_goals(_write(tmp_path, "goals: [{x: 1, y: -1, yaw: 90}, {x: -2, y: 1}]\n"))
    assert goals == [mut.Goal(1.0, -1.0, 90.0), mut.Goal(-2.0, 1.0, 0.0)]
    assert goals[0].pose() == pytest.approx((1.0, -1.0, math.pi / 2))


@pytest.mark.parametrize(
    "text, match",
    [
        ("goals: []\n", "'goals' is empty"),
        ("goals: [{y: 1}]\n", r"missing key 'goals\[0\].x'"),
        ("goals: [{x: 1, y: -1}, {x: 1}]\n", r"missing key 'goals\[1\].y'"),
        ("goals: [{x: 1, y: -1, yaw: .nan}]\n", r"'goals\[0\].yaw' must be finite"),
        ("goals: [{x: 1, y: -1, z: 0}]\n", r"unknown key 'goals\[0\].z'"),
        ("goals: [{x: 1.0, y: 0.5}]\n", r"'goals\[0\]'.* is inside 'obstacle_0'"),
        ("goals: [{x: 1, y: -1}, {x: 3.5, y: 0}]\n", r"'goals\[1\]': \(3.5, 0\) lies outside"),
        ("goals: [{x: 2.9, y: 0}]\n", r"'goals\[0\]'.* 0.100 m from 'wall_east'"),
    ],
)
def test_bad_goals_name_the_file_and_goal(tmp_path, arena, text, match):
    with pytest.raises(ConfigError, match=match) as error:
        mut.load_goals(_write(tmp_path, text, "goals.yaml"), arena)
    assert "goals.yaml" in str(error.value) and "\n" not in str(error.value)


def test_default_files_sit_beside_the_config_and_exist_for_shipped_arenas(tmp_path):
    for path in shipped_arenas():
        assert mut.default_route_file(path) == config_dir() / "routes" / path.name
        assert mut.default_goals_file(path) == config_dir() / "goals" / path.name
        assert mut.default_route_file(path).is_file() and mut.default_goals_file(path).is_file()
    assert not mut.default_route_file(tmp_path / "elsewhere.yaml").exists()
    assert mut.default_goals_file("elsewhere.yaml") == config_dir() / "goals" / "elsewhere.yaml"


def test_random_goals_keep_their_margin_and_spacing_and_repeat_per_seed():
    arena = load_arena(config_dir() / "arenas" / "maze.yaml")
    goals = mut.random_goals(arena, 12, seed=4, margin=0.4, spacing=1.0)
    assert len(goals) == 12
    xy = np.array([g[:2] for g in goals])
    assert (clearance(arena_footprints(arena), xy) >= 0.4).all()
    previous = np.vstack([arena.start_pose()[:2], xy[:-1]])
    assert (np.hypot(*(xy - previous).T) >= 1.0).all()
    assert all(-np.pi <= g[2] <= np.pi for g in goals)
    again = mut.random_goals(arena, 12, seed=4, margin=0.4, spacing=1.0)
    assert np.array_equal(np.array(goals), np.array(again))
    with pytest.raises(ValueError, match="margin"):
        mut.random_goals(arena, 2, seed=0, margin=5.0)
