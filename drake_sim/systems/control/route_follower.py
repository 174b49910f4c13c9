"""Drives a diff-drive robot through a route's waypoints: the scripted stand-in for a person at
the teleop keys during mapping.

At each waypoint the robot turns on the spot towards the next one, then drives straight at it,
steering out small heading errors, and slows down as it arrives: the motion SLAM handles best
(no fast turns while moving). It is given the robot's true pose, as a person at the keys sees
the robot; the mapping itself never uses that pose.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem

from drake_sim.base.checks import fields_of, require_positive
from drake_sim.base.planar import wrap_angle


@dc.dataclass
class RouteFollowerConfig:
    """Speeds, gains and tolerances of the route follower."""

    rate: float = 20.0  # Hz, command updates.
    speed: float = 0.2  # m/s, cruising speed between waypoints.
    turn_rate: float = 0.6  # rad/s, largest turn rate (on the spot and while driving).
    heading_gain: float = 2.0  # rad/s of turn per rad of heading error.
    distance_gain: float = 1.0  # m/s per m left to the waypoint, when slowing down to it.
    # rad: a heading error above this stops the robot and turns it on the spot; it drives on
    # once the error is below a third of it.
    turn_in_place: float = 0.25
    tolerance: float = 0.05  # m: a waypoint this close is reached.


def check_route_follower_config(config: RouteFollowerConfig, where: str = "route_follower"):
    """Returns ``config`` if every value is finite and positive; else raises ``ConfigError``."""
    require_positive(where, fields_of(config, (f.name for f in dc.fields(config))))
    return config


# Layout of the follower's discrete state.
_COMMAND = slice(0, 2)  # [v, omega] m/s, rad/s.
_INDEX = 2  # The waypoint driven to; len(waypoints) once the route is done.
_TURNING = 3  # 1 while turning on the spot.


def route_command(
    pose, target, turning: bool, config: RouteFollowerConfig
) -> tuple[float, float, bool]:
    """The command ``(v, omega, turning)`` that takes a robot at ``pose`` ([x, y, yaw]) towards
    ``target`` ([x, y]), given whether it was turning on the spot."""
    dx, dy = target[0] - pose[0], target[1] - pose[1]
    error = wrap_angle(math.atan2(dy, dx) - pose[2])
    if abs(error) > config.turn_in_place:
        turning = True
    elif abs(error) < config.turn_in_place / 3:
        turning = False
    omega = float(np.clip(config.heading_gain * error, -config.turn_rate, config.turn_rate))
    if turning:
        return 0.0, omega, True
    distance = math.hypot(dx, dy)
    v = min(config.speed, config.distance_gain * distance) * math.cos(error)
    return v, omega, False


class RouteFollower(LeafSystem):
    """Drives through ``waypoints`` in order, then stops.

    .. pydrake_system::

        name: RouteFollower
        input_ports:
        - pose
        output_ports:
        - command
        - done

    ``pose`` is the robot's ``[x, y, yaw]`` (m, m, rad); ``command`` the ``cmd_vel``
    ``[v, omega]`` (m/s, rad/s) for a ``DiffDriveController``; ``done`` is ``[1]`` once the
    last waypoint is reached (the command is then zero), else ``[0]``. Updated at
    ``config.rate``.
    """

    def __init__(self, *, waypoints, config: RouteFollowerConfig):
        super().__init__()
        self._waypoints = np.asarray(waypoints, dtype=float).reshape(-1, 2)
        self._config = config
        self._pose = self.DeclareVectorInputPort("pose", 3)
        self._state = self.DeclareDiscreteState(4)
        self.DeclarePeriodicDiscreteUpdateEvent(1.0 / config.rate, 0.0, self._update)
        ticket = {self.discrete_state_ticket(self._state)}
        self.DeclareVectorOutputPort(
            "command",
            2,
            lambda context, out: out.SetFromVector(
                context.get_discrete_state(self._state).value()[_COMMAND]
            ),
            ticket,
        )
        self.DeclareVectorOutputPort("done", BasicVector(1), self._calc_done, ticket)

    def waypoint_index(self, context) -> int:
        """The index of the waypoint being driven to (``len(waypoints)`` when done)."""
        return int(context.get_discrete_state(self._state).value()[_INDEX])

    def _calc_done(self, context, output):
        output.SetFromVector([float(self.waypoint_index(context) >= len(self._waypoints))])

    def _update(self, context, discrete_state):
        x = np.array(context.get_discrete_state(self._state).value())
        pose = self._pose.Eval(context)
        index = int(x[_INDEX])
        while index < len(self._waypoints):
            if np.hypot(*(self._waypoints[index] - pose[:2])) > self._config.tolerance:
                break
            index += 1
            x[_TURNING] = 0.0
        if index >= len(self._waypoints):
            x[_COMMAND] = 0.0
        else:
            v, omega, turning = route_command(
                pose, self._waypoints[index], bool(x[_TURNING]), self._config
            )
            x[_COMMAND] = v, omega
            x[_TURNING] = float(turning)
        x[_INDEX] = index
        discrete_state.get_mutable_vector(self._state).SetFromVector(x)
