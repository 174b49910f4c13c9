"""drake_sim.systems.estimation.scan_matching_slam: SLAM in synthetic rooms, drifting odometry."""

import dataclasses as dc
import functools
import math

import numpy as np
import pytest

import drake_sim.systems.estimation.scan_matching_slam as mut
from drake_sim.base.map_files import load_map
from drake_sim.base.planar import compose, wrap_angle
from drake_sim.systems.estimation.occupancy_grid import known_fraction, occupancy_iou
from tests import slam_helpers as helpers

X_BASE_SENSOR = (-0.064, 0.0, 0.0)  # The TurtleBot3 Waffle's LDS sits behind the axle.


def run(world, route, start, *, seed, config=None, **odometry):
    """Drives ``route``; returns (slam, truth poses, odometry poses)."""
    truth = helpers.drive(route, start)
    odom = helpers.drifting_odometry(truth, seed=seed, **odometry)
    sensor = np.array([helpers.compose(pose, X_BASE_SENSOR) for pose in truth])
    ranges, angles = helpers.lidar_scans(world, sensor, seed=seed + 100)
    dut = mut.ScanMatchingSlam(config, truth[0], X_BASE_SENSOR)
    for k, (scan, pose) in enumerate(zip(ranges, odom, strict=True)):
        dut.update(scan, angles, pose, range_max=3.5, range_min=0.12, time=0.2 * k)
    return dut, truth, odom


@functools.cache
def room_run_with(seed: int, hit_offset: float = mut.SlamConfig().hit_offset):
    """The room's route driven with odometry drift ``seed``, SLAM's ``hit_offset`` set: each
    once per test process (the runs take seconds; several tests read the same one)."""
    config = dc.replace(mut.SlamConfig(), hit_offset=hit_offset)
    return run(helpers.room(), helpers.ROOM_ROUTE, helpers.ROOM_START, seed=seed, config=config)


@pytest.fixture(scope="module", params=[7, 12])
def room_run(request):
    return room_run_with(request.param)


def test_slam_corrects_the_drift_of_odometry(room_run):
    dut, truth, odom = room_run
    trajectory = dut.trajectory
    assert trajectory.shape == truth.shape and dut.scans == len(truth)
    error = np.hypot(*(trajectory[:, :2] - truth[:, :2]).T)
    rmse = math.sqrt(np.mean(error**2))
    odometry_final = math.hypot(*(odom[-1, :2] - truth[-1, :2]))
    assert odometry_final > 0.15  # the odometry did drift (2 % and 0.5 deg/m over ~30 m)
    assert rmse <= 0.05 and 3 * rmse <= odometry_final, (rmse, odometry_final)
    yaw_error = wrap_angle(trajectory[-1, 2] - truth[-1, 2])
    assert abs(math.degrees(yaw_error)) < 1.0
    assert dut.rejected <= 0.02 * dut.scans and dut.degenerate <= 0.02 * dut.scans
    np.testing.assert_allclose(dut.times[:3], [0.0, 0.2, 0.4])


def test_the_map_matches_the_room(room_run):
    dut = room_run[0]
    truth = helpers.room().truth(0.05)
    result = dut.map()
    assert result.resolution == 0.05
    assert occupancy_iou(result, truth) >= 0.9
    assert known_fraction(result, truth) >= 0.95
    assert result.width_m < 10.0 and result.height_m < 8.0  # cropped to what was seen


def occupied_precision(occupancy_map, truth) -> float:
    """The fraction of the map's occupied cells that are occupied in ``truth`` (same grid)."""
    rows, cols = np.nonzero(occupancy_map.cells == 100)
    x = occupancy_map.origin[0] + (cols + 0.5) * occupancy_map.resolution
    y = occupancy_map.origin[1] + (rows + 0.5) * occupancy_map.resolution
    j = np.floor((x - truth.origin[0]) / truth.resolution).astype(int)
    i = np.floor((y - truth.origin[1]) / truth.resolution).astype(int)
    return float(np.mean(truth.cells[i, j] == 100))


def test_walls_are_drawn_where_the_truth_has_them():
    # Hits half a cell beyond the end along the surface's normal (the default) draw each wall
    # one cell thick, behind its face; hector's end cells draw the faces on cell edges two
    # cells thick (and the pose slides across them).
    truth = helpers.room().truth(0.05)
    assert mut.SlamConfig().hit_offset == 0.5  # the default run serves as the first
    precision = {}
    for offset in (0.5, 0.0):
        dut = room_run_with(7, offset)[0]
        precision[offset] = occupied_precision(dut.map(), truth)
    assert precision[0.5] >= 0.85 and precision[0.0] < 0.75, precision


