"""Arenas (drake_sim.worlds.arena): loading, checks naming file and key, footprints, grid."""

import math

import numpy as np
import pytest
from scipy import ndimage

import drake_sim.worlds.arena as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap
from drake_sim.worlds.footprints import clearance

CONTRACT = """
size: [6.0, 5.0]                  # m, a walled rectangle centred on the origin
wall: {height: 0.3, thickness: 0.05}
obstacles:
  - {box: {size: [0.4, 0.4, 0.3], position: [1.0, 0.5], yaw: 30}}   # m, degrees
  - {cylinder: {radius: 0.15, height: 0.3, position: [-1.2, 0.8]}}
  - {wall: {from: [0.0, -2.5], to: [0.0, 0.5]}}                       # an inner wall
start: {x: -2.0, y: -1.5, yaw: 0}
"""


def _load(tmp_path, text: str, name: str = "room.yaml") -> mut.Arena:
    path = tmp_path / name
    path.write_text(text)
    return mut.load_arena(path)


def test_the_shipped_arenas_load_and_fit_the_issue():
    files = mut.shipped_arenas()
    assert [f.name for f in files] == ["maze.yaml", "room.yaml", "warehouse.yaml"]
    arenas = {f.stem: mut.load_arena(f) for f in files}
    assert 5.0 <= arenas["room"].size[0] <= 7.0 and 4.0 <= arenas["room"].size[1] <= 6.0
    assert sum(o.wall is not None for o in arenas["maze"].obstacles) >= 3
    assert arenas["warehouse"].size[0] >= 10.0 and arenas["warehouse"].size[1] >= 8.0
    kinds = {k for o in arenas["warehouse"].obstacles for k in ("box", "cylinder") if getattr(o, k)}
    assert kinds == {"box", "cylinder"} and len(arenas["warehouse"].obstacles) >= 10
    for name, arena in arenas.items():
        assert arena.wall.height >= 0.3, name
        footprints = mut.arena_footprints(arena)
        assert all(f.height >= 0.25 for f in footprints), name
        # Everything stands taller than the lidar's scan plane, so the scan sees all of it.
        assert len(mut.arena_footprints(arena, height=0.17)) == len(footprints), name


def test_the_contract_example_loads(tmp_path):
    arena = _load(tmp_path, CONTRACT)
    assert arena.size == [6.0, 5.0] and arena.wall == mut.WallSpec(height=0.3, thickness=0.05)
    box, cylinder, wall = arena.obstacles
    assert box.box == mut.BoxSpec(size=[0.4, 0.4, 0.3], position=[1.0, 0.5], yaw=30.0)
    assert cylinder.cylinder.radius == 0.15 and cylinder.box is None
    assert wall.wall.from_ == [0.0, -2.5] and wall.wall.to == [0.0, 0.5]
    assert arena.start_pose() == (-2.0, -1.5, 0.0)
    assert _load(tmp_path, CONTRACT.replace("yaw: 0}", "yaw: 90}")).start_pose()[2] == (
        pytest.approx(math.pi / 2)
    )


def test_footprints_of_the_contract_example(tmp_path):
    footprints = mut.arena_footprints(_load(tmp_path, CONTRACT))
    names = [f.name for f in footprints]
    assert names == [
        "wall_north",
        "wall_south",
        "wall_east",
        "wall_west",
        "obstacle_0",
        "obstacle_1",
        "obstacle_2",
    ]
    north, _, east, _, box, cylinder, inner = footprints
    assert north.centre == (0.0, 2.525) and north.half_size == (3.05, 0.025)
    assert east.centre == (3.025, 0.0) and east.half_size == (0.025, 2.5)
    assert box.kind == "box" and box.yaw == pytest.approx(math.radians(30)) and box.height == 0.3
    assert cylinder.is_circle and cylinder.radius == 0.15
    # The inner wall takes the arena's thickness and height, with square caps at both ends.
    assert inner.kind == "wall" and inner.centre == pytest.approx((0.0, -1.0))
    assert inner.half_size == pytest.approx((1.525, 0.025)) and inner.height == 0.3
    assert inner.yaw == pytest.approx(math.pi / 2)
    np.testing.assert_allclose(
        sorted(map(tuple, box.corners().round(6))),
        sorted(
            (
                1.0 + 0.2 * (sx * math.cos(a) - sy * math.sin(a)),
                0.5 + 0.2 * (sx * math.sin(a) + sy * math.cos(a)),
            )
            for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))
            for a in (math.radians(30),)
        ),
        atol=1e-6,
    )


