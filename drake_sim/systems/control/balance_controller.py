"""Balancing a two-wheeled robot while it follows a ``cmd_vel`` (v, omega) command.

Both controllers work on the reduced planar model of ``drake_sim.robots.walle`` (a wheeled
inverted pendulum, ``x = [s, theta, s_dot, theta_dot]``: distance rolled, lean, and their
rates; input the wheels' total torque), and every gain derives from it, so one configuration
suits robots of other sizes and masses:

* ``"pid"``, the student project's baseline: a PID on pitch (wheel torque from the lean, its
  integral and its rate) inside a slower PD loop on the distance and speed errors, whose
  output is the lean to hold (``pid_gains``: each loop gets the natural frequency and
  damping asked for, the outer one well below the model's non-minimum-phase zero).
* ``"lqr"``: state feedback ``tau = -K (x - x_ref)`` plus the distance error's integral, with
  ``K`` from Drake's ``DiscreteTimeLinearQuadraticRegulator`` on the model discretised at the
  control rate, weighted by Bryson's rule from tolerances in physical units (``lqr_gain``).

The command is clipped and ramped into a reference (speed, distance, yaw rate, heading). While
the speed reference ramps, both add the lean that produces its acceleration and the torque
that holds that lean (feedforward), so neither has to fall behind before it follows. The
wheels' total torque stays within what the tyres can push (``max_total_torque``): beyond it
they spin, and a spinning wheel balances nothing. Both turn with a PD on heading and yaw rate
(from the encoders) that adds equal and opposite torques, within what balancing leaves.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.systems.analysis import DiscreteTimeApproximation
from pydrake.systems.controllers import DiscreteTimeLinearQuadraticRegulator
from pydrake.systems.framework import LeafSystem
from pydrake.systems.primitives import LinearSystem

from drake_sim.robots.walle import S_DOT, THETA, THETA_DOT, linearize_upright
from drake_sim.robots.walle_params import GRAVITY, WalleParams

CONTROLLERS = ("lqr", "pid")


@dc.dataclass
class PidBalanceConfig:
    """Shape of the cascade PID; its gains derive from the robot's model."""

    # Natural frequency of the pitch loop, as a multiple of the robot's falling rate
    # sqrt(a) (1/s): the rate at which a small lean grows without control.
    pitch_bandwidth: float = 2.0
    pitch_damping: float = 0.7  # Damping ratio of the pitch loop.
    pitch_integral_time: float = 2.0  # s, integral time of the pitch loop (0: no integral).
    # Natural frequency of the outer (distance and speed) loop, as a fraction of the model's
    # non-minimum-phase zero sqrt(g_eff / c) (1/s; see pid_gains): to lean forward, the
    # wheels must first roll back, and a faster loop chases its own reversal.
    speed_bandwidth: float = 0.2
    speed_damping: float = 0.5  # Damping ratio of the outer loop.
    max_lean: float = 10.0  # deg, the most lean the outer loop may ask for.


@dc.dataclass
class LqrBalanceConfig:
    """Bryson's rule: each weight is 1 / (acceptable value)^2."""

    position_tolerance: float = 0.3  # m, of the distance from the reference.
    pitch_tolerance: float = 3.0  # deg.
    speed_tolerance: float = 0.5  # m/s, of the speed error.
    pitch_rate_tolerance: float = 60.0  # deg/s.
    torque_tolerance: float = 0.3  # Fraction of the most torque the wheels may use.
    # m s, of the distance error's integral, which holds the robot's place against a biased
    # pitch estimate or a slope; 0 leaves the integral out.
    integral_tolerance: float = 0.5


