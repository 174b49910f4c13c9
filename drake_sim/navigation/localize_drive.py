"""Driving while the localisation finds itself (global localisation, no first guess).

Turning on the spot is enough where one full scan tells the places apart (the TurtleBot3
world). It is not in a building of repeated aisles seen by a 3.5 m lidar (nav2's depot: from
its start the scans of two places a few metres apart are the same), so, as a nav2 user with a
joystick does, the robot drives a little and looks again: it turns a full turn, then turns to the
most open direction of its latest scan (not back the way it came) and drives up to
``leg`` m that way, stopping early when the corridor ahead closes, then turns a full turn
again, and so on. Everything is decided in the robot's own frame, from the scan and the
measured twist (the map pose is what is being searched for, so it is not used).

``step`` is called once a control cycle; ``LocalizeDrive`` is its (immutable) state.
"""

import dataclasses as dc
import math

import numpy as np

from drake_sim.base.planar import wrap_angle

DIRECTIONS = np.radians(np.arange(-180, 180, 10))
"""Candidate leg directions in the robot's frame (rad)."""
MARGIN = 0.1  # m kept beyond the robot's radius, sideways and ahead.
MIN_LEG = 0.3  # m: a direction more closed than this is not driven.
STOP_TURN = 0.03  # rad: a turn to a leg's direction ends this close to it.


@dc.dataclass(frozen=True)
class LocalizeDrive:
    """Where the exploratory localisation is.

    Attributes:
        phase: "spin" (a full turn), "turn" (to the leg's direction) or "drive".
        left: rad left to turn ("spin", "turn") or m left to drive ("drive").
        sign: +1 turns left, -1 right ("turn").
        yaw: rad, the heading integrated from the measured twist (odometry frame).
        back: rad in that frame, where the last leg came from (None before one).
        distance: m, the leg to drive after this turn.
        driven: m driven in all (the measured twist's, forwards).
    """

    phase: str = "spin"
    left: float = 2 * math.pi
    sign: float = 1.0
    yaw: float = 0.0
    back: float | None = None
    distance: float = 0.0
    driven: float = 0.0


def step(
    state: LocalizeDrive,
    twist,
    points: np.ndarray,
    dt: float,
    *,
    radius: float,
    leg: float,
    speed: float,
    spin: float,
) -> tuple[LocalizeDrive, float, float]:
    """One control cycle of ``dt`` s: the new state and the command (v m/s, omega rad/s).

    Args:
        twist: the measured (v, omega) over the last cycle.
        points: (n, 2) the latest scan's returns in the base frame (m).
        radius: m, the robot's (inscribed) radius.
        leg: m, the longest drive between turns (0: turn on the spot only).
        speed: m/s, the drive's; spin: rad/s, the turns'.
    """
    v_meas, w_meas = (float(u) for u in twist)
    s = dc.replace(state, yaw=state.yaw + w_meas * dt, driven=state.driven + abs(v_meas) * dt)
    if s.phase == "spin":
        s = dc.replace(s, left=s.left - abs(w_meas) * dt)
        if s.left > 0 or leg <= 0:
            return dc.replace(s, left=s.left if s.left > 0 else 2 * math.pi), 0.0, spin
        heading, room = _most_open(points, radius, s.back, s.yaw)
        if room < MIN_LEG:  # boxed in: look again
            return dc.replace(s, left=2 * math.pi), 0.0, spin
        s = dc.replace(
            s,
            phase="turn",
            left=abs(heading),
            sign=math.copysign(1.0, heading),
            back=s.yaw + heading + math.pi,  # the leg's way back, once driven
            distance=min(leg, room),
        )
        return _turn(s, spin)
    if s.phase == "turn":
        return _turn(dc.replace(s, left=s.left - abs(w_meas) * dt), spin)
    left = s.left - max(v_meas, 0.0) * dt
    ahead = clear_length(points, 0.0, radius)
    if left <= 0 or ahead < MARGIN:
        return dc.replace(s, phase="spin", left=2 * math.pi), 0.0, 0.0
    return dc.replace(s, left=left), min(speed, ahead), 0.0


def _turn(s: LocalizeDrive, spin: float) -> tuple[LocalizeDrive, float, float]:
    """Turning to the leg's direction; at it, the drive of ``s.distance`` m starts."""
    if s.left <= STOP_TURN:
        return dc.replace(s, phase="drive", left=s.distance), 0.0, 0.0
    rate = max(0.2, min(spin, 2.0 * s.left))  # slows into the heading
    return s, 0.0, s.sign * rate


def clear_length(points: np.ndarray, heading: float, radius: float) -> float:
    """m the robot's centre can move along ``heading`` (base frame, rad) before its circle
    plus ``MARGIN`` would reach a scan point of ``points`` (n, 2); ``inf`` if none is in the
    way."""
    c, s = math.cos(heading), math.sin(heading)
    along = points[:, 0] * c + points[:, 1] * s
    across = -points[:, 0] * s + points[:, 1] * c
    half = radius + MARGIN
    hit = (along > 0) & (np.abs(across) < half)
    return float(np.min(along[hit]) - half) if np.any(hit) else math.inf


def _most_open(points, radius, back, yaw) -> tuple[float, float]:
    """(heading in the base frame, room in m) of the most open of ``DIRECTIONS``, not within
    90 degrees of ``back`` (odometry frame, the robot at ``yaw``) unless nothing else is open;
    ties go to the smallest turn."""
    room = np.array([clear_length(points, h, radius) for h in DIRECTIONS])
    room = np.minimum(room, 1e3)
    if back is not None:
        behind = np.abs(wrap_angle(DIRECTIONS + yaw - back)) < math.pi / 2
        if np.any(~behind & (room >= MIN_LEG)):
            room = np.where(behind, -1.0, room)
    best = np.flatnonzero(room >= room.max() - 0.05)
    pick = best[np.argmin(np.abs(DIRECTIONS[best]))]
    return float(DIRECTIONS[pick]), float(room[pick])


def scan_points(ranges, angles, X_base_sensor) -> np.ndarray:
    """(n, 2) the finite returns of a scan in the base frame (the lidar at ``X_base_sensor``)."""
    ranges, angles = np.asarray(ranges, dtype=float), np.asarray(angles, dtype=float)
    keep = np.isfinite(ranges)
    x, y, yaw = X_base_sensor
    local = np.column_stack(
        [ranges[keep] * np.cos(angles[keep] + yaw), ranges[keep] * np.sin(angles[keep] + yaw)]
    )
    return local + [x, y]