def test_inner_walls_may_have_their_own_thickness_and_height_and_obstacles_may_be_none(tmp_path):
    text = CONTRACT.replace(
        "to: [0.0, 0.5]}}", "to: [0.0, 0.5], thickness: 0.1, height: 0.5}, name: middle}"
    )
    inner = mut.arena_footprints(_load(tmp_path, text))[-1]
    assert inner.name == "middle" and inner.half_size == pytest.approx((1.55, 0.05))
    assert inner.height == 0.5
    head, _, _ = CONTRACT.partition("obstacles:")
    start = "start: {x: 0, y: 0}\n"
    assert _load(tmp_path, head + "obstacles:\n" + start).obstacles == []
    assert _load(tmp_path, head + "obstacles: []\n" + start).obstacles == []
    assert _load(tmp_path, head + start).obstacles == []


def test_arena_grid_at_two_resolutions(tmp_path):
    arena = _load(tmp_path, CONTRACT)
    for resolution in (0.05, 0.1):
        grid = mut.arena_grid(arena, resolution)
        assert isinstance(grid, OccupancyMap) and grid.resolution == resolution
        # The outer walls' outer boundary (6.1 x 5.1 m) plus one cell each side, centred.
        rows, cols = grid.shape
        assert cols * resolution >= 6.1 + 2 * resolution - 1e-9
        assert rows * resolution >= 5.1 + 2 * resolution - 1e-9
        assert grid.origin == pytest.approx((-cols * resolution / 2, -rows * resolution / 2, 0))

        def value(x, y, grid=grid):
            r, c = grid.cell_of(np.array([x, y]))
            return int(grid.cells[r, c])

        assert value(1.0, 0.5) == 100  # the box's centre
        assert value(1.0 + 0.2 / math.cos(math.radians(15)) + 1.5 * resolution, 0.5) == 0
        # Every cell around the box, 30 degrees rotated, by the box's own frame: occupied
        # exactly when its centre is within 0.2 m of the box's centre along both box axes.
        xs, ys = (np.asarray(v) for v in grid.centres())
        near = (np.abs(xs - 1.0) < 0.5) & (np.abs(ys - 0.5) < 0.5)
        c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
        along = c * (xs - 1.0) + s * (ys - 0.5)
        across = -s * (xs - 1.0) + c * (ys - 0.5)
        inside = (np.abs(along) <= 0.2) & (np.abs(across) <= 0.2)
        np.testing.assert_array_equal(grid.cells[near] == 100, inside[near])
        assert inside[near].sum() == pytest.approx(0.16 / resolution**2, rel=0.35)
        assert value(-1.2, 0.8) == 100 and value(-1.2, 0.8 + 0.15 + 1.2 * resolution) == 0
        assert value(0.0, -1.0) == 100 and value(0.0, 0.5 + 2 * resolution) == 0
        assert value(0.0, -2.5) == 100  # the inner wall meets the south wall
        assert value(-2.0, -1.5) == 0  # the start
        assert value(-3.025, 0.0) == 100 and value(0.0, 2.53) == 100  # outer walls
        assert value(-3.0 - 0.05 - resolution, 0.0) == -1  # beyond the walls
        assert grid.cells[0].tolist() == [-1] * cols and grid.cells[:, -1].tolist() == [-1] * rows
        assert set(np.unique(grid.cells)) == {-1, 0, 100}


def test_a_grid_cell_is_occupied_exactly_when_its_centre_is_inside(tmp_path):
    arena = _load(tmp_path, CONTRACT)
    grid = mut.arena_grid(arena, 0.04)
    xs, ys = grid.centres()
    xs, ys = np.broadcast_arrays(np.asarray(xs), np.asarray(ys))
    inside = clearance(mut.arena_footprints(arena), np.stack([xs, ys], axis=-1)) <= 1e-9
    np.testing.assert_array_equal(grid.cells == 100, inside)


def test_the_grid_at_a_scan_height_leaves_out_lower_obstacles(tmp_path):
    arena = _load(
        tmp_path, CONTRACT.replace("radius: 0.15, height: 0.3", "radius: 0.15, height: 0.1")
    )
    low = mut.arena_grid(arena, 0.05)
    high = mut.arena_grid(arena, 0.05, height=0.17)
    r, c = low.cell_of(np.array([-1.2, 0.8]))
    assert low.cells[r, c] == 100 and high.cells[r, c] == 0
    assert np.sum(low.cells != high.cells) == np.sum((low.cells == 100) & (high.cells == 0))
    assert len(mut.arena_footprints(arena, height=0.17)) == 6


def test_arena_bounds(tmp_path):
    arena = _load(tmp_path, CONTRACT)
    lo, hi = mut.arena_bounds(arena)
    np.testing.assert_allclose([lo, hi], [[-3.0, -2.5], [3.0, 2.5]])
    lo, hi = mut.arena_bounds(arena, walls=True)
    np.testing.assert_allclose([lo, hi], [[-3.05, -2.55], [3.05, 2.55]])


