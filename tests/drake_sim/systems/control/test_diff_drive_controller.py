"""The cmd_vel controller (drake_sim.systems.control.diff_drive_controller)."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

import drake_sim.systems.control.diff_drive_controller as mut
from tests.flip_helpers import default_robot, flip_scenario, run_for

UPRIGHT = np.r_[1.0, 0, 0, 0, np.zeros(6)]
UPSIDE_DOWN = np.r_[0.0, 1.0, 0, 0, np.zeros(6)]  # Turned over about x.


def _torques_after(command, imu=UPRIGHT, seconds=1.0, wheel_rates=(0.0, 0.0)):
    robot = default_robot()
    dut = mut.DiffDriveController(robot=robot, config=mut.DiffDriveConfig())
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    dut.GetInputPort("command").FixValue(context, command)
    dut.GetInputPort("wheel_state").FixValue(context, np.r_[0.0, 0.0, wheel_rates])
    dut.GetInputPort("imu").FixValue(context, imu)
    simulator.AdvanceTo(seconds)
    return dut.GetOutputPort("wheel_torques").Eval(context), robot


def test_torques_saturate_and_stay_equal():
    """Full speed ahead from standstill: both wheels get exactly the motors' maximum torque."""
    torques, robot = _torques_after([5.0, 0.0])
    np.testing.assert_array_equal(torques, [robot.motor.max_torque] * 2)


def test_turning_saturates_opposite():
    torques, robot = _torques_after([0.0, 50.0])
    np.testing.assert_array_equal(torques, [-robot.motor.max_torque, robot.motor.max_torque])


def test_upside_down_reverses_the_wheels():
    upright, _ = _torques_after([0.3, 0.5], seconds=0.05)
    flipped, _ = _torques_after([0.3, 0.5], imu=UPSIDE_DOWN, seconds=0.05)
    np.testing.assert_allclose(flipped, -upright)


def test_a_robot_that_cannot_turn_over_needs_no_imu():
    """upside_down_aware=False: no imu input, and the torques of an upright robot."""
    robot = default_robot()
    dut = mut.DiffDriveController(
        robot=robot, config=mut.DiffDriveConfig(), upside_down_aware=False
    )
    assert not dut.HasInputPort("imu")
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    dut.GetInputPort("command").FixValue(context, [0.3, 0.5])
    dut.GetInputPort("wheel_state").FixValue(context, np.zeros(4))
    simulator.AdvanceTo(0.05)
    upright, _ = _torques_after([0.3, 0.5], seconds=0.05)
    np.testing.assert_array_equal(dut.GetOutputPort("wheel_torques").Eval(context), upright)


def test_nan_command_stops():
    torques, _ = _torques_after([np.nan, 1.0])
    np.testing.assert_array_equal(torques, [0.0, 0.0])


def test_limits_and_gain_follow_the_robot():
    robot = default_robot()
    big = robot.scaled(length=1.25, mass=1.5)
    assert mut.wheel_loop_gain(big, 0.05) > mut.wheel_loop_gain(robot, 0.05)
    left, right = mut.wheel_speed_targets(1.0, 0.0, robot)
    assert left == right == pytest.approx(1.0 / robot.wheel.radius)
    left, right = mut.wheel_speed_targets(0.0, 1.0, robot, sign=-1.0)
    assert left == pytest.approx(robot.wheel_separation / 2 / robot.wheel.radius)
    assert right == -left


def _true_speed_and_yaw_rate(run, after):
    log = run.log("true_pose")
    t, pose = log.sample_times(), log.data()
    keep = t >= after
    t, pose = t[keep], pose[:, keep]
    speed = np.linalg.norm(pose[:2, -1] - pose[:2, 0]) / (t[-1] - t[0])
    yaw_rate = np.unwrap(pose[2])[-1] - np.unwrap(pose[2])[0]
    return speed, yaw_rate / (t[-1] - t[0])


def test_drives_straight_at_the_commanded_speed():
    run = run_for(3.0, controller="cmd_vel", cmd_vel=[0.5, 0.0])
    speed, yaw_rate = _true_speed_and_yaw_rate(run, after=1.0)
    assert speed == pytest.approx(0.5, abs=0.01)
    assert abs(yaw_rate) < 0.01
    assert run.report().max_lateral_deviation_m < 0.005


@pytest.mark.parametrize("upside_down", [False, True], ids=["upright", "upside-down"])
def test_turns_in_place(upside_down):
    """The same body-frame command turns the robot about its own z axis either way up; upside
    down that axis points down, so the world sees the opposite turn."""
    scenario = flip_scenario(upside_down=upside_down)
    run = run_for(3.0, scenario=scenario, controller="cmd_vel", cmd_vel=[0.0, 1.0])
    speed, yaw_rate = _true_speed_and_yaw_rate(run, after=1.0)
    assert speed < 0.02
    assert yaw_rate == pytest.approx(-1.0 if upside_down else 1.0, abs=0.05)
