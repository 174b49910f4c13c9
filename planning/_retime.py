"""Time-parameterisation of piecewise-linear joint paths within velocity and acceleration limits.

Each segment q_k -> q_{k+1} is traversed rest to rest along the straight line with a trapezoidal
(or, when short, triangular) profile of the path parameter s in [0, 1]: q(t) = q_k + s(t) d with
d = q_{k+1} - q_k. The largest speed and acceleration of s are set by the most limited joint,
``s_dot <= min_i v_i / |d_i|`` and ``s_ddot <= min_i a_i / |d_i|``, so every joint stays within
its limits and the timed trajectory follows exactly the path that was collision-checked
(a smoothed trajectory would leave it). The cost is a stop at every waypoint; shortcut paths have
few waypoints. Times are deterministic functions of the waypoints and limits.
"""

from __future__ import annotations

import numpy as np


def segment_profiles(
    waypoints: np.ndarray, max_velocity: np.ndarray, max_acceleration: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Returns per segment (duration s, ramp time s, acceleration of s in 1/s^2)."""
    d = np.abs(np.diff(waypoints, axis=0))
    n = len(d)
    duration, ramp, accel = np.zeros(n), np.zeros(n), np.zeros(n)
    for k in range(n):
        moving = d[k] > 1e-12
        if not moving.any():
            continue
        v = float(np.min(max_velocity[moving] / d[k][moving]))
        a = float(np.min(max_acceleration[moving] / d[k][moving]))
        if v * v / a >= 1.0:  # triangular: never reaches v
            t_a = np.sqrt(1.0 / a)
            duration[k] = 2.0 * t_a
        else:
            t_a = v / a
            duration[k] = 1.0 / v + v / a
        ramp[k], accel[k] = t_a, a
    return duration, ramp, accel


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
