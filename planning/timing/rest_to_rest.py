"""Rest-to-rest timing of straight segments: the time-optimal trapezoidal (or, when short,
triangular) profile of the path parameter s in [0, 1] along a joint displacement d.

The motion is q(t) = q_a + s(t) d with ``s_dot <= min_i v_i / |d_i|`` and
``s_ddot <= min_i a_i / |d_i|`` (per-joint velocity limits v and acceleration limits a): the
profile accelerates at the largest rate, cruises at the largest speed when it reaches it, and
brakes to rest at the end. ``planning.timing.retime`` times a path's straight sections this way,
and compares a smoothed section's duration with ``stopping_time``.
"""

from __future__ import annotations

import numpy as np


def segment_profile(d: np.ndarray, max_velocity, max_acceleration) -> tuple[float, float, float]:
    """Returns (duration s, ramp time s, acceleration of s in 1/s^2) of the rest-to-rest motion
    along the joint displacement d (rad)."""
    d = np.abs(d)
    moving = d > 1e-12
    if not moving.any():
        return 0.0, 0.0, 0.0
    v = float(np.min(max_velocity[moving] / d[moving]))
    a = float(np.min(max_acceleration[moving] / d[moving]))
    if v * v / a >= 1.0:  # triangular: never reaches v
        t_a = np.sqrt(1.0 / a)
        return 2.0 * t_a, t_a, a
    return 1.0 / v + v / a, v / a, a


def sample_segment(t: float, duration: float, ramp: float, accel: float):
    """Returns (s, s_dot, s_ddot) of a rest-to-rest profile at time t in [0, duration]."""
    if duration <= 0.0:
        return 1.0, 0.0, 0.0
    t = min(max(t, 0.0), duration)
    v_peak = accel * ramp
    if t < ramp:
        return 0.5 * accel * t * t, accel * t, accel
    if t <= duration - ramp:
        return 0.5 * accel * ramp * ramp + v_peak * (t - ramp), v_peak, 0.0
    r = duration - t
    return 1.0 - 0.5 * accel * r * r, accel * r, -accel


def stopping_time(waypoints: np.ndarray, max_velocity, max_acceleration) -> float:
    """The total of ``segment_profile``'s durations over the path's segments, s (one numpy pass:
    what stopping at every waypoint would take)."""
    d = np.abs(np.diff(waypoints, axis=0))
    moving = d > 1e-12
    with np.errstate(divide="ignore"):
        v = np.min(np.where(moving, max_velocity / np.where(moving, d, 1.0), np.inf), axis=1)
        a = np.min(np.where(moving, max_acceleration / np.where(moving, d, 1.0), np.inf), axis=1)
    rows = moving.any(axis=1)
    v, a = v[rows], a[rows]
    triangular = v * v / a >= 1.0
    total = np.where(triangular, 2.0 * np.sqrt(1.0 / a), 1.0 / v + v / a)
    return float(total.sum())


class Segment:
    """A straight segment between two waypoints, rest to rest."""

    def __init__(self, q_a, q_b, max_velocity, max_acceleration):
        self.q_a, self.d = q_a, q_b - q_a
        self.duration, self._ramp, self._accel = segment_profile(
            self.d, max_velocity, max_acceleration
        )
        self.waypoint_times = np.array([0.0, self.duration])

    def sample(self, t: float):
        s, s_dot, s_ddot = sample_segment(t, self.duration, self._ramp, self._accel)
        return self.q_a + s * self.d, s_dot * self.d, s_ddot * self.d
