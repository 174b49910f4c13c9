"""drake_sim.systems.estimation.scan_matcher: interpolation, convergence, degenerate scenes."""

import math

import numpy as np
import pytest

import drake_sim.systems.estimation.scan_matcher as mut
from drake_sim.systems.estimation.occupancy_grid import LogOddsGrid
from tests import slam_helpers as helpers

ANGLES = np.linspace(-np.pi, np.pi, 360, endpoint=False)


def pyramid(world, poses, *, levels=4, finest=0.025, seed=0):
    """Match maps of ``world`` built from noisy scans at the true ``poses``, finest first."""
    ranges, angles = helpers.lidar_scans(world, poses, seed=seed)
    grids = [
        LogOddsGrid(resolution=finest * 2**k, size=(16.0, 12.0), origin=(-8.0, -6.0))
        for k in range(levels)
    ]
    for pose, scan in zip(poses, ranges, strict=True):
        for grid in grids:
            grid.insert_scan(pose, scan, angles, 3.5)
    return [mut.MatchMap.from_grid(grid, field=1.0) for grid in grids]


def end_points(world, pose, seed=1):
    ranges, angles = helpers.lidar_scans(world, [pose], seed=seed)
    hit = np.isfinite(ranges[0])
    r, a = ranges[0][hit], angles[hit]
    return np.stack([r * np.cos(a), r * np.sin(a)], -1)


@pytest.fixture(scope="module")
def room_maps():
    truth = helpers.drive(helpers.ROOM_ROUTE, helpers.ROOM_START)
    return pyramid(helpers.room(), truth[::10])


def test_bilinear_interpolation_is_exact_on_a_plane():
    rows, cols = np.indices((6, 8), dtype=float)
    # Values at cell centres (x = (col + 0.5) * 0.1 - 1, y = (row + 0.5) * 0.1 + 2).
    x, y = (cols + 0.5) * 0.1 - 1.0, (rows + 0.5) * 0.1 + 2.0
    dut = mut.MatchMap(0.2 + 0.3 * x - 0.1 * y + 0.5, 0.1, (-1.0, 2.0))
    points = np.array([[-0.87, 2.13], [-0.5, 2.3], [-0.31, 2.44]])
    value, gradient = dut.interpolate(points)
    np.testing.assert_allclose(value, 0.7 + 0.3 * points[:, 0] - 0.1 * points[:, 1])
    np.testing.assert_allclose(gradient, [[0.3, -0.1]] * 3, atol=1e-12)


def test_points_off_the_map_read_unknown():
    dut = mut.MatchMap(np.ones((4, 4)), 0.1, (0.0, 0.0))
    value, gradient = dut.interpolate(np.array([[-5.0, 0.2], [0.2, 9.0]]))
    np.testing.assert_allclose(value, 0.5)
    np.testing.assert_allclose(gradient, 0.0)


def test_likelihood_field_peaks_on_occupied_cells():
    grid = LogOddsGrid(resolution=0.1, size=(2.0, 2.0), origin=(0.0, 0.0))
    grid.insert_scan((0.05, 1.05, 0.0), [1.0], [0.0], 3.5)  # hit cell: column 10, row 10
    dut = mut.MatchMap.from_grid(grid, field=1.0, margin=100)
    value, _ = dut.interpolate(np.array([[1.05, 1.05], [1.15, 1.05], [1.25, 1.05]]))
    np.testing.assert_allclose(value, [1.0, math.exp(-0.5), math.exp(-2.0)])


