"""Options of ``MotionPlanningInterface`` (the ``interface`` section of the pick-and-place
scenario). Units: s, rad, m. No ``from __future__ import annotations``: the YAML loader reads the
field types at run time."""

import dataclasses as dc


@dc.dataclass
class InterfaceOptions:
    """How the interface executes and decides that a motion has finished."""

    poll_period: float = 0.01  # s of simulated time between checks of running actions
    start_tolerance: float = 0.02  # rad, largest joint gap between a plan's start and the robot
    goal_tolerance: float = 0.01  # rad, largest joint error at the end of a successful execution
    settle_time: float = 0.05  # s after the commanded motion ends before checking the arm
    settle_velocity: float = 0.05  # rad/s, the arm counts as at rest below this
    settle_timeout: float = 1.0  # s after the commanded end, at most, before deciding
    finger_speed: float = 0.05  # m/s per finger (the Franka hand: 0.1 m/s in width)
    finger_tolerance: float = 0.002  # m, a finger this close to its target reached it
    finger_settle_velocity: float = 0.005  # m/s, the fingers count as at rest below this
    finger_settle_timeout: float = 0.5  # s after the commanded end, at most