def test_returns_near_the_range_limit_count_as_none():
    angles = np.radians(np.linspace(-20.0, 20.0, 41))
    for distance, drawn in [(3.3, True), (3.45, False)]:  # range_max 3.5, margin 0.1
        dut = mut.ScanMatchingSlam(initial_pose=(0.0, 0.0, 0.0))
        ranges = distance / np.cos(angles)  # a wall x = distance
        dut.update(ranges, angles, (0.0, 0.0, 0.0), range_max=3.5)
        grid = dut.map(crop=False)
        row = int((0.0 - grid.origin[1]) / grid.resolution)
        col = int((distance + 0.01 - grid.origin[0]) / grid.resolution)
        assert (grid.cells[row, col] == 100) == drawn, distance
        if not drawn:  # a return past the margin still clears the space up to 3.4 m
            assert grid.cells[row, int((3.37 - grid.origin[0]) / grid.resolution)] == 0


def test_saved_map_loads_back(room_run, tmp_path):
    dut = room_run[0]
    pgm, yml = dut.save(tmp_path / "room")
    assert pgm.read_bytes().startswith(b"P5\n")
    loaded = load_map(yml)
    np.testing.assert_array_equal(loaded.cells, dut.map().cells)
    assert loaded.origin == dut.map().origin


def test_a_featureless_corridor_falls_back_on_odometry_along_it():
    world = helpers.World(15.0, 0.6)  # 30 m long, 1.2 m wide: no end within range
    route = [(4.0, 0.0)]
    dut, truth, odom = run(world, route, (-4.0, 0.0, 0.0), seed=3, scale=0.03, yaw_deg_per_m=1.0)
    estimate = dut.trajectory
    assert np.all(np.isfinite(estimate))
    # Across the corridor and in yaw the walls hold the estimate...
    assert np.abs(estimate[:, 1] - truth[:, 1]).max() < 0.03
    assert np.abs(np.degrees(wrap_angle(estimate[:, 2] - truth[:, 2]))).max() < 0.6
    # ...while along it, it follows the odometry's distance (3 % too long) without exploding.
    along = estimate[-1, 0] - estimate[0, 0]
    odometry_along = math.hypot(*(odom[-1, :2] - odom[0, :2]))
    assert along == pytest.approx(odometry_along, abs=0.1)
    assert abs(odom[-1, 1] - truth[-1, 1]) > 0.1  # the odometry's own heading drifted away
    assert dut.degenerate >= 0.9 * dut.scans


def test_a_corridor_with_doorways_is_matched_along_it():
    # Its surfaces all face across it, as in the featureless one, but the jambs are depth
    # steps (``depth_edges``): the scan, not the odometry (3 % too long), says how far it went.
    world = helpers.doorways()
    route = [(4.0, 0.0)]
    dut, truth, odom = run(world, route, (-4.0, 0.0, 0.0), seed=3, scale=0.03, yaw_deg_per_m=1.0)
    estimate = dut.trajectory
    odometry_along = math.hypot(*(odom[-1, :2] - odom[0, :2]))
    assert odometry_along - 8.0 > 0.2
    error = np.hypot(*(estimate[:, :2] - truth[:, :2]).T)
    # The young map holds the first scans back (0.15 m), then the jambs take over (0.04 to
    # 0.07 m at the end over seeds 3 to 7; following the odometry ends 0.25 m off).
    assert error[-20:].max() < 0.08 and error.max() < 0.2, (error[-20:].max(), error.max())
    assert dut.degenerate <= 0.1 * dut.scans


def test_a_match_beyond_the_gate_keeps_the_prediction():
    world = helpers.room()
    pose = np.array([-2.0, -2.0, 0.3])
    ranges, angles = helpers.lidar_scans(world, [pose, pose], seed=5)
    gated = dc.replace(mut.SlamConfig(), max_correction=0.001, recovery_window=0.0)
    for config, expect_prediction in [(gated, True), (mut.SlamConfig(), False)]:
        dut = mut.ScanMatchingSlam(config, pose)
        dut.update(ranges[0], angles, (0.0, 0.0, 0.0), range_max=3.5)
        # The odometry claims a 5 cm move sideways that did not happen.
        result = dut.update(ranges[1], angles, (0.0, 0.05, 0.0), range_max=3.5)
        prediction = compose(pose, (0.0, 0.05, 0.0))
        if expect_prediction:
            np.testing.assert_allclose(result, prediction)
            assert dut.rejected == 1
        else:
            assert math.hypot(*(result[:2] - pose[:2])) < 0.01 and dut.rejected == 0
        assert dut.last_match is not None