@dc.dataclass
class BalanceConfig:
    """The balance controller: which law, its rate, the command's limits and the turning loop.

    The default law, ``"lqr"``, was chosen by measurement: see ``BalanceController``.
    """

    controller: str = "lqr"  # "lqr" or "pid".
    rate: float = 200.0  # Hz, control rate.
    max_linear_velocity: float = 0.6  # m/s.
    max_angular_velocity: float = 3.0  # rad/s.
    max_linear_acceleration: float = 0.6  # m/s^2, ramp of the speed reference.
    max_angular_acceleration: float = 6.0  # rad/s^2, ramp of the yaw-rate reference.
    # m: the distance reference stays within this of the robot (it waits for a robot that was
    # pushed away, instead of pulling it back at full lean).
    max_position_error: float = 0.1
    yaw_response_time: float = 0.1  # s, time constant of the yaw-rate loop.
    heading_time: float = 0.5  # s, a heading error is corrected over about this time.
    fallen_pitch: float = 45.0  # deg; past this lean the robot has fallen: motors off.
    # The wheels' total push on the floor is kept within this fraction of the robot's weight
    # (a friction coefficient below the tyres'): a spinning wheel cannot balance anything.
    max_traction: float = 0.7
    pid: PidBalanceConfig = dc.field(default_factory=PidBalanceConfig)
    lqr: LqrBalanceConfig = dc.field(default_factory=LqrBalanceConfig)


def yaw_inertia(robot: WalleParams) -> float:
    """Moment of inertia (kg m^2) of the robot turning on the spot about the vertical through
    the axle's midpoint, the wheels' spin included (they roll at +-d/2 omega / r)."""
    b, w = robot.body, robot.wheel
    half = 0.5 * robot.wheel_separation
    body = b.mass * (b.length**2 + b.width**2) / 12
    wheel_across = w.mass * (3 * w.radius**2 + w.width**2) / 12 + w.mass * half**2
    wheel_spin = 0.5 * w.mass * w.radius**2 * (half / w.radius) ** 2
    return body + 2 * (wheel_across + wheel_spin)


@dc.dataclass
class PendulumModel:
    """The linearised planar model reduced to the numbers the controllers use:
    ``theta_ddot = a theta - b tau`` and, eliminating ``tau``, ``s_ddot = g_eff theta - c
    theta_ddot``. Holding a lean ``theta`` (``theta_ddot = 0``) takes ``tau = a theta / b``
    and accelerates the robot at ``g_eff theta``; the lean-to-distance response has a zero at
    ``sqrt(g_eff / c)`` in the right half-plane: the robot rolls back before it goes forward.
    """

    a: float  # 1/s^2, the square of the rate at which a small lean grows uncontrolled.
    b: float  # 1/(kg m^2), pitch acceleration per N m of wheel torque (turning it back).
    g_eff: float  # m/s^2 of steady acceleration per rad of lean held.
    c: float  # m.


def pendulum_model(robot: WalleParams) -> PendulumModel:
    """Reads the ``PendulumModel`` off ``linearize_upright(robot)``."""
    A, B = linearize_upright(robot)
    a, b = A[THETA_DOT, THETA], -B[THETA_DOT, 0]
    return PendulumModel(a=a, b=b, g_eff=A[S_DOT, THETA] + B[S_DOT, 0] * a / b, c=B[S_DOT, 0] / b)


@dc.dataclass
class PidGains:
    """The cascade's gains."""

    kp: float  # N m/rad.
    kd: float  # N m s/rad.
    ki: float  # N m/(rad s).
    position: float  # 1/s^2: lean (rad) per metre of distance error, times g_eff.
    speed: float  # 1/s: lean per m/s of speed error, times g_eff.


