"""Differential-drive velocity control: a ``cmd_vel`` in, wheel torques out.

The robot is any object with the attributes read here (``RobotParams``, ``WalleParams``,
``Turtlebot3Params``): ``wheel.radius``, ``wheel.mass`` (m, kg), ``wheel_separation`` (m),
``total_mass`` (kg) and ``motor.max_torque`` (N m, per wheel).
"""

import dataclasses as dc

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem

from drake_sim.robots.ddrive_params import RobotParams
from drake_sim.systems.axle import up_sign
from drake_sim.systems.sensors.imu import IMU_SIZE, rotation_from_imu


@dc.dataclass
class DiffDriveConfig:
    """Limits and loop shape of the diff-drive controller (like Gazebo's diff-drive plugin)."""

    rate: float = 200.0  # Hz, control rate.
    max_linear_velocity: float = 1.0  # m/s.
    max_angular_velocity: float = 4.0  # rad/s.
    max_linear_acceleration: float = 2.0  # m/s^2.
    max_angular_acceleration: float = 10.0  # rad/s^2.
    # Time constant of each wheel's velocity loop, s; the gain is derived from the robot's mass
    # and wheel inertia, so the response is the same for any robot size.
    response_time: float = 0.05
    integral_time: float = 0.5  # s, PI integral time (0 disables the integral term).


def wheel_loop_gain(robot: RobotParams, response_time: float) -> float:
    """Proportional gain (N m per rad/s) of a wheel velocity loop with time constant
    ``response_time``: the wheel's inertia plus its share of the robot's mass seen through the
    wheel radius, divided by the time constant."""
    r = robot.wheel.radius
    wheel_inertia = 0.5 * robot.wheel.mass * r**2
    return (wheel_inertia + 0.5 * robot.total_mass * r**2) / response_time


def wheel_speed_targets(v: float, omega: float, robot: RobotParams, sign: float = 1.0):
    """Left and right wheel joint rates (rad/s) for a body-frame twist (v m/s, omega rad/s).

    ``sign`` is +1 upright, -1 upside down: upside down the body's x axis is reversed relative to
    the wheel joints' positive rolling direction, so the same body-frame command needs the
    opposite joint rates.
    """
    half = 0.5 * robot.wheel_separation
    r = robot.wheel.radius
    return sign * (v - omega * half) / r, sign * (v + omega * half) / r


# Layout of the controller's discrete state.
_REF = slice(0, 2)  # Rate-limited (v, omega).
_INTEGRAL = slice(2, 4)  # Integral of the left and right wheel speed errors, rad.
_TORQUE = slice(4, 6)  # Wheel torques, N m.


class DiffDriveController(LeafSystem):
    """Per-wheel PI velocity loops tracking a body-frame (v, omega) command, saturated at the
    motors' maximum torque, with velocity and acceleration limits on the command.

    .. pydrake_system::

        name: DiffDriveController
        input_ports:
        - command
        - wheel_state
        - imu
        output_ports:
        - wheel_torques

    ``command`` is ``[v, omega]`` in the body frame (m/s, rad/s), ROS's ``cmd_vel``;
    ``wheel_state`` is ``[q_left, q_right, v_left, v_right]``; ``imu`` the ``Imu`` output (only
    its orientation is used, to drive the same way upside down); a robot that cannot turn over
    (``upside_down_aware=False``) has no ``imu`` input and is always taken upright.
    ``wheel_torques`` is ``[left, right]`` in N m, held between control updates.
    """

    def __init__(
        self, *, robot: RobotParams, config: DiffDriveConfig, upside_down_aware: bool = True
    ):
        super().__init__()
        self._robot = robot
        self._config = config
        self._dt = 1.0 / config.rate
        self._kp = wheel_loop_gain(robot, config.response_time)
        self._ki = self._kp / config.integral_time if config.integral_time > 0 else 0.0
        self._max_torque = robot.motor.max_torque
        self._command = self.DeclareVectorInputPort("command", 2)
        self._wheels = self.DeclareVectorInputPort("wheel_state", 4)
        self._imu = self.DeclareVectorInputPort("imu", IMU_SIZE) if upside_down_aware else None
        self._state = self.DeclareDiscreteState(6)
        self.DeclarePeriodicDiscreteUpdateEvent(self._dt, 0.0, self._update)
        self.DeclareVectorOutputPort(
            "wheel_torques",
            BasicVector(2),
            lambda context, out: out.SetFromVector(
                context.get_discrete_state(self._state).value()[_TORQUE]
            ),
            {self.discrete_state_ticket(self._state)},
        )

    def _update(self, context, discrete_state):
        c, dt = self._config, self._dt
        x = np.array(context.get_discrete_state(self._state).value())
        v_cmd, w_cmd = self._command.Eval(context)
        if not (np.isfinite(v_cmd) and np.isfinite(w_cmd)):
            v_cmd, w_cmd = 0.0, 0.0  # A NaN command stops the robot rather than poisoning it.
        v_cmd = np.clip(v_cmd, -c.max_linear_velocity, c.max_linear_velocity)
        w_cmd = np.clip(w_cmd, -c.max_angular_velocity, c.max_angular_velocity)
        v_ref, w_ref = x[_REF]
        v_ref += np.clip(
            v_cmd - v_ref, -c.max_linear_acceleration * dt, c.max_linear_acceleration * dt
        )
        w_ref += np.clip(
            w_cmd - w_ref, -c.max_angular_acceleration * dt, c.max_angular_acceleration * dt
        )
        sign = 1.0 if self._imu is None else up_sign(rotation_from_imu(self._imu.Eval(context)))
        target = np.array(wheel_speed_targets(v_ref, w_ref, self._robot, sign))
        error = target - self._wheels.Eval(context)[2:4]
        integral = x[_INTEGRAL] + error * dt
        torque = self._kp * error + self._ki * integral
        saturated = np.abs(torque) > self._max_torque
        integral[saturated] = x[_INTEGRAL][saturated]  # Anti-windup: hold while saturated.
        x[_REF] = v_ref, w_ref
        x[_INTEGRAL] = integral
        x[_TORQUE] = np.clip(torque, -self._max_torque, self._max_torque)
        discrete_state.set_value(self._state, x)
