"""Offline SLAM over a recorded log: the trajectory follows the truth, odometry jumps are
bridged, a stop ends the run with what it has, the map is sized to the log."""

import dataclasses as dc

import numpy as np

from drake_sim.systems.estimation import log_slam as mut
from drake_sim.systems.estimation.occupancy_grid import known_fraction
from drake_sim.systems.estimation.slam_config import SlamConfig
from tests import log_helpers as lh
from tests import slam_helpers as sh


def test_the_trajectory_follows_the_truth_where_the_odometry_drifts():
    truth, odometry, ranges, angles = lh.room_drive()
    log = lh.laser_log(truth, odometry, ranges, angles)
    result = mut.run_log_slam(log, SlamConfig())
    assert result.scans == len(truth) and not result.stopped and result.odometry_jumps == 0
    np.testing.assert_allclose(result.times, [s.time for s in log.scans])
    assert lh.rmse(result.poses, truth) < 0.03
    assert lh.rmse(odometry, truth) > 2 * lh.rmse(result.poses, truth)  # the drift removed


def test_an_odometry_jump_is_bridged_by_the_scan_matcher():
    truth, odometry, ranges, angles = lh.room_drive()
    jumped = odometry.copy()
    jumped[100:, :2] += [1.5, -0.8]  # the log's odometry leaps once, as MIT CSAIL's does
    result = mut.run_log_slam(lh.laser_log(truth, jumped, ranges, angles), SlamConfig())
    assert result.odometry_jumps == 1
    assert lh.rmse(result.poses, truth) < 0.03


def test_loop_closure_brings_back_a_pose_the_matcher_lost():
    """The whole room route with the odometry stepping 0.5 m sideways at once, within the
    jump rule's 0.5 m (so matched from the step only) and beyond the matcher's 0.3 m gate,
    with no search after the rejected match: the matcher alone stays off; with loop closure
    the end is found again."""
    truth, odometry, ranges, angles = lh.room_drive(sh.ROOM_ROUTE)
    odometry[400:, 1] += 0.45
    log = lh.laser_log(truth, odometry, ranges, angles)
    blind = SlamConfig(recovery_window=0.0)  # no search after a rejected match
    plain = mut.run_log_slam(log, blind)
    loops = dc.replace(blind.loop_closure, enabled=True)
    closed = mut.run_log_slam(log, dc.replace(blind, loop_closure=loops))
    assert plain.loop_closures == 0 and closed.loop_closures >= 1
    end = slice(-50, None)
    assert lh.rmse(plain.poses[end], truth[end]) > 0.3
    assert lh.rmse(closed.poses[end], truth[end]) < 0.03
    assert lh.rmse(closed.poses, truth) < 0.5 * lh.rmse(plain.poses, truth)


def test_a_real_move_across_a_gap_in_the_log_is_kept():
    truth, odometry, ranges, angles = lh.room_drive()
    # 16 scans missing on a straight stretch: the odometry steps 0.6 m at once.
    moves = np.hypot(*(truth[56:, :2] - truth[40:-16, :2]).T)
    gap = 40 + int(np.argmax(moves > 0.55))
    keep = np.r_[0 : gap + 1, gap + 16 : len(truth)]
    assert np.hypot(*(truth[gap + 16, :2] - truth[gap, :2])) > 0.55
    log = lh.laser_log(truth[keep], odometry[keep], ranges[keep], angles)
    result = mut.run_log_slam(log, SlamConfig())
    assert result.odometry_jumps == 0
    assert lh.rmse(result.poses, truth[keep]) < 0.03


def test_scans_before_the_first_odometry_predict_no_motion():
    truth, odometry, ranges, angles = lh.room_drive()
    log = lh.laser_log(truth, odometry, ranges, angles)
    scans = [dc.replace(s, odometry=None) if k < 3 else s for k, s in enumerate(log.scans)]
    result = mut.run_log_slam(dc.replace(log, scans=scans), SlamConfig())
    assert result.scans == len(truth)
    # The map's frame starts at the first odometry (the fourth scan's): compare the shapes.
    shifted = result.poses - result.poses[0] + truth[0]
    assert lh.rmse(shifted, truth) < 0.03


def test_a_stop_ends_the_run_with_the_scans_so_far():
    truth, odometry, ranges, angles = lh.room_drive()
    log = lh.laser_log(truth, odometry, ranges, angles)
    calls = []
    result = mut.run_log_slam(
        log, SlamConfig(), should_stop=lambda: len(calls.append(0) or calls) > 40
    )
    assert result.stopped and result.scans == 40
    assert len(result.poses) == len(result.times) == 40


def test_the_map_is_sized_to_the_log():
    truth, odometry, ranges, angles = lh.room_drive()
    log = lh.laser_log(truth, odometry, ranges, angles)
    assert mut.map_side(log, SlamConfig()) == 30.0  # a small room: the config's size
    far = [dc.replace(s, odometry=s.odometry * [20.0, 20.0, 1.0]) for s in log.scans]
    side = mut.map_side(dc.replace(log, scans=far), SlamConfig())
    extent = np.ptp(odometry[:, :2] * 20.0, axis=0).max()
    assert side >= extent + 2 * 3.0 and side % mut.MAP_SIDE_STEP == 0


def test_a_log_that_starts_at_one_end_of_a_corridor_maps_the_far_end():
    # The map starts centred on the first pose, sized to the odometry's extent (a 40 m square
    # here, reaching 6 m past the middle of a 30 m corridor driven end to end): it grows as the
    # scans reach beyond it, on the same cells, so the SLAM tracks and maps the far end exactly
    # as with a square that held the whole corridor from the start.
    world = sh.doorways()
    truth = sh.drive([(14.0, 0.0)], (-14.0, 0.0, 0.0))
    odometry = sh.drifting_odometry(truth, seed=1)
    ranges, angles = sh.lidar_scans(world, truth, seed=1, range_max=lh.RANGE_MAX)
    log = lh.laser_log(truth, odometry, ranges, angles)
    assert mut.map_side(log, SlamConfig()) == 40.0
    result = mut.run_log_slam(log, SlamConfig())
    held = mut.run_log_slam(log, dc.replace(SlamConfig(), map_size=80.0))
    np.testing.assert_allclose(result.poses, held.poses, atol=1e-9)
    assert lh.rmse(result.poses, truth) < 0.1 < lh.rmse(odometry, truth)
    occupancy = result.slam.map()
    assert occupancy.origin[0] + occupancy.width_m > 15.0  # the corridor's far end wall
    assert np.array_equal(occupancy.cells, held.slam.map().cells)
    assert known_fraction(occupancy, world.truth(0.05)) > 0.5