@pytest.mark.parametrize("offset", [(0.4, 0.0, 0.0), (-0.25, 0.3, 0.2)])
def test_a_prediction_beyond_the_gate_is_found_again_by_the_search(offset):
    """Odometry off by more than the gate (0.3 m, 20 degrees) for one scan, as a stale reading
    in a log: the search around the prediction finds the scan's pose; without it the pose stays
    near the wrong prediction."""
    world = helpers.room()
    pose = np.array([-2.0, -2.0, 0.3])
    ranges, angles = helpers.lidar_scans(world, [pose] * 4, seed=5)
    for window in (0.5, 0.0):
        dut = mut.ScanMatchingSlam(dc.replace(mut.SlamConfig(), recovery_window=window), pose)
        for k in range(3):
            dut.update(ranges[k], angles, (0.0, 0.0, 0.0), range_max=3.5)
        result = dut.update(ranges[3], angles, offset, range_max=3.5)
        if window:
            assert math.hypot(*(result[:2] - pose[:2])) < 0.02
            assert abs(result[2] - pose[2]) < math.radians(1.0)
            assert (dut.rejected, dut.recovered) == (0, 1)
        else:  # the prediction stands (rejected), or a wrong fit near it does
            assert math.hypot(*(result[:2] - pose[:2])) > 0.2 and dut.recovered == 0


def test_scans_with_too_few_returns_are_not_matched():
    dut = mut.ScanMatchingSlam(initial_pose=(1.0, 2.0, 0.5))
    angles = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    nothing = np.full(360, np.inf)
    dut.update(nothing, angles, (0.0, 0.0, 0.0), range_max=3.5)
    pose = dut.update(nothing, angles, (0.1, 0.0, 0.0), range_max=3.5)
    np.testing.assert_allclose(pose, compose((1.0, 2.0, 0.5), (0.1, 0.0, 0.0)))
    assert dut.rejected == 1 and dut.last_match is None
    assert (dut.map().cells == 0).sum() > 1000  # no return: free up to range_max


def test_map_update_thresholds():
    angles = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    ranges = helpers.World(2.0, 2.0).cast((0.0, 0.0, 0.0), angles)
    dut = mut.ScanMatchingSlam(dc.replace(mut.SlamConfig(), initial_map_updates=1))
    for _ in range(5):  # standing still: only the first scan goes into the map
        dut.update(ranges, angles, (0.0, 0.0, 0.0), range_max=3.5)
    assert dut.map_updates == 1


def test_the_map_square_can_be_centred_elsewhere_on_the_same_cells():
    """``map_center`` moves the square (to hold a place the start-centred one would miss),
    its cells on the same lattice: the same scans give the same poses, to the rounding of the
    cells' coordinates (which a wall on a cell edge can turn into a few mm)."""
    route = helpers.ROOM_ROUTE[:4]
    centred = run(helpers.room(), route, helpers.ROOM_START, seed=3)[0]
    config = dc.replace(mut.SlamConfig(), map_size=12.0)
    truth = helpers.drive(route, helpers.ROOM_START)
    odom = helpers.drifting_odometry(truth, seed=3)
    sensor = np.array([helpers.compose(pose, X_BASE_SENSOR) for pose in truth])
    ranges, angles = helpers.lidar_scans(helpers.room(), sensor, seed=103)
    dut = mut.ScanMatchingSlam(config, truth[0], X_BASE_SENSOR, map_center=(0.3, -0.2))
    grid, other = dut.grids[dut.map_level], centred.grids[centred.map_level]
    assert grid.log_odds.shape == (240, 240)  # 12 m at 0.05 m
    low = np.array(grid.origin[:2])
    assert np.all(low <= [0.3 - 6.0, -0.2 - 6.0]) and np.all(low + 12.0 >= [0.3 + 5.8, -0.2 + 5.8])
    coarsest = config.resolution * 2 ** (config.levels - 1)
    cells = (low - np.array(other.origin[:2])) / coarsest
    np.testing.assert_allclose(cells, np.round(cells), atol=1e-9)
    for k, (scan, pose) in enumerate(zip(ranges, odom, strict=True)):
        dut.update(scan, angles, pose, range_max=3.5, range_min=0.12, time=0.2 * k)
    error = np.hypot(*(dut.trajectory[:, :2] - truth[:, :2]).T)
    assert math.sqrt(np.mean(error**2)) <= 0.03
    np.testing.assert_allclose(dut.trajectory, centred.trajectory, atol=0.05)
    with pytest.raises(ValueError, match="map_center"):
        mut.ScanMatchingSlam(config, truth[0], map_center=(np.nan, 0.0))


