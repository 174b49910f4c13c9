"""Time-parameterisation of joint paths within per-joint velocity and acceleration limits.

A path is a list of waypoints whose straight-line interpolation was collision-checked. The robot
stops at its first and last waypoints, at repeated waypoints and where the path turns by more
than ``max_corner_angle``; in between, it is timed in *sections*:

* a straight segment alone is traversed rest to rest with the time-optimal trapezoidal (or,
  when short, triangular) profile of the path parameter s in [0, 1]: q(t) = q_k + s(t) d with
  d = q_{k+1} - q_k, ``s_dot <= min_i v_i / |d_i|`` and ``s_ddot <= min_i a_i / |d_i|``;
* a section of several segments becomes a cubic spline q(s) with continuous second derivatives, s
  the cumulative joint-space distance (rad), through all its waypoints, timed from rest to rest by
  TOPP-RA (``planning.timing.toppra``, compiled; Drake's ``Toppra`` gives the same durations
  within 0.2 % at 50 times the cost) without stopping at them. When the spline through the
  waypoints alone strays more than ``path_tolerance`` (joint-space L2, rad) from the straight
  segments, knots are added on the segments near each corner (``blend_knots``) so that the spline
  rounds the corners within the tolerance; when it still strays, the section is split at its
  sharpest corner (a stop). The deviation is measured on 16 samples per knot interval against the
  chord, which lies on the checked path. A section is timed this way only when that is faster than
  stopping at each of its waypoints.

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
import functools

import numpy as np

from planning.timing import cubic
from planning.timing.toppra import time_knots

_SAMPLES_PER_SEGMENT = 16  # spline samples per waypoint interval for the tolerance check
_SAMPLES_PER_GRID_INTERVAL = 16  # timing samples per TOPP-RA grid interval for the limit check
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


# ------------------------------------------------------------------------ rest to rest ----
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


class _Segment:
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


# ----------------------------------------------------------------------------- TOPP-RA ----
@functools.cache
def _seven_joint_plant():
    """A 7-revolute-joint chain: TOPP-RA needs a plant, only its joint count matters here."""
    from pydrake.multibody.plant import MultibodyPlant
    from pydrake.multibody.tree import RevoluteJoint, SpatialInertia

    plant = MultibodyPlant(0.0)
    parent = plant.world_body()
    for i in range(7):
        body = plant.AddRigidBody(f"link{i}", SpatialInertia.SolidSphereWithMass(1.0, 0.05))
        plant.AddJoint(
            RevoluteJoint(f"joint{i}", parent.body_frame(), body.body_frame(), [0, 0, 1])
        )
        parent = body
    plant.Finalize()
    return plant


def _slopes(waypoints: np.ndarray):
    """(knots s_k, rad: the cumulative joint-space distance; the unit directions of the first
    and last segments, the spline's end slopes)."""
    steps = np.diff(waypoints, axis=0)
    knots = np.concatenate([[0.0], np.cumsum(np.linalg.norm(steps, axis=1))])
    return knots, steps[0] / np.linalg.norm(steps[0]), steps[-1] / np.linalg.norm(steps[-1])


def _spline(waypoints: np.ndarray):
    """Returns (q(s) as a PiecewisePolynomial, knots s_k in rad) through the waypoints."""
    from pydrake.trajectories import PiecewisePolynomial

    knots, first, last = _slopes(waypoints)
    path = PiecewisePolynomial.CubicWithContinuousSecondDerivatives(
        knots, waypoints.T, first.reshape(7, 1), last.reshape(7, 1)
    )
    return path, knots


def _cubic(waypoints: np.ndarray):
    """``_spline``'s curve, compiled (``planning.timing.cubic``: the same conditions, continuous
    second derivatives and the given end slopes; equal within 1e-14 rad), which evaluates many
    points at once far faster than Drake's ``vector_values`` and is built faster too.

    Returns:
        (q(s) as a ``cubic.Curve``, knots s_k in rad).
    """
    knots, first, last = _slopes(waypoints)
    values = np.ascontiguousarray(waypoints, dtype=float)
    return cubic.Curve(knots, cubic.clamped(knots, values, first, last)), knots


def grid_points(ddq: cubic.Curve, end: float, options) -> np.ndarray:
    """The TOPP-RA grid on [0, end] by the rule of Drake's ``Toppra.CalcGridPoints``
    (``cubic.grid``, compiled), ``ddq`` the path's second derivative q''(s)."""
    return cubic.grid(
        ddq.c,
        ddq.knots,
        ddq.order,
        float(end),
        float(options.max_err),
        int(options.max_iter),
        float(options.max_seg_length),
        int(options.min_points),
    )


def spline_deviation(waypoints: np.ndarray) -> np.ndarray:
    """Returns, per waypoint interval, the largest distance (rad) of the spline through the
    waypoints from the straight segment between them (sampled)."""
    path, knots = _cubic(waypoints)
    values = np.ascontiguousarray(waypoints, dtype=float)
    return cubic.chord_deviation(path.c, knots, values, _SAMPLES_PER_SEGMENT)


class _Smooth:
    """A spline section timed by TOPP-RA, rest to rest at its ends.

    Dense evaluations (the limit check, the knots' times, path samples) use compiled splines
    (``cubic``); ``sample`` uses Drake's, made on its first call.
    """

    def __init__(self, waypoints, max_velocity, max_acceleration, margin: float):
        from pydrake.multibody.optimization import CalcGridPointsOptions

        self._waypoints = waypoints
        self._path = None  # Drake's spline, made by ``sample`` when first needed
        q, self._knots = _cubic(waypoints)
        self._q, self._dq, self._ddq = q, q.derivative(1), q.derivative(2)
        self._q_end = waypoints[-1].copy()
        options = CalcGridPointsOptions(
            max_err=1e-4, max_iter=100, max_seg_length=0.02, min_points=2 * len(waypoints)
        )
        grid = grid_points(self._ddq, self._knots[-1], options)
        scale = 1.0 - margin
        vmax, amax = scale * max_velocity, scale * max_acceleration
        knots = time_knots(grid, self._dq(grid), self._ddq(grid), vmax, amax)
        if knots is not None:
            times, rate = knots
            self._s_knots = (times, grid, rate)
            s = cubic.hermite(times, grid[:, None], rate[:, None])
            # (ts, order) -> s or its derivative at the times ts
            self._s_eval = lambda ts, order=0: cubic.evaluate(
                s, times, np.ascontiguousarray(ts, dtype=float), order
            )[:, 0]
            self._end = float(times[-1])
            self._drake_s = None  # made by ``sample`` when first needed
        else:  # Drake's own, should ours find none (not seen)
            from pydrake.multibody.optimization import Toppra

            toppra = Toppra(self._drake_path(), _seven_joint_plant(), grid)
            toppra.AddJointVelocityLimit(-vmax, vmax)
            toppra.AddJointAccelerationLimit(-amax, amax)
            drake_s = toppra.SolvePathParameterization()
            if drake_s is None:
                raise RuntimeError("TOPP-RA found no parameterization")
            self._drake_s = drake_s
            rates = [drake_s, drake_s.MakeDerivative(1), drake_s.MakeDerivative(2)]
            self._s_eval = lambda ts, order=0: rates[order].vector_values(ts)[0]
            self._end = drake_s.end_time()
        ts = np.linspace(0.0, self._end, _SAMPLES_PER_GRID_INTERVAL * len(grid) + 1)
        knot_times = self._knot_times(ts)
        # The joint acceleration has a corner where the path passes a knot (the spline's third
        # derivative jumps there), and a corner peak falls between the samples: the knots'
        # times are sampled too (missed, a peak 0.04 % over the limit made the gate refuse a
        # plan; pick-and-place scene 51 of the sweep).
        v, a = self._rates(np.concatenate([ts, knot_times]))
        ratio = max(np.max(np.abs(v) / max_velocity), np.sqrt(np.max(np.abs(a) / max_acceleration)))
        # Slow down until the samples are within (1 - margin / 2) of the limits, so that peaks
        # between samples stay under the limits too.
        self._stretch = max(1.0, float(ratio) / (1.0 - 0.5 * margin))
        self.duration = self._end * self._stretch
        self.waypoint_times = knot_times * self._stretch

    def path_samples(self, resolution: float) -> np.ndarray:
        """Configurations (M, 7) on the spline at most about ``resolution`` rad apart."""
        chord = self._knots[-1]
        speed = np.max(np.linalg.norm(self._dq(self._knots), axis=1))
        n = max(1, int(np.ceil(chord * max(speed, 1.0) / resolution)))
        return self._q(np.linspace(0.0, chord, n + 1))

    def _rates(self, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Returns (v, a) at the times ts (rows) of the unstretched timing."""
        s = np.clip(self._s_eval(ts, 0), 0.0, self._knots[-1])
        sd = self._s_eval(ts, 1)
        sdd = self._s_eval(ts, 2)
        dq = self._dq(s)
        ddq = self._ddq(s)
        return dq * sd[:, None], ddq * (sd**2)[:, None] + dq * sdd[:, None]

    def _knot_times(self, ts: np.ndarray) -> np.ndarray:
        """Times (s, before the stretch) at which the timed spline passes its knots (s(t)
        increases): interpolated from the samples, then refined by Newton steps."""
        s = np.maximum.accumulate(self._s_eval(ts, 0))
        times = np.interp(self._knots, s, ts)
        inner = times[1:-1]  # a view: refined in place
        going = np.ones(len(inner), dtype=bool)
        for _ in range(4):
            rate = self._s_eval(inner, 1)
            going &= rate > 1e-9
            if not going.any():
                break
            step = (self._s_eval(inner, 0) - self._knots[1:-1]) / np.where(going, rate, 1.0)
            inner[going] = np.clip(inner - step, 0.0, self._end)[going]
        times[0], times[-1] = 0.0, self._end
        return times

    def _drake_path(self):
        if self._path is None:
            self._path = _spline(self._waypoints)[0]
        return self._path

    def sample(self, t: float):
        if t >= self.duration:
            return self._q_end.copy(), np.zeros(7), np.zeros(7)
        if self._drake_s is None:
            from pydrake.trajectories import PiecewisePolynomial

            times, grid, rate = self._s_knots
            self._drake_s = PiecewisePolynomial.CubicHermite(
                times, grid.reshape(1, -1), rate.reshape(1, -1)
            )
        s_t, path = self._drake_s, self._drake_path()
        tau, k = max(t, 0.0) / self._stretch, self._stretch
        s = min(max(s_t.value(tau)[0, 0], 0.0), self._knots[-1])
        sd = s_t.EvalDerivative(tau, 1)[0, 0] / k
        sdd = s_t.EvalDerivative(tau, 2)[0, 0] / (k * k)
        dq = path.EvalDerivative(s, 1)[:, 0]
        ddq = path.EvalDerivative(s, 2)[:, 0]
        return path.value(s)[:, 0], dq * sd, ddq * sd * sd + dq * sdd


# ------------------------------------------------------------------------------ timing ----
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
        (knots (M, 7) rad, mask (M,) true at the original waypoints).
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
        waypoints: (N, 7) rad.
        max_velocity: (7,) rad/s.
        max_acceleration: (7,) rad/s^2.
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
                smooth = _Smooth(knots, max_velocity, max_acceleration, options.margin)
                piece = waypoints[i : j + 1]
                if smooth.duration < stopping_time(piece, max_velocity, max_acceleration):
                    self._sections.append(smooth)
                    times.extend(times[-1] + smooth.waypoint_times[mask][1:])
                    self.smoothed.append((i, j))
                    continue
                stopping = [
                    _Segment(waypoints[k], waypoints[k + 1], max_velocity, max_acceleration)
                    for k in range(i, j)
                ]
                stops[stops.index(i) + 1 : stops.index(i) + 1] = list(range(i + 1, j))
            else:
                stopping = [_Segment(waypoints[i], waypoints[j], max_velocity, max_acceleration)]
            for seg in stopping:
                self._sections.append(seg)
                times.append(times[-1] + seg.duration)
        self._starts = np.array([times[k] for k in stops[:-1]])
        self.times = np.array(times)
        self.duration = float(self.times[-1])
        self.stops = stops

    def smoothed_paths(self, resolution: float) -> list[tuple[int, int, np.ndarray]]:
        """Returns ``(i, j, samples)`` per smoothed section: the configurations (M, 7) the
        trajectory passes between waypoints i and j, at most about ``resolution`` rad apart."""
        smooth = [sec for sec in self._sections if isinstance(sec, _Smooth)]
        pairs = zip(self.smoothed, smooth, strict=True)
        return [(i, j, sec.path_samples(resolution)) for (i, j), sec in pairs]

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Returns (q rad, v rad/s, a rad/s^2) at time t s (clamped to [0, duration])."""
        if not self._sections or t >= self.duration:
            return self._q_end.copy(), np.zeros(7), np.zeros(7)
        k = int(np.searchsorted(self._starts, max(t, 0.0), side="right") - 1)
        k = min(max(k, 0), len(self._sections) - 1)
        return self._sections[k].sample(max(t, 0.0) - self._starts[k])
