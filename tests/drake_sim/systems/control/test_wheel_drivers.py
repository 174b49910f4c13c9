"""The flip controller's wheel drivers (drake_sim.systems.control.wheel_drivers)."""

import numpy as np
import pytest

import drake_sim.systems.control.wheel_drivers as mut
from drake_sim.systems.control.diff_drive_controller import wheel_loop_gain
from tests.flip_helpers import default_robot


def _torques(command, rates):
    robot = default_robot()
    dut = mut.make_wheel_drivers(robot, sync_response_time=0.05)
    context = dut.CreateDefaultContext()
    dut.GetInputPort("torque_command").FixValue(context, [command])
    dut.GetInputPort("wheel_state").FixValue(context, np.r_[0.0, 0.0, rates])
    return dut.GetOutputPort("wheel_torques").Eval(context), robot


def test_equal_speeds_get_the_command():
    torques, _ = _torques(1.5, [3.0, 3.0])
    np.testing.assert_allclose(torques, [1.5, 1.5])


def test_a_faster_wheel_is_held_back_and_the_sum_is_kept():
    torques, robot = _torques(1.0, [4.0, 2.0])
    k = wheel_loop_gain(robot, 0.05)
    np.testing.assert_allclose(torques, [1.0 - k, 1.0 + k])
    assert torques.sum() == pytest.approx(2.0)


def test_saturates_at_the_motor_limit():
    torques, robot = _torques(100.0, [0.0, 0.0])
    np.testing.assert_allclose(torques, [robot.motor.max_torque] * 2)
