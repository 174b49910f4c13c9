"""Travel back and forth along a line by flipping over the wheel axle instead of turning."""

import dataclasses as dc
import enum
import math

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem

from drake_sim.base.planar import wrap_angle
from drake_sim.robots.ddrive_params import RobotParams
from drake_sim.systems.axle import axle_yaw_and_pitch
from drake_sim.systems.control.diff_drive_controller import wheel_loop_gain
from drake_sim.systems.sensors.imu import ANGULAR_VELOCITY, IMU_SIZE, rotation_from_imu

_GRAVITY = 9.81  # m/s^2.


class FlipMode(enum.IntEnum):
    """The flip controller's modes."""

    DRIVE = 0  # Roll towards the wheels (body trailing) at the drive speed.
    FLIP = 1  # Full reverse torque: the body's tail swings up and over the axle.
    SETTLE = 2  # Hold the wheels still while the body lands and stops rocking.
    RECOVER = 3  # A flip failed or the robot is stuck: let it fall, then rock it free.


@dc.dataclass
class FlipConfig:
    """Parameters of the flip controller. Gains and torques are derived from the robot's
    dimensions, masses and motor limit (speed-loop gains from the robot's inertia, the flip
    torque from the body's weight moment about the axle), so one file suits robots of other
    sizes."""

    rate: float = 100.0  # Hz, control rate.
    drive_speed: float = 0.8  # m/s, along the line, towards the wheels.
    drive_time: float = 1.0  # s of driving before each flip.
    # m/s^2: the drive speed is ramped up and down at this rate, below what the tyres' grip
    # allows, so the wheels roll rather than spin and the odometry stays true.
    drive_acceleration: float = 3.0
    # The flip turns the body over the axle at this pitch rate, rad/s: wheel torque (whose
    # reaction turns the body) = gravity compensation + a rate loop, capped at max torque.
    flip_rate: float = 5.0
    flip_response_time: float = 0.05  # s, time constant of the flip's pitch-rate loop.
    flip_angle: float = 150.0  # deg of body pitch about the axle that ends the flip.
    flip_timeout: float = 1.5  # s; a flip not past flip_angle by then has failed.
    settled_tilt: float = 25.0  # deg; lying flat means the body's z axis within this of vertical.
    settled_rate: float = 1.0  # rad/s; and its angular velocity below this.
    settle_min_time: float = 0.15  # s in SETTLE before the next drive may start.
    settle_timeout: float = 2.0  # s; still not settled by then means RECOVER.
    recover_torque: float = 0.5  # fraction of max torque for the rocking pulses.
    recover_pulse: float = 0.4  # s, length of each rocking pulse, alternating in direction.
    recover_timeout: float = 6.0  # s; then RECOVER starts over.
    response_time: float = 0.05  # s, time constant of the drive's wheel velocity loop.
    # s, time constant of the wheel drivers' loop that keeps both wheels at the same speed
    # (see drake_sim.systems.control.wheel_drivers).
    wheel_sync_response_time: float = 0.05


# Layout of the discrete state.
_MODE, _START, _SIGN, _PITCH0, _TORQUE, _FLIPS, _FAILED, _RECOVERIES, _ATTEMPTS, _SPEED = range(10)
_SIZE = 10  # _SPEED: the ramped speed target over ground, m/s.
STATUS_FIELDS = ("mode", "travel_sign", "flips", "failed_flips", "recoveries", "attempts")
"""Names of the entries of the ``status`` output."""