def pid_gains(robot: WalleParams, config: PidBalanceConfig) -> PidGains:
    """Derives the cascade's gains from the ``PendulumModel``.

    Inner loop: with ``tau = kp theta + kd theta_dot`` the closed loop ``theta_ddot + b kd
    theta_dot + (b kp - a) theta = 0`` has natural frequency ``w_p`` and damping ``z_p`` when
    ``kp = (w_p^2 + a) / b`` and ``kd = 2 z_p w_p / b``. Outer loop: a lean target ``-(w_o^2
    e_s + 2 z_o w_o e_v) / g_eff`` makes the distance error ``e_s`` a damped oscillator at
    ``w_o`` (``e_v`` the speed error), ``w_o`` well below the zero ``sqrt(g_eff / c)``.
    """
    model = pendulum_model(robot)
    a, b = model.a, model.b
    w_p = config.pitch_bandwidth * math.sqrt(a)
    kp = (w_p**2 + a) / b
    w_o = config.speed_bandwidth * math.sqrt(model.g_eff / model.c)
    return PidGains(
        kp=kp,
        kd=2 * config.pitch_damping * w_p / b,
        ki=kp / config.pitch_integral_time if config.pitch_integral_time > 0 else 0.0,
        position=w_o**2,
        speed=2 * config.speed_damping * w_o,
    )


def max_total_torque(robot: WalleParams, traction: float) -> float:
    """The most torque (N m) both wheels together may apply: the motors' limit, or what makes
    the tyres push the floor with ``traction`` times the robot's weight, whichever is less."""
    grip = traction * robot.total_mass * GRAVITY * robot.wheel.radius
    return min(2 * robot.motor.max_torque, grip)


def lqr_gain(
    robot: WalleParams, config: LqrBalanceConfig, period: float, traction: float
) -> np.ndarray:
    """The state-feedback gain ``K`` (``tau = -K x``) for a controller updating every
    ``period`` s with its torque held in between, allowed ``config.torque_tolerance`` of
    ``max_total_torque(robot, traction)``.

    ``x`` is ``linearize_upright``'s state (1 x 4 gain), followed by the distance error's
    integral (m s) when ``config.integral_tolerance`` is not 0 (1 x 5).
    """
    A, B = linearize_upright(robot)
    discrete = DiscreteTimeApproximation(
        LinearSystem(A, B, np.zeros((0, 4)), np.zeros((0, 1))), period
    )
    Ad, Bd = discrete.A(), discrete.B()
    tolerances = [
        config.position_tolerance,
        math.radians(config.pitch_tolerance),
        config.speed_tolerance,
        math.radians(config.pitch_rate_tolerance),
    ]
    if config.integral_tolerance > 0:  # A fifth state: the sum of s * period.
        Ad = np.block([[Ad, np.zeros((4, 1))], [period * np.eye(1, 4), np.eye(1)]])
        Bd = np.vstack([Bd, np.zeros((1, 1))])
        tolerances.append(config.integral_tolerance)
    Q = np.diag(1.0 / np.square(tolerances))
    R = np.array([[1.0 / (config.torque_tolerance * max_total_torque(robot, traction)) ** 2]])
    K, _ = DiscreteTimeLinearQuadraticRegulator(Ad, Bd, Q, R)
    return np.asarray(K)


# Layout of the controller's discrete state.
# _INTEGRAL: of the pitch error (PID, rad s) or of the distance error (LQR, m s).
_V_REF, _W_REF, _S_REF, _YAW_REF, _INTEGRAL, _FALLEN = range(6)
_TORQUE = slice(6, 8)  # Wheel torques [left, right], N m.
_SIZE = 8
STATUS_FIELDS = ("fallen", "s", "s_ref", "yaw", "yaw_ref")
"""Names of the entries of the ``status`` output."""


