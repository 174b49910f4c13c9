"""Tests of the costmaps: costmap_2d's inflation values, the static layer, the obstacle layer
marking and clearing from synthetic scans, the rolling window and the config checks."""

import dataclasses as dc
import math

import numpy as np
import pytest

import drake_sim.navigation.costmap as mut
from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.resources import config_dir
from drake_sim.worlds.arena import arena_footprints, arena_grid, load_arena
from drake_sim.worlds.footprints import Footprint, cast_rays

RES = 0.05
ANGLES = np.linspace(-math.pi, math.pi, 360, endpoint=False)


def room():
    arena = load_arena(config_dir() / "arenas" / "room.yaml")
    return arena, arena_grid(arena, RES)


def scan(footprints, p_WS, max_range=3.5):
    return cast_rays(footprints, np.asarray(p_WS, dtype=float), ANGLES, max_range)[0]


def costmap_2d_cost(d, config):
    """costmap_2d's InflationLayer::computeCost, d in m."""
    if d == 0:
        return 254
    if d <= config.robot_radius:
        return 253
    if d > config.inflation_radius:
        return 0
    return int(252 * math.exp(-config.cost_scaling_factor * (d - config.robot_radius)))


def test_cost_values_are_costmap_2d_s():
    assert (mut.FREE_SPACE, mut.INSCRIBED, mut.LETHAL, mut.NO_INFORMATION) == (0, 253, 254, 255)


@pytest.mark.parametrize(
    "config",
    [
        mut.CostmapConfig(),
        mut.CostmapConfig(robot_radius=0.2, inflation_radius=1.0, cost_scaling_factor=5.0),
    ],
)
def test_inflate_is_the_costmap_2d_formula_at_known_distances(config):
    lethal = np.zeros((61, 61), dtype=bool)
    lethal[30, 30] = True
    dut = mut.inflate(lethal, RES, config)
    assert dut.dtype == np.uint8
    for dr, dc_ in [
        (0, 0),
        (0, 1),
        (2, 3),
        (0, 4),
        (3, 4),
        (0, 5),
        (4, 4),
        (6, 8),
        (0, 10),
        (0, 11),
        (7, 7),
        (0, 19),
        (0, 20),
        (0, 21),
        (14, 14),
        (0, 25),
    ]:
        d = math.hypot(dr, dc_) * RES
        assert dut[30 + dr, 30 + dc_] == costmap_2d_cost(d, config), (dr, dc_, d)
        assert dut[30 - dc_, 30 - dr] == dut[30 + dr, 30 + dc_]  # symmetric
    if config.inflation_radius == 0.5:
        # Hand-computed: d = 0.25 m -> floor(252 exp(-3 * 0.03)) = 230; d = 0.5 m -> 108.
        assert dut[30, 35] == 230 and dut[30, 40] == 108 and dut[30, 41] == 0


def test_inflate_matches_brute_force_distances_on_random_masks():
    rng = np.random.default_rng(11)
    config = mut.CostmapConfig()
    for _ in range(5):
        lethal = rng.random((18, 23)) < 0.02
        lethal[rng.integers(18), rng.integers(23)] = True
        dut = mut.inflate(lethal, RES, config)
        obstacles = np.argwhere(lethal)
        for (r, c), value in np.ndenumerate(dut):
            d = np.hypot(*(obstacles - (r, c)).T).min() * RES
            assert value == costmap_2d_cost(d, config), (r, c, d)


def test_inflate_without_obstacles_is_free():
    assert not mut.inflate(np.zeros((5, 7), dtype=bool), RES, mut.CostmapConfig()).any()


def test_from_map_static_layer_and_unknown_handling():
    cells = np.zeros((40, 50), dtype=np.int8)
    cells[:, :10] = -1
    cells[20, 30] = 100
    cells[5, 40] = 50  # below the lethal threshold 65
    cells[20, 12] = 100  # unknown cells within its inscribed radius become >= INSCRIBED
    grid = OccupancyMap(cells, RES, (1.0, -2.0, 0.0))
    dut = mut.Costmap.from_map(grid)
    assert dut.shape == (40, 50) and dut.resolution == RES and dut.origin == (1.0, -2.0, 0.0)
    assert dut.costs[20, 30] == mut.LETHAL and dut.costs[20, 31] == mut.INSCRIBED
    assert dut.costs[5, 40] == mut.FREE_SPACE
    assert dut.costs[0, 0] == mut.NO_INFORMATION
    assert dut.costs[20, 9] == mut.INSCRIBED and dut.costs[20, 6] == mut.NO_INFORMATION
    untracked = mut.Costmap.from_map(grid, mut.CostmapConfig(track_unknown_space=False))
    assert untracked.costs[0, 0] == mut.FREE_SPACE
    assert np.array_equal(untracked.costs[:, 10:], dut.costs[:, 10:])


