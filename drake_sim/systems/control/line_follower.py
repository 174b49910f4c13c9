"""Following a line: the line detector's measurement in, a diff-drive ``(v, omega)`` command out.

While the line is seen (mode FOLLOW) the turn rate is the line's curvature times the speed
(feed-forward) plus feedback on the line's heading and lateral offset::

    omega = v * kappa + heading_gain * heading + offset_gain * offset

For a robot moving at v along a straight line this makes the lateral error obey
``e'' + heading_gain e' + offset_gain v e = 0``: with the defaults and v = 0.3 m/s, a natural
frequency of 1.5 rad/s, damping about 1. The speed is the cruise speed limited three ways, so the
robot slows down for tight turns and when it is far off the line: by the lateral acceleration a
curve needs (``v <= sqrt(max_lateral_acceleration / |kappa|)``), and linearly by the heading
error and by the offset, never below ``min_speed``; it changes at most at ``max_acceleration``
(a balancing robot leans to accelerate).

Losing the line is a state, not a guess: after ``lost_delay`` without a detection (a frame or
two may drop out) the robot stops and turns in place (mode SEARCH) towards the side where it
last saw the line ahead of it; once it has turned ``search_turn`` without finding it, it stops
(mode STOPPED) and waits. It never drives on blindly. Seeing the line again resumes FOLLOW.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.systems.framework import LeafSystem

from drake_sim.base.errors import ConfigError
from drake_sim.systems.perception.line_detector import (
    CURVATURE,
    FOUND,
    HEADING,
    MEASUREMENT_SIZE,
    OFFSET,
)

# Modes (held in the discrete state as a number).
FOLLOW = 0
SEARCH = 1
STOPPED = 2

# Layout of the discrete state.
_MODE = 0
_V = 1  # m/s, the commanded speed (slew-limited).
_OMEGA = 2  # rad/s, the commanded turn rate.
_LOST_TIME = 3  # s since the line was last seen.
_SIDE = 4  # +1 if the line was last seen ahead on the left, -1 on the right.
_TURNED = 5  # rad turned while searching.
_STATE_SIZE = 6


@dc.dataclass
class LineFollowerConfig:
    """Gains and limits of the line follower."""

    rate: float = 50.0  # Hz, control updates.
    speed: float = 0.3  # m/s, cruise speed on straights.
    min_speed: float = 0.05  # m/s, the least speed while the line is seen.
    max_acceleration: float = 0.5  # m/s^2, of the commanded speed.
    max_lateral_acceleration: float = 0.1  # m/s^2 in curves: v <= sqrt(a / |kappa|).
    heading_slowdown: float = 1.0  # rad: the speed falls linearly to min_speed at this error.
    offset_slowdown: float = 0.15  # m: the speed falls linearly to min_speed at this offset.
    heading_gain: float = 3.0  # rad/s per rad of heading error.
    offset_gain: float = 8.0  # rad/s per m of lateral offset.
    max_curvature: float = 5.0  # 1/m, feed-forward curvature is clipped to this.
    max_omega: float = 3.0  # rad/s.
    lost_delay: float = 0.25  # s without the line before searching.
    look_ahead: float = 0.3  # m: the side to search is where the line was this far ahead.
    search_omega: float = 1.2  # rad/s, turning in place while searching.
    search_turn: float = 2 * math.pi  # rad turned searching before stopping.


def check_line_follower_config(config: LineFollowerConfig, where: str = "line_follower"):
    """Returns ``config`` if its values are usable; raises ``ConfigError`` naming the key."""
    for f in dc.fields(config):
        value = getattr(config, f.name)
        if not (math.isfinite(value) and value > 0):
            raise ConfigError(f"{where}: '{f.name}' must be positive, got {value!r}")
    if config.min_speed > config.speed:
        raise ConfigError(f"{where}: 'min_speed' must be at most 'speed'")
    return config


def follow_command(measurement, config: LineFollowerConfig) -> tuple[float, float]:
    """Returns the target ``(v, omega)`` (m/s, rad/s) for a measurement vector in which the line
    is seen (before the speed's slew limit)."""
    c = config
    heading, offset = measurement[HEADING], measurement[OFFSET]
    kappa = float(np.clip(measurement[CURVATURE], -c.max_curvature, c.max_curvature))
    v = c.speed
    if abs(kappa) > 1e-9:
        v = min(v, math.sqrt(c.max_lateral_acceleration / abs(kappa)))
    v = min(v, c.speed * (1.0 - abs(heading) / c.heading_slowdown))
    v = min(v, c.speed * (1.0 - abs(offset) / c.offset_slowdown))
    v = max(v, c.min_speed)
    omega = v * kappa + c.heading_gain * heading + c.offset_gain * offset
    return v, float(np.clip(omega, -c.max_omega, c.max_omega))


class LineFollower(LeafSystem):
    """Turns line measurements into a ``(v, omega)`` command, searching when the line is lost.

    .. pydrake_system::

        name: LineFollower
        input_ports:
        - measurement
        output_ports:
        - command
        - mode

    ``measurement`` is the ``LineDetector``'s output; ``command`` is ``[v, omega]`` (m/s forward,
    rad/s turning left, the diff-drive ``cmd_vel`` convention); ``mode`` is ``[FOLLOW]``,
    ``[SEARCH]`` or ``[STOPPED]``. Both are held between updates, at ``config.rate``.
    """

    def __init__(self, *, config: LineFollowerConfig):
        super().__init__()
        self._config = check_line_follower_config(config)
        self._dt = 1.0 / config.rate
        self._measurement = self.DeclareVectorInputPort("measurement", MEASUREMENT_SIZE)
        initial = np.zeros(_STATE_SIZE)
        initial[_SIDE] = 1.0
        self._state = self.DeclareDiscreteState(initial)
        self.DeclarePeriodicDiscreteUpdateEvent(self._dt, 0.0, self._update)
        self.DeclareVectorOutputPort(
            "command", 2, self._calc_command, {self.discrete_state_ticket(self._state)}
        )
        self.DeclareVectorOutputPort(
            "mode", 1, self._calc_mode, {self.discrete_state_ticket(self._state)}
        )

    def _calc_command(self, context, output):
        output.SetFromVector(context.get_discrete_state(self._state).value()[[_V, _OMEGA]])

    def _calc_mode(self, context, output):
        output.SetFromVector(context.get_discrete_state(self._state).value()[[_MODE]])

    def _update(self, context, discrete_state):
        c, dt = self._config, self._dt
        x = np.array(context.get_discrete_state(self._state).value())
        m = self._measurement.Eval(context)
        if m[FOUND] > 0.5:
            x[_MODE], x[_LOST_TIME], x[_TURNED] = FOLLOW, 0.0, 0.0
            v, omega = follow_command(m, c)
            ahead = m[OFFSET] + c.look_ahead * math.sin(m[HEADING])
            x[_SIDE] = 1.0 if ahead >= 0 else -1.0
        else:
            x[_LOST_TIME] += dt
            if x[_MODE] == FOLLOW and x[_LOST_TIME] >= c.lost_delay:
                x[_MODE] = SEARCH
            if x[_MODE] == FOLLOW:  # a short dropout: keep turning, slow down
                v, omega = min(x[_V], c.min_speed), x[_OMEGA]
            elif x[_MODE] == SEARCH:
                v, omega = 0.0, x[_SIDE] * c.search_omega
                x[_TURNED] += c.search_omega * dt
                if x[_TURNED] >= c.search_turn:
                    x[_MODE], omega = STOPPED, 0.0
            else:
                v, omega = 0.0, 0.0
        step = c.max_acceleration * dt
        x[_V] += float(np.clip(v - x[_V], -step, step))
        x[_OMEGA] = omega
        discrete_state.set_value(self._state, x)
