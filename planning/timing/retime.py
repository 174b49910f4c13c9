"""Time-parameterisation of joint paths within per-joint velocity and acceleration limits.

A path is a list of waypoints whose straight-line interpolation was collision-checked. The robot
stops at its first and last waypoints, at repeated waypoints and where the path turns by more
than ``max_corner_angle``; in between, it is timed in *sections*:

* a straight segment alone is traversed rest to rest with the time-optimal trapezoidal (or,
  when short, triangular) profile of the path parameter s in [0, 1]: q(t) = q_k + s(t) d with
  d = q_{k+1} - q_k, ``s_dot <= min_i v_i / |d_i|`` and ``s_ddot <= min_i a_i / |d_i|``
  (``planning.timing.rest_to_rest``);
* a section of several segments becomes a cubic spline q(s) with continuous second derivatives, s
  the cumulative joint-space distance (rad), through all its waypoints, timed from rest to rest by
  TOPP-RA (``planning.timing.toppra``, compiled; Drake's ``Toppra`` gives the same durations
  within 0.2 % at 50 times the cost) without stopping at them (``planning.timing.spline_section``).
  When the spline through the waypoints alone strays more than ``path_tolerance`` (joint-space
  L2, rad) from the straight segments, knots are added on the segments near each corner
  (``blend_knots``) so that the spline rounds the corners within the tolerance; when it still
  strays, the section is split at its sharpest corner (a stop). The deviation is measured on 16
  samples per knot interval against the chord, which lies on the checked path. A section is timed
  this way only when that is faster than stopping at each of its waypoints.

So the timed trajectory passes through every waypoint and stays within ``path_tolerance`` of the
checked path (``Plan.validate`` also checks the smoothed parts themselves). TOPP-RA enforces the
limits at its grid points only, with the limits shrunk by ``margin``; the timing is then sampled
densely (16 points per grid interval) and, where a joint would exceed ``1 - margin / 2`` of a
limit, the whole section is slowed uniformly (t -> k t scales v by 1/k and a by 1/k^2). Results
are deterministic functions of the waypoints, limits and options.

Measured (Panda limits, pick-and-place scene): a 20 cm Cartesian line of 41 waypoints, 2.37 s
rest to rest, takes 0.40 s; a KTO-smoothed path of 486 waypoints 9.7 s -> 0.51 s; shortcut
RRT paths (2 to 4 segments) gain 0 to 10 %: corners turning by 0.5 rad or more allow little
speed within a 2 mrad blend. Timing a smoothed section costs about 1 ms in TOPP-RA plus the
dense check of its limits (Drake's TOPP-RA took 7 to 35 ms), nothing for straight segments.

Reference:
    H. Pham, Q.-C. Pham, "A new approach to time-optimal path parameterization based on
    reachability analysis", IEEE T-RO 2018.
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np

from planning.timing.rest_to_rest import Segment, stopping_time
from planning.timing.spline_section import SmoothSection, spline_deviation

_BLEND_GAIN = 4.0  # measured: 1 and 2 gave longer durations on RRT paths


@dc.dataclass
class RetimeOptions:
    """How a path is timed (stored in plan files).

    Attributes:
        method: "toppra" (stops only at sharp corners) or "rest_to_rest" (stops at every
            waypoint; the timing of version-1 plan files).
        max_corner_angle: rad, in [0, pi); the robot stops at waypoints where the path turns
            by more.
        path_tolerance: rad; largest joint-space L2 distance between a smoothed section and
            the straight segments it replaces.
        margin: fraction by which TOPP-RA's limits are shrunk (its grid misses the peaks).
    """

    method: str = "toppra"
    max_corner_angle: float = 1.0
    path_tolerance: float = 0.002
    margin: float = 0.01

    def __post_init__(self):
        if self.method not in ("toppra", "rest_to_rest"):
            raise ValueError(f"unknown timing method {self.method!r}")
        # Ends and repeated waypoints turn by pi: an angle of pi or more would stop nowhere.
        if not 0 <= self.max_corner_angle < np.pi:
            raise ValueError(f"max_corner_angle must be in [0, pi), got {self.max_corner_angle}")
        if self.path_tolerance < 0 or not 0 <= self.margin < 0.5:
            raise ValueError(f"bad RetimeOptions {self}")


def _turns(waypoints: np.ndarray) -> np.ndarray:
    """The turning angle (rad) of the path at each waypoint; pi at the ends and at repeats."""
    steps = np.diff(waypoints, axis=0)
    norms = np.linalg.norm(steps, axis=1)
    turn = np.full(len(waypoints), np.pi)
    a, b = steps[:-1], steps[1:]
    ok = (norms[:-1] > 1e-12) & (norms[1:] > 1e-12)
    c = np.einsum("ij,ij->i", a, b) / np.where(ok, norms[:-1] * norms[1:], 1.0)
    turn[1:-1] = np.where(ok, np.arccos(np.clip(c, -1.0, 1.0)), np.pi)
    return turn


def blend_knots(waypoints: np.ndarray, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """Adds knots on the straight segments at h, 2h and 3h from every interior corner, with
    h = min(4 tolerance / turn, an eighth of either segment), so that a spline through them
    rounds the corner by about tolerance / 2 (a cubic spline through points h apart around a
    corner turning by theta strays about h theta / 8 from it).

    Returns:
        (knots (M, n) rad, mask (M,) true at the original waypoints).
    """
    turn = _turns(waypoints)
    lengths = np.linalg.norm(np.diff(waypoints, axis=0), axis=1)
    n = len(waypoints)
    h = np.zeros(n)
    for k in range(1, n - 1):
        blend = _BLEND_GAIN * tolerance / max(turn[k], 1e-9)
        h[k] = min(blend, lengths[k - 1] / 8, lengths[k] / 8)
    knots, mask = [waypoints[0]], [True]
    for k in range(n - 1):
        a, d, length = waypoints[k], waypoints[k + 1] - waypoints[k], lengths[k]
        fractions = [m * h[k] / length for m in (1, 2, 3) if h[k] > 0]
        fractions += [1 - m * h[k + 1] / length for m in (3, 2, 1) if h[k + 1] > 0]
        for f in sorted(x for x in fractions if 0 < x < 1):
            knots.append(a + f * d)
            mask.append(False)
        knots.append(waypoints[k + 1])
        mask.append(True)
    return np.array(knots), np.array(mask)


def plan_sections(waypoints: np.ndarray, options: RetimeOptions) -> list[tuple]:
    """Splits the path where the robot stops and smooths the sections in between.

    Returns:
        One ``(i, j, knots, mask)`` per section from waypoint i to waypoint j: ``knots`` is
        None for a straight segment (j = i + 1), else the spline's knots (the waypoints, with
        blend knots when the spline through the waypoints alone strays too far) and ``mask``
        marks the waypoints among them.
    """
    n = len(waypoints)
    if options.method == "rest_to_rest" or n <= 2:
        return [(k, k + 1, None, None) for k in range(n - 1)]
    turn = _turns(waypoints)
    stops = [k for k in range(n) if turn[k] > options.max_corner_angle]
    pending = [(stops[i], stops[i + 1]) for i in range(len(stops) - 1)]
    out = []
    tol = options.path_tolerance
    while pending:
        i, j = pending.pop(0)
        if j - i == 1:
            out.append((i, j, None, None))
            continue
        piece = waypoints[i : j + 1]
        knots, mask = piece, np.ones(len(piece), dtype=bool)
        deviation = np.max(spline_deviation(knots))
        if deviation > tol:
            knots, mask = blend_knots(piece, tol)
            deviation = np.max(spline_deviation(knots))
        if deviation <= tol:
            out.append((i, j, knots, mask))
            continue
        m = i + 1 + int(np.argmax(turn[i + 1 : j]))  # stop at the sharpest corner
        pending[:0] = [(i, m), (m, j)]
    return out


class Timing:
    """The timed trajectory through a path's waypoints (see the module docstring).

    Args:
        waypoints: (N, n) rad (or m).
        max_velocity: (n,) rad/s.
        max_acceleration: (n,) rad/s^2.
        options: how to time; ``RetimeOptions()`` when None.
    """

    def __init__(self, waypoints, max_velocity, max_acceleration, options=None):
        options = options if options is not None else RetimeOptions()
        waypoints = np.asarray(waypoints, dtype=float)
        self._q_end = waypoints[-1].copy()
        sections = plan_sections(waypoints, options)
        stops = [i for i, _, _, _ in sections] + [len(waypoints) - 1]
        self._sections = []
        self.smoothed: list[tuple[int, int]] = []  # (i, j): waypoints i..j timed without stops
        times = [0.0]
        for i, j, knots, mask in sections:
            if knots is not None:
                smooth = SmoothSection(knots, max_velocity, max_acceleration, options.margin)
                piece = waypoints[i : j + 1]
                if smooth.duration < stopping_time(piece, max_velocity, max_acceleration):
                    self._sections.append(smooth)
                    times.extend(times[-1] + smooth.waypoint_times[mask][1:])
                    self.smoothed.append((i, j))
                    continue
                stopping = [
                    Segment(waypoints[k], waypoints[k + 1], max_velocity, max_acceleration)
                    for k in range(i, j)
                ]
                stops[stops.index(i) + 1 : stops.index(i) + 1] = list(range(i + 1, j))
            else:
                stopping = [Segment(waypoints[i], waypoints[j], max_velocity, max_acceleration)]
            for seg in stopping:
                self._sections.append(seg)
                times.append(times[-1] + seg.duration)
        self._starts = np.array([times[k] for k in stops[:-1]])
        self.times = np.array(times)
        self.duration = float(self.times[-1])
        self.stops = stops

    def smoothed_paths(self, resolution: float) -> list[tuple[int, int, np.ndarray]]:
        """Returns ``(i, j, samples)`` per smoothed section: the configurations (M, n) the
        trajectory passes between waypoints i and j, at most about ``resolution`` rad apart."""
        smooth = [sec for sec in self._sections if isinstance(sec, SmoothSection)]
        pairs = zip(self.smoothed, smooth, strict=True)
        return [(i, j, sec.path_samples(resolution)) for (i, j), sec in pairs]

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Returns (q rad, v rad/s, a rad/s^2) at time t s (clamped to [0, duration])."""
        if not self._sections or t >= self.duration:
            return self._q_end.copy(), np.zeros_like(self._q_end), np.zeros_like(self._q_end)
        k = int(np.searchsorted(self._starts, max(t, 0.0), side="right") - 1)
        k = min(max(k, 0), len(self._sections) - 1)
        return self._sections[k].sample(max(t, 0.0) - self._starts[k])