def test_cell_of_cost_at_and_centres_agree():
    _, grid = room()
    dut = mut.Costmap.from_map(grid)
    xs, ys = dut.centres()
    rows, cols = dut.cell_of(np.stack([xs, ys], -1))
    assert np.array_equal(rows, np.indices(dut.shape)[0])
    assert np.array_equal(cols, np.indices(dut.shape)[1])
    assert np.array_equal(dut.cost_at(np.stack([xs, ys], -1)), dut.costs)
    assert dut.cost_at([[100.0, 0.0]])[0] == mut.NO_INFORMATION
    assert dut.cost_at([[100.0, 0.0]], outside=mut.LETHAL)[0] == mut.LETHAL
    # Cells agree with the map's, and the world <-> grid maps invert each other.
    probe = np.array([[0.1234, -1.987], [2.5, 2.0]])
    assert all(
        np.array_equal(a, b) for a, b in zip(dut.cell_of(probe), grid.cell_of(probe), strict=True)
    )
    assert np.allclose(dut.to_world(dut.to_grid(probe)), probe)


def test_obstacle_layer_marks_a_new_box_and_clears_it_when_it_moves_away():
    arena, grid = room()
    walls = arena_footprints(arena)
    dut = mut.Costmap.from_map(grid)
    static_costs = dut.costs.copy()
    box = Footprint("box", "extra", (0.0, -1.5), (0.2, 0.2), 0.0, 0.0, 0.4)
    p = (-1.5, -1.5)
    dut.update_scan((*p, 0.0), scan([*walls, box], p), ANGLES, 3.5)
    # The face seen by the lidar is at x = -0.2, a cell boundary: the hits mark the cells on
    # one side of it.
    front = (-0.175, -1.5)
    assert dut.cost_at([front])[0] == mut.LETHAL
    assert dut.cost_at([(-0.35, -1.5)])[0] == mut.INSCRIBED  # 0.15 m in front of its face
    assert 0 < dut.cost_at([(-0.6, -1.5)])[0] < mut.INSCRIBED
    # The box moves 0.5 m away along y: the old place is cleared, the new one marked.
    moved = dc.replace(box, centre=(0.0, -2.0))
    dut.update_scan((*p, 0.0), scan([*walls, moved], p), ANGLES, 3.5)
    assert dut.cost_at([front])[0] < mut.INSCRIBED  # only the moved box's inflation
    assert dut.obstacle_layer[dut.cell_of(np.array(front))] == mut.FREE_SPACE
    seen = np.array([[x, y] for x in (-0.225, -0.175) for y in np.arange(-2.125, -1.85, 0.05)])
    assert np.sum(dut.cost_at(seen) == mut.LETHAL) >= 5
    # Gone altogether: only the static map's obstacles remain lethal.
    dut.update_scan((*p, 0.0), scan(walls, p), ANGLES, 3.5)
    assert not np.any(
        (dut.costs == mut.LETHAL)
        & (static_costs != mut.LETHAL)
        & (dut.obstacle_layer != mut.LETHAL)
    )
    new_lethal = (dut.costs == mut.LETHAL) & (static_costs != mut.LETHAL)
    assert not new_lethal[dut.cell_of(seen)].any()


def test_scans_never_clear_the_static_layer():
    arena, grid = room()
    dut = mut.Costmap.from_map(grid)
    static_costs = dut.costs.copy()
    # A lidar that sees nothing at all (every beam inf) clears its surroundings, walls too.
    p = (2.0, 1.8)
    dut.update_scan((*p, 0.3), np.full(360, np.inf), ANGLES, 3.5)
    assert np.array_equal(dut.costs[static_costs == mut.LETHAL], static_costs[static_costs == 254])
    assert np.all(dut.costs >= np.where(static_costs == mut.NO_INFORMATION, 0, static_costs))


