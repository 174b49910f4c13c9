"""A section of a path through several waypoints, timed without stopping at them: a cubic
spline q(s) through its knots, s the cumulative joint-space distance (rad), timed from rest to
rest by TOPP-RA (``planning.timing.toppra``, compiled) within per-joint velocity and
acceleration limits.

TOPP-RA enforces the limits at its grid points only (``grid_points``: Drake's
``Toppra.CalcGridPoints`` rule), with the limits shrunk by a margin; ``SmoothSection`` then
samples its timing densely (``_SAMPLES_PER_GRID_INTERVAL`` points per grid interval, and the
times it passes its knots) and, where a joint would exceed ``1 - margin / 2`` of a limit, slows
the whole section uniformly (t -> k t scales v by 1/k and a by 1/k^2). ``spline_deviation``
measures how far the spline strays from the straight segments between its knots.

Dense evaluations use compiled splines (``planning.timing.cubic``); Drake's own
(``drake_spline``, ``PiecewisePolynomial``) serve ``SmoothSection.sample`` and the fallback to
Drake's ``Toppra``. See ``planning.timing.retime`` for how a path is cut into sections.
"""

from __future__ import annotations

import functools

import numpy as np

from planning.timing import cubic
from planning.timing.toppra import time_knots

_SAMPLES_PER_SEGMENT = 16  # spline samples per waypoint interval for the tolerance check
_SAMPLES_PER_GRID_INTERVAL = 16  # timing samples per TOPP-RA grid interval for the limit check


@functools.cache
def chain_plant(num_joints: int):
    """A chain of ``num_joints`` revolute joints: TOPP-RA needs a plant, only its joint count
    matters here (made once per count)."""
    from pydrake.multibody.plant import MultibodyPlant
    from pydrake.multibody.tree import RevoluteJoint, SpatialInertia

    plant = MultibodyPlant(0.0)
    parent = plant.world_body()
    for i in range(num_joints):
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


def drake_spline(waypoints: np.ndarray):
    """Returns (q(s) as a PiecewisePolynomial, knots s_k in rad) through the waypoints."""
    from pydrake.trajectories import PiecewisePolynomial

    knots, first, last = _slopes(waypoints)
    path = PiecewisePolynomial.CubicWithContinuousSecondDerivatives(
        knots, waypoints.T, first.reshape(-1, 1), last.reshape(-1, 1)
    )
    return path, knots


def compiled_spline(waypoints: np.ndarray):
    """``drake_spline``'s curve, compiled (``planning.timing.cubic``: the same conditions,
    continuous second derivatives and the given end slopes; equal within 1e-14 rad), which
    evaluates many points at once far faster than Drake's ``vector_values`` and is built
    faster too.

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
    path, knots = compiled_spline(waypoints)
    values = np.ascontiguousarray(waypoints, dtype=float)
    return cubic.chord_deviation(path.c, knots, values, _SAMPLES_PER_SEGMENT)


class SmoothSection:
    """A spline section timed by TOPP-RA, rest to rest at its ends.

    Dense evaluations (the limit check, the knots' times, path samples) use compiled splines
    (``cubic``); ``sample`` uses Drake's, made on its first call.
    """

    def __init__(self, waypoints, max_velocity, max_acceleration, margin: float):
        from pydrake.multibody.optimization import CalcGridPointsOptions

        self._waypoints = waypoints
        self._path = None  # Drake's spline, made by ``sample`` when first needed
        q, self._knots = compiled_spline(waypoints)
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

            toppra = Toppra(self._drake_path(), chain_plant(waypoints.shape[1]), grid)
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
        """Configurations (M, n) on the spline at most about ``resolution`` rad apart."""
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
            self._path = drake_spline(self._waypoints)[0]
        return self._path

    def sample(self, t: float):
        if t >= self.duration:
            return self._q_end.copy(), np.zeros_like(self._q_end), np.zeros_like(self._q_end)
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