@pytest.mark.parametrize(
    "offset",
    [(0.1, 0.0, 0.0), (0.0, -0.1, 0.0), (0.0, 0.0, 5.0), (0.1, 0.05, 5.0), (-0.07, 0.1, -4.0)],
)
def test_recovers_a_known_offset_through_the_pyramid(room_maps, offset):
    world = helpers.room()
    errors = []
    for pose in [(-2.0, -2.0, 0.3), (1.0, 1.5, 2.0), (2.5, 0.0, -1.2), (-0.6, -1.5, 1.6)]:
        start = np.array(pose) + [offset[0], offset[1], math.radians(offset[2])]
        result = mut.match_scan(room_maps, end_points(world, pose), start, iterations=[6, 4, 4, 4])
        error = result.pose - pose
        errors.append([math.hypot(error[0], error[1]), abs(math.degrees(error[2]))])
        assert result.iterations > 0 and result.scores[0] > 0.6
    errors = np.array(errors)
    assert errors[:, 0].max() < 0.015 and errors[:, 1].max() < 0.3, errors


@pytest.mark.parametrize("level, offset", [(0, 0.01), (1, 0.025), (2, 0.05), (3, 0.1)])
def test_each_level_alone_converges_within_its_basin(room_maps, level, offset):
    world = helpers.room()
    pose = np.array([1.0, 1.5, 2.0])
    start = pose + [offset, -offset, math.radians(1.0)]
    result = mut.match_scan([room_maps[level]], end_points(world, pose), start, iterations=10)
    resolution = 0.025 * 2**level
    assert math.hypot(*(result.pose[:2] - pose[:2])) < 0.5 * resolution
    assert math.hypot(*(start[:2] - pose[:2])) > 0.5 * resolution


def test_a_strong_prior_holds_the_pose():
    world = helpers.room()
    pose = np.array([-2.0, -2.0, 0.3])
    start = pose + [0.05, 0.0, 0.0]
    result = mut.match_scan(
        pyramid(world, [pose]), end_points(world, pose), start, prior_weight=[1e9] * 3
    )
    np.testing.assert_allclose(result.pose, start, atol=1e-4)


def corridor():
    """A 30 m corridor, 1.2 m wide: no feature along x within the lidar's range."""
    return helpers.World(15.0, 0.6)


def test_a_featureless_corridor_does_not_explode():
    world = corridor()
    truth = [(x, 0.1, 0.0) for x in np.arange(-2.0, 2.01, 0.5)]
    maps = pyramid(world, truth)
    pose = np.array([0.0, 0.1, 0.0])
    start = pose + [0.2, 0.06, math.radians(3.0)]
    result = mut.match_scan(maps, end_points(world, pose), start, prior_weight=[50.0] * 3)
    # Across the corridor and in yaw the walls correct the pose; along it the prior holds.
    assert abs(result.pose[1] - pose[1]) < 0.01
    assert abs(math.degrees(result.pose[2])) < 0.3
    assert abs(result.pose[0] - start[0]) < 0.05


def test_no_points_or_no_map_leave_the_pose():
    maps = [mut.MatchMap(np.full((10, 10), 0.5), 0.1, (0.0, 0.0))]
    start = (0.3, 0.4, 0.5)
    result = mut.match_scan(maps, np.zeros((0, 2)), start)
    np.testing.assert_allclose(result.pose, start)
    flat = mut.match_scan(maps, np.ones((5, 2)), start)
    np.testing.assert_allclose(flat.pose, start)
    points = mut.transform_points((1.0, 2.0, math.pi / 2), np.array([[1.0, 0.0], [0.0, 1.0]]))
    np.testing.assert_allclose(points, [[1.0, 3.0], [0.0, 2.0]], atol=1e-12)


def test_normal_spread_tells_a_corridor_from_a_room():
    ratios = {}
    for name, world, pose in [
        ("corridor", corridor(), (1.0, 0.1, 0.4)),
        ("room", helpers.room(), (1.0, 1.5, 2.0)),
    ]:
        values, vectors = mut.normal_spread(end_points(world, pose))
        ratios[name] = values[0] / values[1]
        if name == "corridor":  # the weak direction is the corridor's axis, in the scan frame
            axis = np.array([math.cos(-0.4), math.sin(-0.4)])
            assert abs(vectors[:, 0] @ axis) > 0.99
    assert ratios["corridor"] < 0.03 and ratios["room"] > 0.1, ratios
    assert mut.normal_spread(np.zeros((3, 2)))[0].tolist() == [0.0, 0.0]