def test_clearing_and_marking_ranges():
    cells = np.zeros((200, 200), dtype=np.int8)
    grid = OccupancyMap(cells, RES, (-5.0, -5.0, 0.0))
    config = mut.CostmapConfig(obstacle_max_range=2.5, raytrace_max_range=3.0)
    dut = mut.Costmap.from_map(grid, config)
    angles = np.array([0.0, math.pi / 2, math.pi, -math.pi / 2])
    # Beam 0 hits at 2.0 m (marked), beam 1 at 2.8 m (too far to mark), beams 2 and 3 no return.
    dut.update_scan((0.0, 0.0, 0.0), [2.0, 2.8, np.inf, np.inf], angles, 3.5)
    layer = dut.obstacle_layer
    assert layer[dut.cell_of(np.array([2.0 + 1e-6, 0.0]))] == mut.LETHAL
    assert layer[dut.cell_of(np.array([1.0, 0.0]))] == mut.FREE_SPACE
    assert layer[dut.cell_of(np.array([0.0, 2.8 + 1e-6]))] == mut.NO_INFORMATION
    assert layer[dut.cell_of(np.array([0.0, 2.5]))] == mut.FREE_SPACE
    assert layer[dut.cell_of(np.array([-2.95, 0.0]))] == mut.FREE_SPACE
    assert layer[dut.cell_of(np.array([-3.1, 0.0]))] == mut.NO_INFORMATION  # beyond raytrace
    assert layer[dut.cell_of(np.array([0.0, -3.1]))] == mut.NO_INFORMATION
    assert (layer == mut.LETHAL).sum() == 1
    # A shorter lidar clears inf beams only up to its own range.
    dut.clear_obstacles()
    assert np.all(dut.obstacle_layer == mut.NO_INFORMATION) and not dut.costs.any()
    dut.update_scan((0.0, 0.0, 0.0), [np.inf], [0.0], 1.0)
    assert dut.obstacle_layer[dut.cell_of(np.array([0.95, 0.0]))] == mut.FREE_SPACE
    assert dut.obstacle_layer[dut.cell_of(np.array([1.1, 0.0]))] == mut.NO_INFORMATION
    # The sensor's yaw turns the beams; NaN beams are ignored; hits nearer than
    # obstacle_min_range do not mark.
    near = mut.Costmap.from_map(grid, dc.replace(config, obstacle_min_range=0.3))
    near.update_scan((1.0, 1.0, math.pi / 2), [1.0, np.nan, 0.2], [0.0, 1.0, math.pi], 3.5)
    assert near.obstacle_layer[near.cell_of(np.array([1.0, 2.0 + 1e-6]))] == mut.LETHAL
    assert (near.obstacle_layer == mut.LETHAL).sum() == 1


def test_a_rotated_map_origin_places_marks_and_clears_in_the_world():
    grid = OccupancyMap(np.zeros((100, 100), dtype=np.int8), RES, (1.0, -2.0, 0.5))
    dut = mut.Costmap.from_map(grid)
    sensor = np.array([3.0, 0.5])
    for yaw, beam, r in [(0.2, 0.3, 1.0), (-1.0, -2.0, 1.3)]:
        dut.update_scan((*sensor, yaw), [r], [beam], 3.5)
        u = np.array([math.cos(yaw + beam), math.sin(yaw + beam)])
        hit = sensor + (r + 1e-6) * u
        assert dut.cost_at([hit])[0] == mut.LETHAL
        layer = dut.obstacle_layer
        assert layer[dut.cell_of(sensor + 0.5 * r * u)] == mut.FREE_SPACE
        assert layer[dut.cell_of(sensor - 0.5 * r * u)] == mut.NO_INFORMATION
    assert (dut.obstacle_layer == mut.LETHAL).sum() == 2


def test_clearing_unknown_space_makes_it_free():
    cells = np.full((100, 100), -1, dtype=np.int8)
    dut = mut.Costmap.from_map(OccupancyMap(cells, RES, (-2.5, -2.5, 0.0)))
    assert np.all(dut.costs == mut.NO_INFORMATION)
    dut.update_scan((0.0, 0.0, 0.0), [1.0], [0.0], 3.5)
    # (Probes at cell centres.) The hit cell is the one centred on (1.025, 0.025).
    assert dut.cost_at([(1.025, 0.025)])[0] == mut.LETHAL
    assert dut.cost_at([(0.475, 0.025)])[0] == mut.FREE_SPACE  # 0.55 m away, cleared
    assert dut.cost_at([(0.825, 0.025)])[0] == mut.INSCRIBED  # 0.2 m away
    assert dut.cost_at([(0.025, 0.525)])[0] == mut.NO_INFORMATION
    # Unknown cells near the obstacle take its inscribed cost, farther ones stay unknown.
    assert dut.cost_at([(1.025, 0.175)])[0] == mut.INSCRIBED
    assert dut.cost_at([(1.025, 0.325)])[0] == mut.NO_INFORMATION