class BalanceController(LeafSystem):
    """Keeps the robot upright on its two wheels while it tracks a (v, omega) command.

    .. pydrake_system::

        name: BalanceController
        input_ports:
        - command
        - pitch
        - wheel_state
        output_ports:
        - wheel_torques
        - status

    ``command`` is ``[v, omega]`` (m/s forward, rad/s counter-clockwise), ROS's ``cmd_vel``;
    ``pitch`` is ``[theta, theta_dot]`` (rad, rad/s; a ``PitchEstimator``'s output);
    ``wheel_state`` is ``[q_left, q_right, v_left, v_right]`` (rad, rad/s). ``wheel_torques``
    is ``[left, right]`` (N m, within the motors' limit), held between updates. ``status``
    holds ``STATUS_FIELDS``: 1 once the robot has fallen (the motors are then off for good),
    the distance rolled and its reference (m), the heading from the encoders and its
    reference (rad, from the start).

    The command is clipped and ramped to the configured limits into references: speed
    ``v_ref`` and yaw rate ``w_ref``, integrated into a distance ``s_ref`` and heading.

    Why LQR is the default (``benchmarks/walle_balance_benchmark.py``, default robot and
    scenario): both balance within 0.25 degrees under the IMU's noise and recover from pushes
    well beyond the 0.3 m g asked for, the PID from somewhat larger ones (0.59 m g for 0.2 s,
    against 0.53). But driving (forward, turning, reversing, stopping) the LQR leans less (5.7
    degrees at most, against 8.1) and lags its reference less (2.0 cm RMS, against 2.8), and
    its integral holds the robot's place without the PID's offset from the IMU's bias (2.2 cm
    at most, against 3.0). The line follower looks through a camera on the body, whose view
    of the floor swings with every degree of lean: steadier matters more than the last 10 %
    of push. The PID stays as the student project's baseline.

    Args:
        robot: the robot (model for the gains, wheel radius and separation, motor limit).
        config: the law and its tuning.
    """

    def __init__(self, *, robot: WalleParams, config: BalanceConfig):
        super().__init__()
        if config.controller not in CONTROLLERS:
            raise ValueError(f"unknown controller {config.controller!r}; expected {CONTROLLERS}")
        self._config = config
        self._dt = 1.0 / config.rate
        self._radius = robot.wheel.radius
        self._track = robot.wheel_separation
        self._max_total = max_total_torque(robot, config.max_traction)
        self._fallen_pitch = math.radians(config.fallen_pitch)
        self._model = pendulum_model(robot)
        if config.controller == "pid":
            self._pid = pid_gains(robot, config.pid)
        else:
            self._K = lqr_gain(robot, config.lqr, self._dt, config.max_traction)[0]
        # Yaw: J psi_ddot = tau_d d / (2 r) for tau_d the right minus left torque split.
        self._yaw_gain = yaw_inertia(robot) * 2 * self._radius / self._track
        self._command = self.DeclareVectorInputPort("command", 2)
        self._pitch = self.DeclareVectorInputPort("pitch", 2)
        self._wheels = self.DeclareVectorInputPort("wheel_state", 4)
        self._state = self.DeclareDiscreteState(_SIZE)
        self.DeclarePeriodicDiscreteUpdateEvent(self._dt, 0.0, self._update)
        tickets = {self.discrete_state_ticket(self._state)}
        self.DeclareVectorOutputPort("wheel_torques", 2, self._calc_torques, tickets)
        self.DeclareVectorOutputPort("status", len(STATUS_FIELDS), self._calc_status)

    def _calc_torques(self, context, output):
        output.SetFromVector(context.get_discrete_state(self._state).value()[_TORQUE])

    def _odometry(self, context) -> np.ndarray:
        """[s, yaw, s_dot, yaw_rate] from the encoders and the pitch estimate: the wheels'
        rotation relative to the world is the joint's plus the body's pitch."""
        q_l, q_r, v_l, v_r = self._wheels.Eval(context)
        theta, theta_dot = self._pitch.Eval(context)
        r, d = self._radius, self._track
        return np.array(
            [
                r * (0.5 * (q_l + q_r) + theta),
                r * (q_r - q_l) / d,
                r * (0.5 * (v_l + v_r) + theta_dot),
                r * (v_r - v_l) / d,
            ]
        )

    def _calc_status(self, context, output):
        x = context.get_discrete_state(self._state).value()
        s, yaw, _, _ = self._odometry(context)
        output.SetFromVector([x[_FALLEN], s, x[_S_REF], yaw, x[_YAW_REF]])

    def _ramp_command(self, context, x: np.ndarray) -> float:
        """Clips the command to its limits, ramps the references towards it and returns the
        reference's acceleration (m/s^2)."""
        c, dt = self._config, self._dt
        v_cmd, w_cmd = self._command.Eval(context)
        if not (np.isfinite(v_cmd) and np.isfinite(w_cmd)):
            v_cmd, w_cmd = 0.0, 0.0  # A NaN command stops the robot rather than poisoning it.
        v_cmd = np.clip(v_cmd, -c.max_linear_velocity, c.max_linear_velocity)
        w_cmd = np.clip(w_cmd, -c.max_angular_velocity, c.max_angular_velocity)
        dv, dw = c.max_linear_acceleration * dt, c.max_angular_acceleration * dt
        step = float(np.clip(v_cmd - x[_V_REF], -dv, dv))
        x[_V_REF] += step
        x[_W_REF] += np.clip(w_cmd - x[_W_REF], -dw, dw)
        x[_S_REF] += x[_V_REF] * dt
        x[_YAW_REF] += x[_W_REF] * dt
        return step / dt

    def _balance_torque(self, x: np.ndarray, error: np.ndarray, lean: float) -> float:
        """The wheels' total torque (N m) for the state error [e_s, theta, e_v, theta_dot]
        about the reference, whose lean ``lean`` (rad) accelerates it as the command ramps."""
        feedforward = self._model.a * lean / self._model.b  # Holds the lean.
        if self._config.controller == "lqr":
            error = error - [0.0, lean, 0.0, 0.0]
            if len(self._K) == 4:
                return feedforward - float(self._K @ error)
            torque = feedforward - float(self._K @ np.append(error, x[_INTEGRAL]))
            # Anti-windup: hold while saturated, or while the robot is pushed far away.
            if abs(torque) < self._max_total and abs(error[0]) < self._config.max_position_error:
                x[_INTEGRAL] += error[0] * self._dt
            return torque
        g, c = self._pid, self._config.pid
        max_lean = math.radians(c.max_lean)
        lean -= (g.position * error[0] + g.speed * error[2]) / self._model.g_eff
        lean = float(np.clip(lean, -max_lean, max_lean))
        pitch_error = error[1] - lean
        torque = feedforward + g.kp * pitch_error + g.kd * error[3] + g.ki * x[_INTEGRAL]
        if abs(torque) < self._max_total:  # Anti-windup: hold while saturated.
            x[_INTEGRAL] += pitch_error * self._dt
        return torque

    def _update(self, context, discrete_state):
        c = self._config
        x = np.array(context.get_discrete_state(self._state).value())
        theta, theta_dot = self._pitch.Eval(context)
        s, yaw, s_dot, yaw_rate = self._odometry(context)
        if abs(theta) > self._fallen_pitch:
            x[_FALLEN] = 1.0
        if x[_FALLEN]:
            x[_TORQUE] = 0.0
            discrete_state.set_value(self._state, x)
            return
        acceleration = self._ramp_command(context, x)
        # The distance reference waits for a robot pushed far from it.
        x[_S_REF] = np.clip(x[_S_REF], s - c.max_position_error, s + c.max_position_error)
        error = np.array([s - x[_S_REF], theta, s_dot - x[_V_REF], theta_dot])
        limit = self._max_total
        lean = acceleration / self._model.g_eff
        torque = float(np.clip(self._balance_torque(x, error, lean), -limit, limit))
        # Turning: a PD on heading and yaw rate, within what balancing leaves of the limit.
        turn = self._yaw_gain / c.yaw_response_time
        turn *= (x[_W_REF] - yaw_rate) + (x[_YAW_REF] - yaw) / c.heading_time
        headroom = limit - abs(torque)  # Each wheel within half the total's limit.
        turn = float(np.clip(turn, -headroom, headroom))
        x[_TORQUE] = 0.5 * (torque - turn), 0.5 * (torque + turn)
        discrete_state.set_value(self._state, x)
