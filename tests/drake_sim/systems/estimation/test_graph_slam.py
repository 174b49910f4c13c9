"""drake_sim.systems.estimation.graph_slam: the scan matcher with a pose graph; a pose knocked
half a metre off (an odometry jump the matcher's gate refuses) comes back when the robot
returns to where it has been, the map is drawn again from the closed loop, and with loop
closure off nothing changes."""

import dataclasses as dc
import functools

import numpy as np
import pytest

import drake_sim.systems.estimation.graph_slam as mut
from drake_sim.systems.estimation.loop_closure import LoopClosureConfig
from drake_sim.systems.estimation.occupancy_grid import occupancy_iou
from drake_sim.systems.estimation.scan_matching_slam import ScanMatchingSlam
from drake_sim.systems.estimation.slam_config import SlamConfig
from tests import slam_helpers as helpers

JUMP_SCAN = 400  # where the odometry jumps ...
JUMP = np.array([0.0, 0.5, 0.0])  # ... this far sideways (m, in its own frame)


@functools.cache
def drive(seed=3):
    """(truth, odometry with a jump, ranges, angles) of the room's whole route."""
    truth = helpers.drive(helpers.ROOM_ROUTE, helpers.ROOM_START)
    odometry = helpers.drifting_odometry(truth, seed=seed)
    odometry[JUMP_SCAN:, :2] += JUMP[:2]
    ranges, angles = helpers.lidar_scans(helpers.room(), truth, seed=seed + 100)
    return truth, odometry, ranges, angles


@functools.cache
def run(enabled: bool):
    truth, odometry, ranges, angles = drive()
    # No search after a rejected match (it finds the jump at once: test_scan_matching_slam):
    # the matcher loses the pose, for the loop closure to bring back.
    config = SlamConfig(recovery_window=0.0, loop_closure=LoopClosureConfig(enabled=enabled))
    dut = mut.make_slam(config, truth[0])
    for k, (scan, odom) in enumerate(zip(ranges, odometry, strict=True)):
        dut.update(scan, angles, odom, range_max=3.5, range_min=0.12, time=0.2 * k)
    if enabled:
        dut.finish()
    return dut


def errors(dut):
    truth = drive()[0]
    return np.hypot(*(dut.trajectory[:, :2] - truth[:, :2]).T)


def test_make_slam_gives_the_plain_matcher_with_loop_closure_off():
    assert type(run(False)) is ScanMatchingSlam
    assert type(run(True)) is mut.GraphSlam


def test_a_pose_knocked_off_comes_back_when_the_loop_closes():
    plain, graph = run(False), run(True)
    truth = drive()[0]
    assert len(truth) > JUMP_SCAN + 50
    # the jump beat the plain matcher: it stays off to the end
    assert errors(plain)[-20:].min() > 0.3
    # with loop closure: found, and the end is back where it belongs
    assert graph.loop_closures >= 1 and graph.redraws >= 1
    assert errors(graph)[-20:].max() < 0.05
    assert errors(graph)[:JUMP_SCAN].max() < 0.05  # what was right stays right
    # the correction went where the matcher had only the odometry (``unmatched_sigma``)
    assert errors(graph)[JUMP_SCAN + 20 :].max() < 0.1
    assert graph.trajectory.shape == truth.shape and graph.scans == len(truth)


def test_the_map_is_drawn_again_from_the_closed_loop():
    truth_map = helpers.room().truth(0.05)
    plain, graph = run(False), run(True)
    iou_plain = occupancy_iou(plain.map(), truth_map)
    iou_graph = occupancy_iou(graph.map(), truth_map)
    assert iou_graph > iou_plain + 0.15 and iou_graph > 0.75, (iou_plain, iou_graph)


def test_with_nothing_to_close_the_graph_keeps_the_matchers_trajectory():
    """A drive shorter than ``min_travel``: no closure, the same poses as the matcher's."""
    truth, odometry, ranges, angles = drive()
    config = dc.replace(SlamConfig(), loop_closure=LoopClosureConfig(enabled=True))
    dut = mut.GraphSlam(config, truth[0])
    plain = ScanMatchingSlam(SlamConfig(), truth[0])
    for k in range(60):
        for slam in (dut, plain):
            slam.update(ranges[k], angles, odometry[k], range_max=3.5, range_min=0.12)
    dut.finish()
    assert dut.loop_closures == 0 and len(dut.graph) == plain.map_updates
    np.testing.assert_allclose(dut.trajectory, plain.trajectory, atol=1e-12)
    np.testing.assert_array_equal(dut.map().cells, plain.map().cells)


def test_bad_loop_closure_settings_are_refused():
    from drake_sim.base.errors import ConfigError

    for key, value, words in [
        ("min_travel", 0.0, "min_travel"),
        ("attempt_every", 0, "attempt_every"),
        ("min_score", 1.5, "min_score"),
        ("closure_sigma", [0.1, 0.1], "closure_sigma"),
        ("loss", "tukey", "loss"),
    ]:
        config = dc.replace(SlamConfig(), loop_closure=LoopClosureConfig(**{key: value}))
        with pytest.raises(ConfigError, match=words):
            mut.make_slam(config)