def test_depth_edges_are_steps_not_grazing_walls():
    pose = (0.3, 0.1, 0.0)
    assert mut.depth_edges(end_points(corridor(), pose)) == 0  # walls at grazing angles too
    assert mut.depth_edges(end_points(helpers.doorways(), pose)) >= 4
    values, _ = mut.normal_spread(end_points(helpers.doorways(), pose))
    assert values[0] < 0.05 * values[1]  # the normals alone call it a corridor
    assert mut.depth_edges(np.zeros((1, 2))) == 0


def test_unknown_cells_do_not_weigh():
    values = np.full((10, 10), 0.2)
    known = np.zeros((10, 10), bool)
    known[:, :5] = True
    dut = mut.MatchMap(values, 0.1, (0.0, 0.0), known)
    points = np.array([[0.25, 0.5], [0.75, 0.5], [2.0, 2.0]])
    np.testing.assert_array_equal(dut.is_known(points), [True, False, False])
    _, _, weights = mut._linearise(dut, points, np.zeros(3))
    np.testing.assert_allclose(weights, [3.0, 0.0, 0.0])  # the known point carries them all


def test_surface_normals_point_into_the_surfaces():
    wall = np.stack([np.full(21, 1.0), np.linspace(-0.5, 0.5, 21)], -1)  # the line x = 1
    # (A scan is a ring: the first and last points pair with each other's neighbours.)
    np.testing.assert_allclose(mut.surface_normals(wall)[3:-3], [[1.0, 0.0]] * 15, atol=1e-12)
    angles = np.linspace(0.0, 1.0, 30)
    ring = 2.0 * np.stack([np.cos(angles), np.sin(angles)], -1)  # a circle round the sensor
    normals = mut.surface_normals(ring)
    np.testing.assert_allclose(normals[3:-3], ring[3:-3] / 2.0, atol=1e-3)
    lone = np.array([[1.0, 0.0], [0.0, 3.0], [-2.0, 0.0], [0.0, -1.5]] * 3)  # far apart
    np.testing.assert_allclose(mut.surface_normals(lone), lone / np.hypot(*lone.T)[:, None])


def test_levels_are_read_where_their_grids_put_the_hits():
    # Grids that put each hit half a cell beyond the end along the surface's normal, read at
    # the same points: the pose is recovered as well as with hector's end cells.
    world = helpers.room()
    poses = helpers.drive(helpers.ROOM_ROUTE, helpers.ROOM_START)[::10]
    ranges, angles = helpers.lidar_scans(world, poses, seed=0)
    grids = [
        LogOddsGrid(resolution=0.025 * 2**k, size=(16.0, 12.0), origin=(-8.0, -6.0), hit_offset=0.5)
        for k in range(4)
    ]
    for pose, scan in zip(poses, ranges, strict=True):
        hit = np.isfinite(scan)
        normals = np.stack([np.cos(angles), np.sin(angles)], -1)
        normals[hit] = mut.surface_normals(scan[hit, None] * normals[hit])
        for grid in grids:
            grid.insert_scan(pose, scan, angles, 3.5, hit_directions=normals)
    maps = [mut.MatchMap.from_grid(grid, field=1.0) for grid in grids]
    for pose in [(-2.0, -2.0, 0.3), (1.0, 1.5, 2.0), (2.5, 0.0, -1.2)]:
        points = end_points(world, pose)
        start = np.array(pose) + [0.07, -0.05, math.radians(3.0)]
        kwargs = dict(iterations=[6, 4, 4, 4], hit_offset=0.5)
        result = mut.match_scan(maps, points, start, **kwargs)  # without: read at the ends
        shifted = mut.match_scan(
            maps, points, start, hit_directions=mut.surface_normals(points), **kwargs
        )
        error = math.hypot(*(shifted.pose[:2] - pose[:2]))
        assert error < 0.01 and abs(math.degrees(shifted.pose[2] - pose[2])) < 0.3
        assert result.scores[0] < shifted.scores[0]  # the ends sit half a cell off the peaks
