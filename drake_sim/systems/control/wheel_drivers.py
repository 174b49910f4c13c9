"""The two wheels' motor drivers for the flip controller: one command for both wheels.

The flip controller's single torque goes to both wheels. Each driver adds a synchronising term
that pushes its wheel towards the mean wheel speed, so that, as the mission asks, both wheels
turn at the same speed: a wheel that loses grip (on landing from a flip, say) does not spin
away from the other and turn the robot. The common torque is unchanged by it:

    tau_i = sat(tau + k (mean(w) - w_i), max_torque),   i = left, right

Drake C++ primitives only, since it is evaluated at every plant step.
"""

import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import Adder, MatrixGain, Saturation

from drake_sim.robots.ddrive_params import RobotParams
from drake_sim.systems.control.diff_drive_controller import wheel_loop_gain


def make_wheel_drivers(robot: RobotParams, *, sync_response_time: float) -> Diagram:
    """Builds the drivers.

    Ports:
        torque_command (input): the one torque for both wheels, N m.
        wheel_state (input): [q_left, q_right, v_left, v_right] (rad, rad/s).
        wheel_torques (output): [left, right], N m, each within the motor's maximum.

    Args:
        robot: the robot (motor limit, and the gain of the synchronising loop).
        sync_response_time: time constant of the synchronising loop, s.
    """
    k = wheel_loop_gain(robot, sync_response_time)
    sync = k * np.array([[0.0, 0.0, -0.5, 0.5], [0.0, 0.0, 0.5, -0.5]])
    limit = np.full(2, robot.motor.max_torque)
    builder = DiagramBuilder()
    fan_out = builder.AddNamedSystem("fan_out", MatrixGain(np.ones((2, 1))))
    synchronise = builder.AddNamedSystem("synchronise", MatrixGain(sync))
    total = builder.AddNamedSystem("total", Adder(2, 2))
    saturate = builder.AddNamedSystem("saturate", Saturation(-limit, limit))
    builder.ExportInput(fan_out.get_input_port(), "torque_command")
    builder.ExportInput(synchronise.get_input_port(), "wheel_state")
    builder.Connect(fan_out.get_output_port(), total.get_input_port(0))
    builder.Connect(synchronise.get_output_port(), total.get_input_port(1))
    builder.Connect(total.get_output_port(), saturate.get_input_port())
    builder.ExportOutput(saturate.get_output_port(), "wheel_torques")
    diagram = builder.Build()
    diagram.set_name("wheel_drivers")
    return diagram
