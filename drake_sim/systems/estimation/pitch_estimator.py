"""The body's pitch from an IMU: a complementary filter of the gyroscope and the accelerometer.

The gyro's pitch rate, integrated, is right over short times but drifts with its bias; the
accelerometer's direction of gravity is right on average but is disturbed by every
acceleration of the robot. The filter

    theta_dot_hat = omega_y + (theta_acc - theta_hat) / T

trusts the gyro for changes faster than the time constant T and the accelerometer for slower
ones. A balancing robot accelerates hard to catch itself, and its accelerometer then reads
that acceleration as a lean (``-a / g`` rad). The filter removes it: the axle's acceleration
``a``, from the wheel encoders and the gyro, is taken out of the measured specific force
before the angle of gravity is read (the IMU sits on the axle, so nothing else moves it).
Measured on Wall-E, this is what makes balancing work: without it the robot rocks by 6
degrees instead of 0.2. While the wheels slip or leave the floor the accelerometer reads
neither, and is ignored (``gate``). At start-up the first readings are averaged (the blend
starts at 1 and falls to its steady value, as a Kalman filter's gain would), so a robot
released at a lean knows it within a sample.

Pitch is the rotation about the body's y axis (the axle), positive when the body leans
forward (its z axis tilts towards +x), as in ``drake_sim.robots.walle``.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem

from drake_sim.systems.sensors.imu import ANGULAR_VELOCITY, GRAVITY_W, IMU_SIZE, LINEAR_ACCELERATION

_G = -GRAVITY_W[2]  # m/s^2.


@dc.dataclass
class PitchEstimatorConfig:
    """Rate and crossover of the complementary filter."""

    rate: float = 200.0  # Hz, how often the estimate is updated.
    # s: changes of pitch faster than this come from the gyro, slower ones from the
    # accelerometer; the gyro's bias b leaves an error of about b * time_constant.
    time_constant: float = 0.5
    # Take the axle's acceleration (from the wheel encoders) out of the accelerometer's reading.
    compensate_acceleration: bool = True
    # The accelerometer is ignored while the size of its reading differs from that of the
    # expected (a, 0, g) by more than this fraction of g: the wheels slip or leave the floor.
    gate: float = 0.2


# Layout of the discrete state.
_THETA = 0  # Estimated pitch, rad.
_SPEED = 1  # The axle's speed over ground at the last update (encoders and gyro), m/s.
_SAMPLES = 2  # Accelerometer samples blended in so far.
_SIZE = 3


class PitchEstimator(LeafSystem):
    """A complementary filter of the IMU's gyro and accelerometer, updated at a fixed rate.

    .. pydrake_system::

        name: PitchEstimator
        input_ports:
        - imu
        - wheel_state
        output_ports:
        - pitch

    ``imu`` is the ``Imu`` output (only the angular velocity and specific force are used, not
    its orientation); ``wheel_state`` is ``[q_left, q_right, v_left, v_right]`` (rad, rad/s),
    for the axle's acceleration. ``pitch`` is ``[theta, theta_dot]`` (rad, rad/s): the
    estimate the next update will store, computed from the current measurements, so a
    controller updating at the same instant sees it without a period's delay.

    Args:
        wheel_radius: m, to turn the wheels' rotation into the axle's speed.
        config: rate and time constant.
    """

    def __init__(self, *, wheel_radius: float, config: PitchEstimatorConfig):
        super().__init__()
        self._config = config
        self._dt = 1.0 / config.rate
        self._radius = wheel_radius
        self._imu = self.DeclareVectorInputPort("imu", IMU_SIZE)
        self._wheels = self.DeclareVectorInputPort("wheel_state", 4)
        self._state = self.DeclareDiscreteState(_SIZE)
        self.DeclarePeriodicDiscreteUpdateEvent(self._dt, 0.0, self._update)
        self.DeclareVectorOutputPort("pitch", BasicVector(2), self._calc_pitch)

    def _estimate(self, context) -> np.ndarray:
        """Returns the next state: the filtered pitch and the axle's speed."""
        x = context.get_discrete_state(self._state).value()
        imu = self._imu.Eval(context)
        rate = imu[ANGULAR_VELOCITY][1]
        f_x, _, f_z = imu[LINEAR_ACCELERATION]
        speed = self._radius * (0.5 * np.sum(self._wheels.Eval(context)[2:4]) + rate)
        samples = x[_SAMPLES]
        acceleration = (speed - x[_SPEED]) / self._dt  # The state starts at rest.
        if not self._config.compensate_acceleration:
            acceleration = 0.0
        # The specific force is the axle's acceleration (a, 0, g) in the heading frame turned
        # by -theta into the body: theta is the angle between the two.
        theta_acc = math.atan2(acceleration, _G) - math.atan2(f_x, f_z)
        theta = x[_THETA] + rate * self._dt
        if abs(math.hypot(f_x, f_z) - math.hypot(acceleration, _G)) > self._config.gate * _G:
            return np.array([theta, speed, samples])  # The gyro alone.
        # Running mean of the first samples (the estimate knows nothing yet), then the
        # complementary filter's fixed blend: as a Kalman filter's gain falls to steady state.
        blend = max(1.0 / (samples + 1), self._dt / (self._config.time_constant + self._dt))
        return np.array([theta + blend * (theta_acc - theta), speed, samples + 1])

    def _update(self, context, discrete_state):
        discrete_state.set_value(self._state, self._estimate(context))

    def _calc_pitch(self, context, output):
        theta = self._estimate(context)[_THETA]
        output.SetFromVector([theta, self._imu.Eval(context)[ANGULAR_VELOCITY][1]])