class FlipController(LeafSystem):
    """A state machine (drive, flip, settle, recover) driven by the IMU and wheel encoders.

    .. pydrake_system::

        name: FlipController
        input_ports:
        - imu
        - wheel_state
        output_ports:
        - wheel_torque
        - status

    ``wheel_torque`` is ONE scalar (N m) applied to both wheels, so both wheels always get the
    same command; fan it out to the plant's two actuators. ``status`` holds ``STATUS_FIELDS``:
    the mode (``FlipMode``), the travel sign (+1 upright, -1 upside down), and counts of
    completed flips, failed flips (fell back, or timed out), recoveries and flip attempts.

    In DRIVE the robot rolls towards its wheels, so after each flip (the body lands on the
    other side of the axle, upside down) it drives back the way it came: it shuttles along a
    line. Upright and upside down are handled alike through the sign of the body's z axis.
    """

    def __init__(self, *, robot: RobotParams, config: FlipConfig):
        super().__init__()
        c = self._config = config
        self._radius = robot.wheel.radius
        self._max_torque = robot.motor.max_torque
        # The body turning about the axle: its weight's moment arm and its inertia there.
        b = robot.body
        self._body_weight_moment = b.mass * _GRAVITY * robot.axle_x  # N m, body horizontal.
        inertia_cm = b.mass * (b.length**2 + b.height**2) / 12
        self._flip_gain = (inertia_cm + b.mass * robot.axle_x**2) / c.flip_response_time
        self._kp = wheel_loop_gain(robot, c.response_time)
        self._flat = math.cos(math.radians(c.settled_tilt))
        self._imu = self.DeclareVectorInputPort("imu", IMU_SIZE)
        self._wheels = self.DeclareVectorInputPort("wheel_state", 4)
        initial = np.zeros(_SIZE)
        initial[_SIGN] = 1.0
        self._state = self.DeclareDiscreteState(BasicVector(initial))
        self.DeclarePeriodicDiscreteUpdateEvent(1.0 / c.rate, 0.0, self._update)
        tickets = {self.discrete_state_ticket(self._state)}
        self.DeclareVectorOutputPort("wheel_torque", 1, self._calc_torque, tickets)
        self.DeclareVectorOutputPort("status", len(STATUS_FIELDS), self._calc_status, tickets)

    def _flip_torque(self, progress: float, progress_rate: float) -> float:
        """The wheel torque (N m, each wheel; positive turns the body onward) whose reaction
        turns the body over the axle at the flip rate: half of the body's weight moment about
        the axle (it resists until the body is over the axle and helps after) plus half of a
        proportional pitch-rate loop's torque, capped at the motor's maximum.

        Args:
            progress: how far the body has turned over the axle, rad (0 to pi).
            progress_rate: how fast it turns onward, rad/s.
        """
        body_torque = self._body_weight_moment * math.cos(progress)
        body_torque += self._flip_gain * (self._config.flip_rate - progress_rate)
        return float(np.clip(0.5 * body_torque, -self._max_torque, self._max_torque))

    def _calc_torque(self, context, output):
        output.SetAtIndex(0, context.get_discrete_state(self._state).value()[_TORQUE])

    def _calc_status(self, context, output):
        x = context.get_discrete_state(self._state).value()
        output.SetFromVector(x[[_MODE, _SIGN, _FLIPS, _FAILED, _RECOVERIES, _ATTEMPTS]])

    def _speed_loop(self, x: np.ndarray, target: float, wheel_rate: float) -> float:
        """Ramps the speed target ``x[_SPEED]`` towards ``target`` (m/s over ground) and
        returns the wheel torque that tracks it, given the wheels' rate over ground."""
        step = self._config.drive_acceleration / self._config.rate
        x[_SPEED] += float(np.clip(target - x[_SPEED], -step, step))
        torque = self._kp * (x[_SPEED] / self._radius - wheel_rate)
        return float(np.clip(torque, -self._max_torque, self._max_torque))

    def _update(self, context, discrete_state):
        c = self._config
        x = np.array(context.get_discrete_state(self._state).value())
        imu = self._imu.Eval(context)
        R_WB = rotation_from_imu(imu)
        _, pitch = axle_yaw_and_pitch(R_WB)
        up = R_WB[2, 2]
        calm = math.hypot(*imu[ANGULAR_VELOCITY]) < c.settled_rate
        flat = abs(up) > self._flat
        # The wheels' rotation rate relative to the world (joint rate plus the body's pitch
        # rate about the axle): the robot's speed over ground is this times the radius.
        wheels = self._wheels.Eval(context)
        wheel_rate = 0.5 * (wheels[2] + wheels[3]) + imu[ANGULAR_VELOCITY][1]
        now = context.get_time()
        elapsed = now - x[_START]
        mode = FlipMode(int(x[_MODE]))

        def switch(new_mode):
            x[_MODE], x[_START] = new_mode, now

        if mode == FlipMode.DRIVE:
            if flat:
                x[_SIGN] = math.copysign(1.0, up)
            x[_TORQUE] = self._speed_loop(x, x[_SIGN] * c.drive_speed, wheel_rate)
            if elapsed >= c.drive_time:
                switch(FlipMode.FLIP)
                x[_PITCH0] = pitch
                x[_ATTEMPTS] += 1
        elif mode == FlipMode.FLIP:
            # Progress of the body over the axle, 0 to pi, and its rate, from the IMU.
            progress = x[_SIGN] * wrap_angle(pitch - x[_PITCH0])
            progress_rate = x[_SIGN] * imu[ANGULAR_VELOCITY][1]
            # A reaction torque -tau on the body turns it the way the flip goes.
            x[_TORQUE] = -x[_SIGN] * self._flip_torque(max(progress, 0.0), progress_rate)
            if progress > math.radians(c.flip_angle):
                switch(FlipMode.SETTLE)
                x[_SPEED] = wheel_rate * self._radius  # Brake from the speed it lands with.
            elif elapsed > c.flip_timeout:
                x[_FAILED] += 1
                switch(FlipMode.RECOVER)
        elif mode == FlipMode.SETTLE:
            x[_TORQUE] = self._speed_loop(x, 0.0, wheel_rate)
            if elapsed >= c.settle_min_time and flat and calm:
                if math.copysign(1.0, up) != x[_SIGN]:
                    x[_FLIPS] += 1
                else:
                    x[_FAILED] += 1  # It fell back the way it came.
                switch(FlipMode.DRIVE)
            elif elapsed > c.settle_timeout:
                switch(FlipMode.RECOVER)
        else:  # RECOVER: first let it fall by itself, then rock it with alternating pulses.
            if flat and calm and elapsed >= c.settle_min_time:
                x[_RECOVERIES] += 1
                switch(FlipMode.DRIVE)
                x[_TORQUE] = 0.0
            elif elapsed > c.recover_timeout:
                switch(FlipMode.RECOVER)
            elif elapsed < c.recover_pulse:
                x[_SPEED] = 0.0
                x[_TORQUE] = self._speed_loop(x, 0.0, wheel_rate)
            else:
                pulse = int((elapsed - c.recover_pulse) / c.recover_pulse)
                direction = 1.0 if pulse % 2 == 0 else -1.0
                x[_TORQUE] = direction * c.recover_torque * self._max_torque
        discrete_state.set_value(self._state, x)
