"""Tests of the global planner on the shipped arenas' ground-truth maps and on small made-up
maps: collision-free, short paths; the failures and their messages; the goal tolerance, the
start next to a wall, unknown space, blocked paths and the config checks."""

import dataclasses as dc
import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

import drake_sim.navigation.global_planner as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap
from drake_sim.navigation.costmap import INSCRIBED, Costmap, CostmapConfig
from drake_sim.worlds.arena import arena_footprints, arena_grid, load_arena, shipped_arenas
from drake_sim.worlds.footprints import Footprint, cast_rays, clearance

RES = 0.05
ROBOT_RADIUS = CostmapConfig().robot_radius
SMALL = CostmapConfig(robot_radius=0.04, inflation_radius=0.04)


def dense(path: np.ndarray, step: float = 0.01) -> np.ndarray:
    """Points every ``step`` m or less along the polyline ``path``."""
    parts = [path[:1]]
    for a, b in zip(path[:-1], path[1:], strict=True):
        n = max(1, int(math.ceil(np.linalg.norm(b - a) / step)))
        parts.append(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
    return np.concatenate(parts)


def free_points(arena, rng, count: int, margin: float = 0.3) -> np.ndarray:
    footprints = arena_footprints(arena)
    half = 0.5 * np.asarray(arena.size)
    points = []
    while len(points) < count:
        p = rng.uniform(-half, half)
        if clearance(footprints, p) >= margin:
            points.append(p)
    return np.array(points)


def walled_map(size=(80, 80), walls=(), unknown=()) -> OccupancyMap:
    """A free square map (1 cell border of walls) plus wall and unknown rectangles given as
    (r0, r1, c0, c1) cell ranges; origin (0, 0)."""
    cells = np.zeros(size, dtype=np.int8)
    cells[[0, -1], :] = 100
    cells[:, [0, -1]] = 100
    for r0, r1, c0, c1 in walls:
        cells[r0:r1, c0:c1] = 100
    for r0, r1, c0, c1 in unknown:
        cells[r0:r1, c0:c1] = -1
    return OccupancyMap(cells, RES, (0.0, 0.0, 0.0))


@pytest.mark.parametrize("arena_file", shipped_arenas(), ids=lambda p: p.stem)
def test_paths_in_shipped_arenas_are_collision_free_and_short(arena_file):
    arena = load_arena(arena_file)
    grid = arena_grid(arena, RES)
    costmap = Costmap.from_map(grid)
    footprints = arena_footprints(arena)
    xs, ys = grid.centres()
    occupied = cKDTree(np.stack([xs[grid.occupied()], ys[grid.occupied()]], -1))
    rng = np.random.default_rng(7)
    points = free_points(arena, rng, 30)
    straight_free = 0
    for start, goal in zip(points[::2], points[1::2], strict=True):
        dut = mut.plan_path(costmap, start, goal)
        assert dut.success and dut.message == "", (start, goal, dut.message)
        path = dut.path
        assert np.allclose(path[0], start) and np.allclose(path[-1], goal)
        assert dut.length_m == pytest.approx(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
        # Every vertex (cell centres, the start and goal) is farther than the robot's radius
        # from every occupied cell; points between vertices lie in cells that are too.
        assert occupied.query(path)[0].min() > ROBOT_RADIUS
        samples = dense(path)
        assert np.all(costmap.cost_at(samples) < INSCRIBED)
        assert occupied.query(samples)[0].min() >= ROBOT_RADIUS - RES / math.sqrt(2)
        assert clearance(footprints, samples).min() >= ROBOT_RADIUS - RES
        straight = float(np.linalg.norm(goal - start))
        assert dut.length_m >= straight - 1e-9
        if np.all(costmap.cost_at(dense(np.array([start, goal]))) < INSCRIBED):
            straight_free += 1
            assert dut.length_m < 1.3 * straight
    assert straight_free >= 2


def test_astar_and_dijkstra_find_equally_cheap_paths():
    arena = load_arena(shipped_arenas()[-1])
    costmap = Costmap.from_map(arena_grid(arena, RES))
    start, goal = (-5.2, -3.8), (5.0, 3.5)
    astar = mut.plan_path(costmap, start, goal)
    dijkstra = mut.plan_path(costmap, start, goal, mut.GlobalPlannerConfig(use_astar=False))
    assert astar.success and dijkstra.success
    assert astar.cost == pytest.approx(dijkstra.cost, rel=1e-9)
    assert astar.expanded < dijkstra.expanded
    raw = mut.plan_path(costmap, start, goal, mut.GlobalPlannerConfig(simplify=False))
    assert raw.cost == astar.cost and len(raw.path) > 3 * len(astar.path)
    assert astar.length_m <= raw.length_m


def test_goal_in_a_closed_box_is_unreachable_without_searching_beyond_the_start_s_room():
    # A 4 m x 4 m map; a closed box of walls (1 m inside) in one corner.
    grid = walled_map(
        walls=[(40, 42, 40, 70), (68, 70, 40, 70), (40, 70, 40, 42), (40, 70, 68, 70)]
    )
    costmap = Costmap.from_map(grid)
    dut = mut.plan_path(costmap, (0.5, 0.5), (2.75, 2.75))
    assert not dut.success and dut.message == mut.UNREACHABLE == "unreachable"
    assert dut.path.shape == (0, 2) and dut.length_m == 0.0
    outside = np.sum(costmap.costs < INSCRIBED) - np.sum(costmap.costs[42:68, 42:68] < INSCRIBED)
    assert 0 < dut.expanded <= outside + 8 * 30  # the start's component (+ escape cells)


def test_goal_in_an_obstacle_uses_the_tolerance_or_fails():
    grid = walled_map(walls=[(30, 50, 30, 50)])  # a 1 m x 1 m block at (1.5..2.5)^2
    costmap = Costmap.from_map(grid)
    start = (0.5, 0.5)
    deep = mut.plan_path(costmap, start, (2.0, 2.0))
    assert not deep.success and deep.message == mut.GOAL_IN_OBSTACLE == "goal in an obstacle"
    # 0.15 m from the block's face: inscribed; the nearest passable cell is within 0.2 m.
    near = (1.35, 2.0)
    assert costmap.cost_at([near])[0] >= INSCRIBED
    dut = mut.plan_path(costmap, start, near)
    assert dut.success
    assert np.linalg.norm(dut.path[-1] - near) <= 0.2 and costmap.cost_at(dut.path[-1:])[0] < 253
    strict = mut.plan_path(costmap, start, near, mut.GlobalPlannerConfig(tolerance=0.0))
    assert strict.message == mut.GOAL_IN_OBSTACLE


def test_an_unreachable_goal_within_tolerance_of_a_reachable_cell_ends_there():
    # The goal cell sits in a closed pocket just behind a thin wall: unreachable, but free
    # cells on this side lie within the tolerance. A small robot, so one cell is clearance.
    grid = walled_map(walls=[(20, 60, 40, 41)])
    costmap = Costmap.from_map(grid, SMALL)
    goal = (2.075, 2.0)  # just beyond the wall (x 2.0..2.05)
    dut = mut.plan_path(costmap, (1.0, 1.0), goal, mut.GlobalPlannerConfig(tolerance=0.0))
    assert dut.success  # around the wall's end
    closed = walled_map(walls=[(20, 60, 40, 41), (20, 21, 40, 50), (59, 60, 40, 50),
                               (20, 60, 50, 51)])  # fmt: skip
    costmap = Costmap.from_map(closed, SMALL)
    assert mut.plan_path(
        costmap, (1.0, 1.0), goal, mut.GlobalPlannerConfig(tolerance=0.0)
    ).message == (mut.UNREACHABLE)
    dut = mut.plan_path(costmap, (1.0, 1.0), goal, mut.GlobalPlannerConfig(tolerance=0.2))
    assert dut.success and np.linalg.norm(dut.path[-1] - goal) <= 0.2
    assert dut.path[-1][0] < 2.0


def test_outside_the_map_and_non_finite_points():
    costmap = Costmap.from_map(walled_map())
    for start, goal in [((-0.1, 1.0), (2.0, 2.0)), ((1.0, 1.0), (4.1, 2.0)),
                        ((1.0, 1.0), (math.nan, 2.0)), ((1.0, math.inf), (2.0, 2.0))]:  # fmt: skip
        dut = mut.plan_path(costmap, start, goal)
        assert not dut.success and dut.message == mut.OUTSIDE_MAP == "outside the map"


def test_start_in_an_obstacle_fails_but_a_start_next_to_a_wall_escapes():
    grid = walled_map(walls=[(0, 80, 38, 42)])  # a wall from bottom to top, x 1.9..2.1
    grid.cells[70:79, 38:42] = 0  # with a gap at the top
    costmap = Costmap.from_map(grid)
    dut = mut.plan_path(costmap, (2.0, 1.0), (1.0, 1.0))
    assert dut.message == mut.START_IN_OBSTACLE == "start in an obstacle"
    # 0.12 m from the wall's face: inside the inscribed radius, but not in the wall.
    start = (1.78, 1.0)
    assert costmap.cost_at([start])[0] == INSCRIBED
    dut = mut.plan_path(costmap, start, (1.0, 1.0))
    assert dut.success and np.allclose(dut.path[0], start)
    assert np.all(costmap.cost_at(dense(dut.path)[20:]) < INSCRIBED)  # once it left
    stuck = mut.plan_path(costmap, start, (1.0, 1.0), dc.replace(
        mut.GlobalPlannerConfig(), start_escape_radius=0.0))  # fmt: skip
    assert not stuck.success and stuck.message == mut.UNREACHABLE
    # Through the gap to the other side of the wall.
    other = mut.plan_path(costmap, (1.0, 1.0), (3.0, 1.0))
    assert other.success and other.length_m > 2 * 2.5


def test_start_and_goal_in_the_same_cell():
    costmap = Costmap.from_map(walled_map())
    dut = mut.plan_path(costmap, (2.01, 2.01), (2.02, 2.03))
    assert dut.success and dut.path.shape == (2, 2)
    assert np.allclose(dut.path, [[2.01, 2.01], [2.02, 2.03]])


def test_unknown_space_is_crossed_only_when_allowed():
    grid = walled_map(unknown=[(1, 79, 30, 50)])  # an unknown band across the map
    costmap = Costmap.from_map(grid)
    allowed = mut.plan_path(costmap, (0.5, 2.0), (3.5, 2.0))
    assert allowed.success and allowed.length_m < 3.3
    forbidden = mut.GlobalPlannerConfig(allow_unknown=False)
    assert mut.plan_path(costmap, (0.5, 2.0), (3.5, 2.0), forbidden).message == mut.UNREACHABLE
    # A goal in unknown space, not allowed, is "in an obstacle" unless known free is near.
    assert mut.plan_path(costmap, (0.5, 2.0), (2.0, 2.0), forbidden).message == (
        mut.GOAL_IN_OBSTACLE
    )


def test_a_box_across_the_path_blocks_it_and_the_replanned_path_avoids_it():
    arena = load_arena(shipped_arenas()[1])  # room
    costmap = Costmap.from_map(arena_grid(arena, RES))
    start, goal = np.array([-2.2, -1.8]), np.array([2.2, -1.8])
    first = mut.plan_path(costmap, start, goal)
    assert first.success and not mut.path_blocked(costmap, first.path, start_xy=start)
    box = Footprint("box", "new", (0.0, -1.8), (0.3, 0.3), 0.0, 0.0, 0.4)
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    p = np.array([-1.0, -1.8])
    ranges = cast_rays([*arena_footprints(arena), box], p, angles, 3.5)[0]
    costmap.update_scan((*p, 0.0), ranges, angles, 3.5)
    assert mut.path_blocked(costmap, first.path, start_xy=start)
    second = mut.plan_path(costmap, start, goal)
    assert second.success and not mut.path_blocked(costmap, second.path, start_xy=start)
    assert box.signed_distance(dense(second.path)).min() > ROBOT_RADIUS
    assert mut.path_blocked(costmap, np.array([[-2.2, -1.8], [9.0, 0.0]]))  # leaves the map
    assert not mut.path_blocked(costmap, np.zeros((0, 2)))


def test_traversal_costs():
    costmap = Costmap.from_map(walled_map(walls=[(38, 42, 0, 80)], unknown=[(60, 70, 10, 20)]))
    eff = mut.traversal_costs(costmap, mut.GlobalPlannerConfig())
    assert eff.dtype == np.int32 and eff.shape == costmap.shape
    assert eff[40, 40] == -1 and eff[44, 40] == -1  # lethal, inscribed
    assert eff[65, 15] == INSCRIBED - 1 and eff[20, 40] == 0
    no_unknown = mut.traversal_costs(costmap, mut.GlobalPlannerConfig(allow_unknown=False))
    assert no_unknown[65, 15] == -1
    escape = mut.traversal_costs(costmap, mut.GlobalPlannerConfig(), start_xy=(2.0, 2.25))
    assert escape[44, 40] == INSCRIBED and escape[40, 40] == -1 and escape[44, 60] == -1
    # A start far off the costmap (a lost estimate): no escape cells, no error.
    for far in ((-50.0, 2.0), (2.0, 90.0)):
        off = mut.traversal_costs(costmap, mut.GlobalPlannerConfig(), start_xy=far)
        assert np.array_equal(off, eff)


@pytest.mark.parametrize(
    "change, key",
    [
        ({"tolerance": -0.1}, "tolerance"),
        ({"tolerance": math.nan}, "tolerance"),
        ({"neutral_cost": 0.0}, "neutral_cost"),
        ({"cost_factor": -1.0}, "cost_factor"),
        ({"lethal_cost": 255}, "lethal_cost"),
        ({"start_escape_radius": -1.0}, "start_escape_radius"),
        ({"use_astar": 1}, "use_astar"),
    ],
)
def test_check_global_planner_config_names_the_bad_key(change, key):
    mut.check_global_planner_config(mut.GlobalPlannerConfig())
    bad = dc.replace(mut.GlobalPlannerConfig(), **change)
    with pytest.raises(ConfigError, match=rf"^nav.yaml: 'planner\.{key}' must be"):
        mut.check_global_planner_config(bad, "nav.yaml", prefix="planner.")
