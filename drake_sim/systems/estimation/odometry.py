"""Wheel odometry that survives flips, and the ground truth to compare it with.

Both report the pose of the *axle frame* A (see ``drake_sim.systems.axle``) at the midpoint between
the wheels: ``[x, y, yaw]`` in the world (m, m, rad). The Gazebo diff-drive plugin integrates the
wheel joint angles. Here, two things that plugin lacks:

* each wheel's rotation *relative to the world* is its joint angle plus the body's pitch about
  the axle (from the IMU), so a body turning over its axle (a flip) is not counted as travel;
* while the wheels slip (they do when the motors flip the body), the distance comes from the
  IMU instead: the change of its integrated specific force (the IMU sits on the axle), turned
  into the world and projected on the travel direction. The wheels are trusted again as soon as
  their speed agrees with the IMU's.

The naive estimate (joint angles only, as the Gazebo plugin) is reported beside it.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import RigidBody
from pydrake.systems.framework import BasicVector, LeafSystem

from drake_sim.base.planar import wrap_angle
from drake_sim.robots.ddrive_params import RobotParams
from drake_sim.systems.axle import axle_yaw_and_pitch
from drake_sim.systems.sensors.imu import (
    GRAVITY_W,
    IMU_SIZE,
    QUATERNION,
    rotation_from_imu,
    rotation_from_quaternion,
)


@dc.dataclass
class OdometryConfig:
    """Rate and error growth of the wheel odometry."""

    rate: float = 100.0  # Hz.
    # The wheels are taken to slip when their speed over ground differs from the IMU's estimate
    # by more than slip_speed (m/s), until it no longer does, or until their acceleration has
    # matched the IMU's within slip_acceleration (m/s^2) for grip_time (s): gripping again.
    slip_speed: float = 0.15
    slip_acceleration: float = 3.0
    grip_time: float = 0.1
    # s: the body's pitch about the axle is the integrated gyro, pulled towards the pitch of the
    # IMU's (noisy) orientation with this time constant, so neither noise nor drift builds up.
    pitch_time_constant: float = 0.5
    along_track_variance: float = 1e-4  # m^2 of variance added per metre travelled.
    cross_track_variance: float = 1e-4  # m^2 per metre travelled.
    yaw_variance: float = 2e-4  # rad^2 per metre travelled.


# Layout of the odometry's discrete state.
_POSE = slice(0, 3)  # x, y, yaw of the axle frame (flip-aware).
_PREV = slice(3, 6)  # Previous left and right joint angles and unwrapped pitch, rad.
_DISTANCE = 6  # Path length travelled, m.
_NAIVE = slice(7, 10)  # x, y, yaw integrated from the joint angles alone.
_TWIST = slice(10, 12)  # Forward speed (m/s) and yaw rate (rad/s).
_COVARIANCE = slice(12, 21)  # 3x3 covariance of [x, y, yaw], row-major.
_DELTA_V = slice(21, 24)  # The IMU's integrated specific force at the last update, m/s.
_QUATERNION = slice(24, 28)  # The IMU's orientation at the last update.
_SLIPPING = 28  # 1 while the wheels slip and the IMU carries the distance.
_DELTA_ANGLE = slice(29, 32)  # The IMU's integrated angular velocity at the last update, rad.
_WHEEL_SPEED = 32  # The wheels' speed over ground at the last update, m/s.
_GRIP_TIME = 33  # How long the wheels' and the IMU's accelerations have agreed, s.
_SIZE = 34


class WheelOdometry(LeafSystem):
    """Dead reckoning from the wheel encoders and the IMU's orientation.

    .. pydrake_system::

        name: WheelOdometry
        input_ports:
        - wheel_state
        - imu
        - delta_velocity
        - delta_angle
        output_ports:
        - pose
        - twist
        - covariance
        - naive_pose
        - distance
        - slipping

    ``wheel_state`` is ``[q_left, q_right, v_left, v_right]`` (rad, rad/s); ``imu``,
    ``delta_velocity`` and ``delta_angle`` are the ``Imu`` outputs, for an IMU on the axle's
    midpoint. ``pose`` and ``naive_pose`` are ``[x, y, yaw]``; ``twist`` is ``[v, omega]``
    (m/s, rad/s);
    ``covariance`` the 9 entries of the 3x3 covariance of the pose, which grows with the
    distance travelled; ``distance`` the path length, m; ``slipping`` 1 while the IMU carries
    the distance because the wheels slip, else 0.
    """

    def __init__(self, *, robot: RobotParams, config: OdometryConfig, initial_pose=(0, 0, 0)):
        super().__init__()
        self._radius = robot.wheel.radius
        self._separation = robot.wheel_separation
        self._config = config
        self._wheels = self.DeclareVectorInputPort("wheel_state", 4)
        self._imu = self.DeclareVectorInputPort("imu", IMU_SIZE)
        self._delta_v = self.DeclareVectorInputPort("delta_velocity", 3)
        self._delta_angle = self.DeclareVectorInputPort("delta_angle", 3)
        self._dt = 1.0 / config.rate
        initial = np.zeros(_SIZE)
        initial[_POSE] = initial_pose
        initial[_NAIVE] = initial_pose
        initial[_QUATERNION] = [1.0, 0.0, 0.0, 0.0]
        self._state = self.DeclareDiscreteState(BasicVector(initial))
        self.DeclareInitializationDiscreteUpdateEvent(self._initialize)
        self.DeclarePeriodicDiscreteUpdateEvent(1.0 / config.rate, 0.0, self._update)
        for name, part in (
            ("pose", _POSE),
            ("twist", _TWIST),
            ("covariance", _COVARIANCE),
            ("naive_pose", _NAIVE),
            ("distance", slice(_DISTANCE, _DISTANCE + 1)),
            ("slipping", slice(_SLIPPING, _SLIPPING + 1)),
        ):
            size = part.stop - part.start
            self.DeclareVectorOutputPort(
                name, size, self._make_output(part), {self.discrete_state_ticket(self._state)}
            )

    def _make_output(self, part):
        def calc(context, output):
            output.SetFromVector(context.get_discrete_state(self._state).value()[part])

        return calc

    def _initialize(self, context, discrete_state):
        x = discrete_state.get_mutable_vector().get_mutable_value()
        x[:] = context.get_discrete_state(self._state).value()
        q = self._wheels.Eval(context)
        imu = self._imu.Eval(context)
        x[_PREV] = [q[0], q[1], axle_yaw_and_pitch(rotation_from_imu(imu))[1]]
        x[_DELTA_V] = self._delta_v.Eval(context)
        x[_DELTA_ANGLE] = self._delta_angle.Eval(context)
        x[_QUATERNION] = imu[QUATERNION]

    def _update(self, context, discrete_state):
        x = discrete_state.get_mutable_vector().get_mutable_value()
        x[:] = context.get_discrete_state(self._state).value()
        wheels = self._wheels.Eval(context)
        imu = self._imu.Eval(context)
        R_WB = rotation_from_imu(imu)
        heading, pitch_now = axle_yaw_and_pitch(R_WB)
        q_l, q_r, prev_pitch = x[_PREV]
        # The pitch turned (about the axle, the body's y axis) since the last update: the gyro's,
        # nudged towards the orientation's (unwrapped about the running estimate).
        delta_angle = self._delta_angle.Eval(context)
        d_angle_B = delta_angle - x[_DELTA_ANGLE]  # The body's rotation since, in its frame.
        predicted = prev_pitch + d_angle_B[1]
        measured = predicted + wrap_angle(pitch_now - predicted)
        gain = self._dt / self._config.pitch_time_constant
        d_pitch = d_angle_B[1] + gain * (measured - predicted)
        x[_DELTA_ANGLE] = delta_angle
        dq_l, dq_r = wheels[0] - q_l, wheels[1] - q_r
        x[_PREV] = [wheels[0], wheels[1], prev_pitch + d_pitch]
        r, w = self._radius, self._separation
        # Each wheel turns, relative to the world, by its joint angle plus the body's pitch.
        d_left, d_right = r * (dq_l + d_pitch), r * (dq_r + d_pitch)
        ds_wheels, d_yaw = 0.5 * (d_left + d_right), (d_right - d_left) / w
        R_mean = 0.5 * (rotation_from_quaternion(x[_QUATERNION]) + R_WB)
        x[_QUATERNION] = imu[QUATERNION]
        ds = self._fuse_imu(x, context, R_mean, heading, ds_wheels)
        if x[_SLIPPING]:
            d_yaw = float((R_mean @ d_angle_B)[2])  # Slipping wheels can't tell the turn.
        self._integrate(x, _POSE, ds, d_yaw)
        self._integrate(x, _NAIVE, 0.5 * r * (dq_l + dq_r), r * (dq_r - dq_l) / w)
        x[_DISTANCE] += abs(ds)
        x[_TWIST][1] = d_yaw / self._dt
        x[_COVARIANCE] = self._propagate(x[_COVARIANCE].reshape(3, 3), x[2], ds).ravel()

    def _fuse_imu(self, x, context, R_mean, heading, ds_wheels) -> float:
        """Returns the distance travelled since the last update (m): the wheels' unless they
        slip, when the IMU's velocity change carries the speed. ``R_mean`` is the mean of the
        orientations at the last update and now. Updates the speed estimate ``x[_TWIST][0]``,
        the slip flag and the integrated specific force kept for the next update."""
        dt = self._dt
        delta_v = self._delta_v.Eval(context)
        # The velocity change of the axle's midpoint over the update, in the world: the
        # specific force's integral turned by the mean orientation, plus gravity's share.
        dv_W = R_mean @ (delta_v - x[_DELTA_V]) + GRAVITY_W * dt
        x[_DELTA_V] = delta_v
        forward = np.array([np.cos(heading), np.sin(heading), 0.0])
        dv_imu = float(dv_W @ forward)
        v_before = x[_TWIST][0]
        v_imu = v_before + dv_imu
        v_wheels = ds_wheels / dt
        c = self._config
        dv_wheels = v_wheels - x[_WHEEL_SPEED]
        x[_WHEEL_SPEED] = v_wheels
        agree = abs(dv_wheels - dv_imu) < c.slip_acceleration * dt
        x[_GRIP_TIME] = x[_GRIP_TIME] + dt if agree else 0.0
        gripping = abs(v_wheels - v_imu) <= c.slip_speed or x[_GRIP_TIME] >= c.grip_time
        x[_SLIPPING] = 0.0 if gripping else 1.0
        if gripping:
            x[_TWIST][0] = v_wheels
            return ds_wheels
        x[_TWIST][0] = v_imu
        return 0.5 * (v_before + v_imu) * dt

    @staticmethod
    def _integrate(x, part, ds, d_yaw):
        px, py, yaw = x[part]
        mid = yaw + 0.5 * d_yaw
        x[part] = [px + ds * math.cos(mid), py + ds * math.sin(mid), wrap_angle(yaw + d_yaw)]

    def _propagate(self, P, yaw, ds):
        """First-order propagation: P <- F P F' + Q, with Q proportional to |ds|."""
        c, s = math.cos(yaw), math.sin(yaw)
        F = np.array([[1.0, 0.0, -ds * s], [0.0, 1.0, ds * c], [0.0, 0.0, 1.0]])
        R = np.array([[c, -s], [s, c]])
        cfg = self._config
        Q = np.zeros((3, 3))
        Q[:2, :2] = R @ np.diag([cfg.along_track_variance, cfg.cross_track_variance]) @ R.T
        Q[2, 2] = cfg.yaw_variance
        return F @ P @ F.T + abs(ds) * Q


