"""The line follower (drake_sim.systems.control.line_follower) on fixed measurements."""

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.analysis import Simulator

import drake_sim.systems.control.line_follower as mut
from drake_sim.base.errors import ConfigError
from drake_sim.systems.perception.line_detection import (
    LineDetectorConfig,
    LineMeasurement,
    camera_pose_over_ground,
    detect_line,
)
from drake_sim.systems.perception.line_detector import measurement_vector
from drake_sim.systems.sensors.camera import camera_info
from drake_sim.worlds.course import load_course, shipped_courses
from tests.line_camera_helpers import CAMERA, X_BC, make_scene

CONFIG = mut.LineFollowerConfig()
LOST = measurement_vector(LineMeasurement(False))
DETECT = LineDetectorConfig()


def _seen(offset=0.0, heading=0.0, curvature=0.0) -> np.ndarray:
    return measurement_vector(LineMeasurement(True, offset, heading, curvature, 0.1))


class Follower:
    """The system with its measurement input fixed, advanced in simulated time."""

    def __init__(self, config=CONFIG):
        self.dut = mut.LineFollower(config=config)
        self.simulator = Simulator(self.dut)
        self.context = self.simulator.get_mutable_context()

    def run(self, measurement, seconds: float):
        self.dut.GetInputPort("measurement").FixValue(self.context, measurement)
        self.simulator.AdvanceTo(self.context.get_time() + seconds)
        return self

    @property
    def command(self) -> np.ndarray:
        return self.dut.GetOutputPort("command").Eval(self.context)

    @property
    def mode(self) -> int:
        return int(self.dut.GetOutputPort("mode").Eval(self.context)[0])


def test_on_a_straight_it_cruises_and_steers_towards_the_line():
    assert mut.follow_command(_seen(), CONFIG) == (CONFIG.speed, 0.0)
    v, omega = mut.follow_command(_seen(offset=0.02), CONFIG)  # line on the left
    assert omega == pytest.approx(CONFIG.offset_gain * 0.02) and v < CONFIG.speed
    _, omega = mut.follow_command(_seen(offset=-0.02), CONFIG)
    assert omega < 0
    _, omega = mut.follow_command(_seen(heading=0.1), CONFIG)  # line turning away left
    assert omega == pytest.approx(CONFIG.heading_gain * 0.1)
    _, omega = mut.follow_command(_seen(offset=0.5, heading=1.0), CONFIG)
    assert omega == CONFIG.max_omega


def test_it_slows_down_in_tight_turns_and_when_far_off():
    v_wide, omega_wide = mut.follow_command(_seen(curvature=1 / 0.6), CONFIG)
    v_tight, omega_tight = mut.follow_command(_seen(curvature=1 / 0.25), CONFIG)
    assert v_wide == pytest.approx(
        min(CONFIG.speed, math.sqrt(CONFIG.max_lateral_acceleration * 0.6))
    )
    assert v_tight == pytest.approx(math.sqrt(CONFIG.max_lateral_acceleration * 0.25))
    assert v_tight < v_wide <= CONFIG.speed
    assert omega_tight == pytest.approx(v_tight * 4.0)  # feed-forward: it follows the arc
    v_right, omega_right = mut.follow_command(_seen(curvature=-1 / 0.25), CONFIG)
    assert (v_right, omega_right) == pytest.approx((v_tight, -omega_tight))
    v_turned, _ = mut.follow_command(_seen(heading=0.5), CONFIG)
    assert v_turned == pytest.approx(CONFIG.speed * 0.5)
    v_off, _ = mut.follow_command(_seen(offset=-0.3), CONFIG)
    assert v_off == CONFIG.min_speed


def test_the_speed_ramps_up_at_the_acceleration_limit():
    follower = Follower().run(_seen(), 0.2)
    assert follower.mode == mut.FOLLOW
    assert follower.command[0] == pytest.approx(CONFIG.max_acceleration * 0.2, abs=0.011)
    follower.run(_seen(), 1.0)
    np.testing.assert_allclose(follower.command, [CONFIG.speed, 0.0])


def test_a_short_dropout_keeps_the_turn_and_slows_down():
    follower = Follower().run(_seen(curvature=2.0), 1.0)
    v, omega = follower.command
    follower.run(LOST, 0.6 * CONFIG.lost_delay)
    assert follower.mode == mut.FOLLOW
    assert follower.command[1] == omega and follower.command[0] < v


@pytest.mark.parametrize("offset, heading, side", [(0.02, 0.1, 1), (-0.01, -0.2, -1)])
def test_lost_it_stops_and_turns_towards_where_the_line_was(offset, heading, side):
    follower = Follower().run(_seen(offset, heading), 1.0)
    follower.run(LOST, CONFIG.lost_delay + 0.05)
    assert follower.mode == mut.SEARCH
    assert follower.command[1] == side * CONFIG.search_omega
    follower.run(LOST, 1.0)
    np.testing.assert_allclose(follower.command, [0.0, side * CONFIG.search_omega])
    follower.run(_seen(), 0.05)  # found again
    assert follower.mode == mut.FOLLOW and follower.command[1] == 0.0