OBSTACLE_2 = "  - {wall: {from: [0.0, -2.5], to: [0.0, 0.5]}}                       # an inner wall"


def _with_obstacle(line: str) -> str:
    return CONTRACT.replace(OBSTACLE_2, "  - " + line)


@pytest.mark.parametrize(
    "text, match",
    [
        (CONTRACT + "colour: red\n", "unknown key 'colour'"),
        (CONTRACT.replace("thickness: 0.05}", "thickness: 0.05, colour: 1}"), "'wall.colour'"),
        (_with_obstacle("{wall: {from: [0, 0], too: [1, 1]}}"), r"'obstacles\[2\].wall.too'"),
        (_with_obstacle("{wall: {from_: [0, 0], to: [1, 1]}}"), "unknown key 'from_'"),
        (CONTRACT.replace("size: [6.0, 5.0]", "size: [-6.0, 5.0]"), r"'size\[0\]' must be pos"),
        (CONTRACT.replace("size: [6.0, 5.0]", "size: [6.0]"), "'size' must have 2 numbers"),
        (CONTRACT.replace("size: [6.0, 5.0]", "size: [6.0, .nan]"), r"'size\[1\]' must be fin"),
        (CONTRACT.replace("size: [6.0, 5.0]", ""), "missing key 'size'"),
        (CONTRACT.replace("height: 0.3, thickness", "height: 0, thickness"), "'wall.height' must"),
        (CONTRACT.replace("thickness: 0.05", "thickness: -0.05"), "'wall.thickness' must be p"),
        (CONTRACT.replace("[0.4, 0.4, 0.3]", "[0.4, -0.4, 0.3]"), r"box.size\[1\]' must be pos"),
        (CONTRACT.replace("[0.4, 0.4, 0.3]", "[0.4, 0.4]"), r"box.size' must have 3"),
        (CONTRACT.replace("yaw: 30", "yaw: .nan"), r"'obstacles\[0\].box.yaw' must be finite"),
        (CONTRACT.replace("yaw: 30", "yaw: .inf"), r"'obstacles\[0\].box.yaw' must be finite"),
        (CONTRACT.replace("radius: 0.15", "radius: 0"), r"cylinder.radius' must be positive"),
        (CONTRACT.replace("radius: 0.15, ", ""), r"missing key 'obstacles\[1\].cylinder.radius'"),
        (CONTRACT.replace("position: [-1.2, 0.8]", "position: []"), r"cylinder.position'"),
        (
            CONTRACT.replace("position: [1.0, 0.5]", "position: [3.4, 0.0]"),
            r"'obstacles\[0\].box.position': \(3.4, 0\) puts it outside the walls",
        ),
        (
            CONTRACT.replace("position: [1.0, 0.5]", "position: [2.75, 0.0]"),
            r"box.position'.*reaches \(3.02",
        ),  # only the rotated corner pokes out
        (
            CONTRACT.replace("position: [-1.2, 0.8]", "position: [-1.2, 2.4]"),
            r"'obstacles\[1\].cylinder.position'.*outside the walls",
        ),
        (CONTRACT.replace("to: [0.0, 0.5]", "to: [0.0, 2.6]"), r"wall.to': \(0, 2.6\) lies out"),
        (CONTRACT.replace("to: [0.0, 0.5]", "to: [0.0, -2.5]"), r"'obstacles\[2\].wall': zero-len"),
        (CONTRACT.replace("to: [0.0, 0.5]}", "to: [0.0, 0.5], thickness: 0}"), "wall.thickness'"),
        (_with_obstacle("{}"), r"'obstacles\[2\]' must have exactly one of"),
        (_with_obstacle("{name: x}"), r"'obstacles\[2\]' must have exactly one of"),
        (
            _with_obstacle(
                "{box: {size: [1, 1, 1], position: [1, 1]}, "
                "cylinder: {radius: 1, height: 1, position: [1, 1]}}"
            ),
            r"'obstacles\[2\]' must have exactly one",
        ),
        (
            _with_obstacle(
                "{name: wall_north, cylinder: {radius: 0.1, height: 1, position: [1, 1]}}"
            ),
            r"'obstacles\[2\].name': 'wall_north' is taken",
        ),
        (CONTRACT.replace("obstacles:", "obstacles: {box: 1}\nx:"), "'obstacles' must be a list"),
        (CONTRACT.replace("obstacles:\n", "obstacles: 3\nfoo:\n"), "'obstacles' must be a list"),
        (CONTRACT.replace("x: -2.0, y: -1.5", "x: 1.0, y: 0.5"), "'start'.* inside 'obstacle_0'"),
        (
            CONTRACT.replace("x: -2.0, y: -1.5", "x: -1.2, y: 0.5"),
            r"'start'.* is 0.150 m from 'obstacle_1' \(the robot needs 0.2 m\)",
        ),
        (CONTRACT.replace("x: -2.0, y: -1.5", "x: -2.9, y: -1.5"), "'start'.* from 'wall_west'"),
        (CONTRACT.replace("x: -2.0, y: -1.5", "x: -4.0, y: -1.5"), "'start'.* outside the walls"),
        (CONTRACT.replace("x: -2.0, ", ""), "missing key 'start.x'"),
        (CONTRACT.replace("y: -1.5", "y: .nan"), "'start.y' must be finite"),
        (CONTRACT.replace("size: [6.0, 5.0]", "size: [6.0, 5.0"), "malformed YAML at line"),
        ("- 1\n- 2\n", "expected a mapping"),
    ],
)
def test_bad_arenas_are_one_line_naming_the_file_and_key(tmp_path, text, match):
    with pytest.raises(ConfigError, match=match) as error:
        _load(tmp_path, text)
    message = str(error.value)
    assert "room.yaml" in message and "\n" not in message