class AxleGroundTruth(LeafSystem):
    """The true pose of the axle frame, from the plant: what the odometry estimates.

    .. pydrake_system::

        name: AxleGroundTruth
        input_ports:
        - plant_state
        output_ports:
        - pose

    ``plant_state`` is the plant's full state; ``pose`` is ``[x, y, yaw]`` of the wheels'
    midpoint and the axle frame's heading.
    """

    def __init__(self, *, plant: MultibodyPlant, body: RigidBody, robot: RobotParams):
        super().__init__()
        if not body.is_floating_base_body():
            raise ValueError(f"{body.name()} must be a floating base body")
        start = body.floating_positions_start()  # [qw, qx, qy, qz, x, y, z] of the body.
        self._quaternion = slice(start, start + 4)
        self._position = slice(start + 4, start + 7)
        self._p_BA = np.array([robot.axle_x, 0.0, 0.0])
        self._state = self.DeclareVectorInputPort("plant_state", plant.num_multibody_states())
        self.DeclareVectorOutputPort("pose", 3, self._calc_pose)

    def _calc_pose(self, context, output):
        state = self._state.Eval(context)
        R_WB = rotation_from_quaternion(state[self._quaternion])
        output.SetFromVector(_axle_pose(R_WB, state[self._position], self._p_BA))


def axle_pose(X_WB: RigidTransform, robot: RobotParams) -> np.ndarray:
    """``[x, y, yaw]`` of the axle frame for a body pose X_WB (e.g. the start pose)."""
    p_BA = np.array([robot.axle_x, 0.0, 0.0])
    return _axle_pose(X_WB.rotation().matrix(), X_WB.translation(), p_BA)


def _axle_pose(R_WB: np.ndarray, p_WB: np.ndarray, p_BA: np.ndarray) -> np.ndarray:
    """``[x, y, yaw]`` of the axle frame A at p_BA on a body with orientation R_WB at p_WB."""
    p_WA = p_WB + R_WB @ p_BA
    yaw, _ = axle_yaw_and_pitch(R_WB)
    return np.array([p_WA[0], p_WA[1], yaw])