def test_incremental_reinflation_equals_a_full_one():
    arena, grid = room()
    walls = arena_footprints(arena)
    rng = np.random.default_rng(3)
    dut = mut.Costmap.from_map(grid)
    for k in range(8):
        p = rng.uniform([-2.5, -2.0], [2.5, 2.0])
        box = Footprint("box", "b", tuple(rng.uniform(-2.5, 2.5, 2)), (0.15, 0.2), 0.3, 0.0, 1.0)
        dut.update_scan(
            (*p, rng.uniform(-3, 3)), scan([*walls, box] if k % 2 else walls, p), ANGLES, 3.5
        )
    full = mut.inflate(dut.lethal_mask(), RES, dut.config)
    unknown = (dut.static_layer == 255) & (dut.obstacle_layer == 255) & (full < 253)
    full[unknown] = 255
    assert np.array_equal(dut.costs, full)


def test_local_window_is_a_centred_crop_with_the_same_layers():
    arena, grid = room()
    dut = mut.Costmap.from_map(grid)
    p = (-1.5, -1.5)
    dut.update_scan((*p, 0.0), scan(arena_footprints(arena), p), ANGLES, 3.5)
    window = dut.local_window((-1.0, 0.5))
    assert window.shape == (60, 60) and window.resolution == RES
    row, col = dut.cell_of(np.array([-1.0, 0.5]))
    assert np.array_equal(window.cell_of(np.array([-1.0, 0.5])), (30, 30))
    r0, c0 = row - 30, col - 30
    assert np.array_equal(window.costs[:], dut.costs[r0 : r0 + 60, c0 : c0 + 60])
    assert np.array_equal(window.obstacle_layer, dut.obstacle_layer[r0 : r0 + 60, c0 : c0 + 60])
    xs, ys = window.centres()
    assert np.array_equal(window.costs, dut.cost_at(np.stack([xs, ys], -1)))
    # Near a corner of the map, the part outside is NO_INFORMATION.
    corner = dut.local_window((-3.1, -2.6))
    xs, ys = corner.centres()
    outside = ~dut.inside(*dut.cell_of(np.stack([xs, ys], -1)))
    assert outside.any() and np.all(corner.costs[outside] == mut.NO_INFORMATION)
    # The window is a costmap of its own: scans update it.
    before = window.costs.copy()
    window.update_scan((-1.0, 0.5, 0.0), [0.6], [0.0], 3.5)
    assert window.cost_at([(-0.4 + 1e-6, 0.5)])[0] == mut.LETHAL and np.array_equal(
        dut.costs[r0 : r0 + 60, c0 : c0 + 60], before
    )


@pytest.mark.parametrize(
    "change, key",
    [
        ({"robot_radius": 0.0}, "robot_radius"),
        ({"inflation_radius": 0.1}, "inflation_radius"),
        ({"cost_scaling_factor": math.nan}, "cost_scaling_factor"),
        ({"cost_scaling_factor": -1.0}, "cost_scaling_factor"),
        ({"lethal_cost_threshold": 101}, "lethal_cost_threshold"),
        ({"unknown_cost_value": 256}, "unknown_cost_value"),
        ({"obstacle_min_range": 3.0}, "obstacle_min_range"),
        ({"raytrace_max_range": math.inf}, "raytrace_max_range"),
        ({"local_width": -3.0}, "local_width"),
        ({"track_unknown_space": 1}, "track_unknown_space"),
    ],
)
def test_check_costmap_config_names_the_bad_key(change, key):
    mut.check_costmap_config(mut.CostmapConfig(), "x.yaml")
    bad = dc.replace(mut.CostmapConfig(), **change)
    with pytest.raises(ConfigError, match=rf"^nav.yaml: 'costmap\.{key}' must be"):
        mut.check_costmap_config(bad, "nav.yaml", prefix="costmap.")
    with pytest.raises(ConfigError, match=key):
        mut.Costmap(np.zeros((3, 3)), RES, config=bad)


def test_config_loads_from_yaml_with_unknown_keys_rejected(tmp_path):
    path = tmp_path / "costmap.yaml"
    path.write_text("robot_radius: 0.2\ninflation_radius: 0.6\n")
    config = load_typed(mut.CostmapConfig, filename=path)
    mut.check_costmap_config(config, str(path))
    assert (config.robot_radius, config.inflation_radius, config.cost_scaling_factor) == (
        0.2,
        0.6,
        3.0,
    )
    path.write_text("robot_radius: 0.2\ninflation_radus: 0.6\n")
    with pytest.raises(ConfigError, match="inflation_radus"):
        load_typed(mut.CostmapConfig, filename=path)