def test_a_missing_arena_file(tmp_path):
    with pytest.raises(ConfigError, match="nope.yaml: no such arena file"):
        mut.load_arena(tmp_path / "nope.yaml")


def test_check_arena_takes_arenas_built_in_code():
    arena = mut.Arena(size=[4.0, 3.0], start=mut.StartSpec(x=0.0, y=0.0))
    assert mut.check_arena(arena) is arena
    arena.obstacles.append(mut.ObstacleSpec(cylinder=mut.CylinderSpec(0.1, 0.3, [0.0, 0.0])))
    with pytest.raises(ConfigError, match="in code: 'start'.* inside 'obstacle_0'"):
        mut.check_arena(arena, "in code")


def test_grid_resolution_must_be_positive(tmp_path):
    with pytest.raises(ConfigError, match="resolution"):
        mut.arena_grid(_load(tmp_path, CONTRACT), 0.0)


@pytest.mark.parametrize(
    "resolution, inside, outside",
    [(0.05, (1.025, 0.725), (1.075, 0.775)), (0.1, (1.1, 0.7), (1.1, 0.8))],
)
def test_cells_at_the_rotated_box_corner_by_hand(tmp_path, resolution, inside, outside):
    """Near the box's corner (1.073, 0.773): worked by hand in the box's frame, e.g. at 0.05 m
    the centre (1.075, 0.775) is 0.2025 m along the box's x axis (outside; half size 0.2)."""
    grid = mut.arena_grid(_load(tmp_path, CONTRACT), resolution)
    for point, expected in ((inside, 100), (outside, 0)):
        r, c = grid.cell_of(np.array(point) + 1e-6)
        xs, ys = grid.centres()
        assert (xs[r, c], ys[r, c]) == pytest.approx(point)
        assert grid.cells[r, c] == expected, point


def test_check_position_names_the_key(tmp_path):
    arena = _load(tmp_path, CONTRACT)
    mut.check_position(arena, (-2.0, 1.5), "here", "goal")  # clear of everything
    with pytest.raises(
        ConfigError, match=r"^here: 'goal': \(0.1, 0\) is 0.075 m from 'obstacle_2'"
    ):
        mut.check_position(arena, (0.1, 0.0), "here", "goal")
    with pytest.raises(ConfigError, match=r"^here: 'goal': \(0, 3\) lies outside the walls"):
        mut.check_position(arena, (0.0, 3.0), "here", "goal")


@pytest.mark.parametrize("path", mut.shipped_arenas(), ids=lambda p: p.stem)
def test_every_passage_of_a_shipped_arena_is_at_least_0_7_m_wide(path):
    """Where a disc of 0.35 m radius fits is one connected region holding the start: a robot
    needs no passage narrower than 0.7 m to get anywhere."""
    arena = mut.load_arena(path)
    grid = mut.arena_grid(arena, 0.025)
    room = ndimage.distance_transform_edt(grid.cells == 0) * grid.resolution >= 0.35 + 0.0125
    regions, count = ndimage.label(room, np.ones((3, 3), bool))
    assert count == 1
    assert regions[grid.cell_of(np.array(arena.start_pose()[:2]))] == 1
    # and that region reaches within 0.4 m of nearly all of the free floor.
    near = ndimage.distance_transform_edt(~room) * grid.resolution <= 0.4
    assert np.mean(near[grid.cells == 0]) >= 0.95