def test_after_a_full_turn_without_the_line_it_stops_and_waits():
    follower = Follower().run(_seen(), 0.5)
    search_time = CONFIG.search_turn / CONFIG.search_omega
    follower.run(LOST, CONFIG.lost_delay + 0.95 * search_time)
    assert follower.mode == mut.SEARCH
    follower.run(LOST, 0.1 * search_time)
    assert follower.mode == mut.STOPPED
    np.testing.assert_allclose(follower.command, [0.0, 0.0])
    follower.run(LOST, 10.0)
    assert follower.mode == mut.STOPPED
    follower.run(_seen(offset=0.05), 0.05)
    assert follower.mode == mut.FOLLOW and follower.command[1] > 0


def test_with_no_line_from_the_start_it_never_drives():
    follower = Follower()
    speeds = []
    for _ in range(70):
        speeds.append(follower.run(LOST, 0.1).command[0])
    assert max(np.abs(speeds)) == 0.0
    assert follower.mode == mut.STOPPED


@pytest.mark.parametrize(
    "change, match",
    [
        ({"speed": 0.0}, "'speed' must be positive"),
        ({"heading_gain": math.nan}, "'heading_gain' must be positive"),
        ({"min_speed": 1.0}, "'min_speed' must be at most 'speed'"),
    ],
)
def test_bad_gains_are_rejected(change, match):
    with pytest.raises(ConfigError, match=match):
        mut.LineFollower(config=dc.replace(CONFIG, **change))


def _drive(course_file, start_s: float, seconds: float):
    """A kinematic unicycle with the camera, detector and follower in the loop, from the
    line at ``start_s``: the camera's frames (20 Hz), the follower's updates (50 Hz) and the
    unicycle's motion between them. Returns the scene and per-frame (distance from the line,
    arc length, mode)."""
    scene = make_scene(load_course(course_file))
    follower = Follower()
    p_WB, yaw = scene.line.pose_at(start_s)
    trace = []
    steps = round(CONFIG.rate / CAMERA.rate)
    for _ in range(round(seconds * CAMERA.rate)):
        X_WB = RigidTransform(RotationMatrix.MakeZRotation(yaw), [*p_WB, 0.0])
        image = scene.render(X_WB)
        m = detect_line(image, camera_info(CAMERA), camera_pose_over_ground(X_WB, X_BC), DETECT)
        for _ in range(steps):
            v, omega = follower.run(measurement_vector(m), 1.0 / CONFIG.rate).command
            p_WB = p_WB + v / CONFIG.rate * np.array([math.cos(yaw), math.sin(yaw)])
            yaw += omega / CONFIG.rate
        projection = scene.line.project(p_WB)
        trace.append((projection.distance, projection.s, follower.mode))
    return scene, np.array(trace)


def test_in_the_loop_it_follows_the_tight_chicane():
    """From the straight before the chicane of ``tight.yaml`` (0.3 m left turns, 0.25 m right
    turns): through it, never more than 2 cm from the line, slowing down in the turns."""
    _, trace = _drive(shipped_courses()[2], 3.25, 12.5)
    assert np.all(trace[:, 2] == mut.FOLLOW)
    assert np.max(trace[:, 0]) < 0.02
    assert trace[-1, 1] > 4.92  # past the chicane's right turns (3.91 m to 4.90 m)
    speeds = np.diff(trace[:, 1]) * CAMERA.rate
    limit = math.sqrt(CONFIG.max_lateral_acceleration * 0.3)  # 0.17 m/s in its widest turns
    assert np.median(speeds) < limit < 0.6 * CONFIG.speed


def test_in_the_loop_it_stops_at_the_end_of_an_open_path():
    """Near the end of ``s_bend.yaml``: it reaches the end, loses the line, stops and turns in
    place, finds the line behind it and follows it back; never more than 8 cm off the end."""
    scene, trace = _drive(shipped_courses()[1], 3.6, 8.0)
    assert np.max(trace[:, 1]) > scene.line.length - 0.01  # it got to the end
    assert np.max(trace[:, 0]) < 0.08  # without driving on
    searching = np.flatnonzero(trace[:, 2] == mut.SEARCH)
    assert len(searching) > 0 and trace[-1, 2] == mut.FOLLOW
    assert trace[-1, 1] < scene.line.length - 0.05  # on its way back


@pytest.mark.slow
@pytest.mark.parametrize("index, seconds", [(0, 32.0), (2, 45.0)])
def test_in_the_loop_it_laps_the_closed_courses(index, seconds):
    """A whole lap of ``oval.yaml`` and of ``tight.yaml``, never more than 2 cm off the line."""
    scene, trace = _drive(shipped_courses()[index], 0.0, seconds)
    travelled = sum(
        scene.line.advance(a, b) for a, b in zip(trace[:-1, 1], trace[1:, 1], strict=True)
    )
    assert travelled > scene.line.length
    assert np.max(trace[:, 0]) < 0.02 and np.all(trace[:, 2] == mut.FOLLOW)