def test_copies_are_independent():
    import copy

    angles = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    ranges = helpers.World(2.0, 2.0).cast((0.0, 0.0, 0.0), angles)
    dut = mut.ScanMatchingSlam(dc.replace(mut.SlamConfig(), initial_map_updates=1))
    dut.update(ranges, angles, (0.0, 0.0, 0.0), range_max=3.5)
    twin = copy.deepcopy(dut)  # as a Drake abstract state is copied
    assert twin.grids[0] is dut.grids[0]  # shared until one of them updates the map
    before = dut.grids[0].log_odds.copy()
    twin.update(ranges, angles, (0.0, 0.0, 0.01), range_max=3.5)  # no map update
    assert twin.grids[0] is dut.grids[0] and twin.map_updates == dut.map_updates
    shifted = helpers.World(2.0, 2.0).cast((0.5, 0.0, 0.0), angles)
    twin.update(shifted, angles, (0.5, 0.0, 0.0), range_max=3.5)
    assert twin.grids[0] is not dut.grids[0] and twin.map_updates == dut.map_updates + 1
    np.testing.assert_array_equal(dut.grids[0].log_odds, before)
    assert twin.scans == 3 and dut.scans == 1
    np.testing.assert_array_equal(dut.trajectory, [[0.0, 0.0, 0.0]])  # the poses are shared
    assert len(twin.times) == 3 and len(dut.times) == 1  # ... but not the lists
    assert not np.array_equal(twin.grids[0].log_odds, dut.grids[0].log_odds)
    np.testing.assert_allclose(twin.pose, (0.5, 0.0, 0.0), atol=0.03)


def test_redraw_draws_the_map_from_the_scans_at_the_poses_given(room_run):
    """The scans the map took, drawn again at their own poses: the same map; at poses moved
    10 cm: the map moves with them; the estimate becomes the pose given."""
    dut, truth, odom = room_run
    config = dc.replace(mut.SlamConfig(), initial_map_updates=1)
    slam = mut.ScanMatchingSlam(config, truth[0], X_BASE_SENSOR)
    world = helpers.room()
    sensor = np.array([helpers.compose(p, X_BASE_SENSOR) for p in truth[:200:20]])
    ranges, angles = helpers.lidar_scans(world, sensor, seed=1)
    kept = []
    for pose, scan in zip(truth[:200:20], ranges, strict=True):
        slam._pose = pose.copy()  # the pose the scan is drawn at
        slam._insert(scan, angles, 3.5, 0.12, np.stack([np.cos(angles), np.sin(angles)], -1))
        kept.append((pose.copy(), *slam.last_insert))
    drawn = slam.map(crop=False).cells.copy()
    updates = slam.map_updates
    slam.redraw(kept, truth[5])
    np.testing.assert_array_equal(slam.map(crop=False).cells, drawn)
    np.testing.assert_array_equal(slam.pose, truth[5])
    assert slam.map_updates == updates  # a redraw is not a map update
    shifted = [(compose(pose, [0.1, 0.0, 0.0]), *rest) for pose, *rest in kept]
    slam.redraw(shifted, truth[5])
    assert (slam.map(crop=False).cells != drawn).any()


def test_a_map_too_small_for_the_place_grows_as_the_robot_goes():
    # A 4 m square centred on the start holds an eighth of the 8 m x 6 m room: the grids grow
    # as the scans reach beyond them, on the same cells, and the SLAM maps the whole room as
    # well as with a square that held it from the start.
    config = dc.replace(mut.SlamConfig(), map_size=4.0)
    dut, truth, _ = run(
        helpers.room(), helpers.ROOM_ROUTE, helpers.ROOM_START, seed=7, config=config
    )
    error = np.hypot(*(dut.trajectory[:, :2] - truth[:, :2]).T)
    assert math.sqrt(np.mean(error**2)) <= 0.05
    result, room = dut.map(), helpers.room().truth(0.05)
    assert occupancy_iou(result, room) >= 0.9 and known_fraction(result, room) >= 0.95
    grid = dut.grids[dut.map_level]
    assert grid.shape[0] * 0.05 >= 6.0 and grid.shape[1] * 0.05 >= 8.0
    coarsest = dut.grids[-1].resolution
    for each in dut.grids:
        assert each.origin == dut.grids[-1].origin
        assert each.shape[1] * each.resolution == pytest.approx(dut.grids[-1].shape[1] * coarsest)
    held = room_run_with(7)[0]  # the default 30 m square
    np.testing.assert_allclose(dut.trajectory[:, :2], held.trajectory[:, :2], atol=0.05)
