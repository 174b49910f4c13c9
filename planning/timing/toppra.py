"""Time-optimal path parameterisation by reachability analysis (TOPP-RA) under per-joint velocity
and acceleration limits, compiled (numba): the same problem as Drake's ``Toppra`` with those two
constraints, about 35 times faster (Drake solves a linear programme per grid point through
``MathematicalProgram``; with two unknowns per stage each is solved here exactly).

The path q(s) is known at grid points s_0 < ... < s_N through q'(s_i) and q''(s_i). The unknowns
are x_i = s_dot^2 at the grid points and u_i = s_ddot, constant on [s_i, s_i+1], so that
x_i+1 = x_i + 2 (s_i+1 - s_i) u_i. At every grid point (collocation) the joint velocities
q' s_dot and accelerations q' u + q'' x stay within the limits, and the motion starts and ends
at rest (x_0 = x_N = 0). A backward pass computes the controllable sets K_i = [low_i, high_i],
the x_i from which the end can still be reached; a forward pass then takes the largest u_i that
keeps x_i+1 in K_i+1 (Pham and Pham, "A new approach to time-optimal path parameterization
based on reachability analysis", IEEE T-RO 2018).

Each stage is a linear programme in (x, u): every constraint bounds u from below or above by a
linear function of x (or bounds x alone), so the x for which some u exists form an interval,
cut by every (lower, upper) pair of bounds.
"""

from __future__ import annotations

import numpy as np
from numba import njit

_EPS = 1e-12
_SLACK = 1e-9  # relative: the forward pass may exceed a bound by this much (rounding)


@njit(cache=True)
def _bound(c_u, c_x, limit, lower, upper, counts, x_range):
    """Adds -limit <= c_u u + c_x x <= limit: bounds of u linear in x (rows of ``lower`` and
    ``upper``, counted in ``counts``), or of x alone (``x_range``)."""
    if c_u > _EPS or c_u < -_EPS:
        first = (-limit if c_u > 0.0 else limit) / c_u
        second = (limit if c_u > 0.0 else -limit) / c_u
        lower[counts[0], 0] = first
        lower[counts[0], 1] = -c_x / c_u
        upper[counts[1], 0] = second
        upper[counts[1], 1] = -c_x / c_u
        counts[0] += 1
        counts[1] += 1
    elif abs(c_x) > _EPS:
        x_range[1] = min(x_range[1], limit / abs(c_x))  # x >= 0 always


@njit(cache=True)
def _stage(dq, ddq, dq_next, ddq_next, vmax, amax, step, low, high):
    """The bounds of u at stage i as linear functions of x, and the x interval they allow.

    Returns (lower (K, 2), n_lower, upper (K, 2), n_upper, x_min, x_max): u >= a + b x for the
    rows (a, b) of lower, u <= c + d x for those of upper; x within [x_min, x_max] (x_min >
    x_max when nothing is feasible). ``step`` is s_i+1 - s_i (0 at the last grid point, which
    has no transition), [low, high] the next controllable set. The accelerations are bounded at
    both ends of the interval (Drake's ``kInterpolation``: at s_i+1 with x + 2 step u), which
    keeps the peaks between grid points low.
    """
    dims = len(dq)
    lower = np.empty((2 * dims + 1, 2))
    upper = np.empty((2 * dims + 1, 2))
    counts = np.zeros(2, dtype=np.int64)
    x_range = np.array([0.0, np.inf])
    for j in range(dims):
        speed = abs(dq[j])
        if speed > _EPS:
            x_range[1] = min(x_range[1], (vmax[j] / speed) ** 2)
        _bound(dq[j], ddq[j], amax[j], lower, upper, counts, x_range)
        if step > 0.0:
            c_u = dq_next[j] + 2.0 * step * ddq_next[j]
            _bound(c_u, ddq_next[j], amax[j], lower, upper, counts, x_range)
    if step > 0.0:  # low <= x + 2 step u <= high
        lower[counts[0], 0] = low / (2.0 * step)
        lower[counts[0], 1] = -1.0 / (2.0 * step)
        upper[counts[1], 0] = high / (2.0 * step)
        upper[counts[1], 1] = -1.0 / (2.0 * step)
        counts += 1
    x_min, x_max = x_range[0], x_range[1]
    for k in range(counts[0]):  # a + b x <= c + d x for every pair
        for m in range(counts[1]):
            slope = lower[k, 1] - upper[m, 1]
            room = upper[m, 0] - lower[k, 0]
            if slope > _EPS:
                x_max = min(x_max, room / slope)
            elif slope < -_EPS:
                x_min = max(x_min, room / slope)
            elif room < -_EPS * (1.0 + abs(lower[k, 0])):
                x_max = -1.0  # parallel bounds that never meet
    return lower, counts[0], upper, counts[1], x_min, x_max


@njit(cache=True)
def solve(grid, dq, ddq, vmax, amax):
    """x_i = s_dot^2 at the grid points (N + 1,), rest to rest, or an empty array when no
    parameterisation exists. ``dq``, ``ddq``: (N + 1, J) path derivatives at the grid points;
    ``vmax``, ``amax``: (J,) limits."""
    n = len(grid)
    low = np.zeros(n)
    high = np.zeros(n)  # K_N = {0}: at rest at the end
    last = n - 1
    _, _, _, _, x_min, x_max = _stage(
        dq[last], ddq[last], dq[last], ddq[last], vmax, amax, 0.0, 0.0, 0.0
    )
    if x_min > 0.0 or x_max < 0.0:
        return np.empty(0)
    for i in range(n - 2, -1, -1):
        step = grid[i + 1] - grid[i]
        _, _, _, _, x_min, x_max = _stage(
            dq[i], ddq[i], dq[i + 1], ddq[i + 1], vmax, amax, step, low[i + 1], high[i + 1]
        )
        if x_min > x_max * (1.0 + _SLACK) + _EPS:
            return np.empty(0)
        low[i] = x_min
        high[i] = max(x_min, x_max)
    if low[0] > _EPS:
        return np.empty(0)  # cannot start at rest
    x = np.zeros(n)
    for i in range(n - 1):
        step = grid[i + 1] - grid[i]
        lower, n_lower, upper, n_upper, _, _ = _stage(
            dq[i], ddq[i], dq[i + 1], ddq[i + 1], vmax, amax, step, low[i + 1], high[i + 1]
        )
        u_low = -np.inf
        u_high = np.inf
        for k in range(n_lower):
            u_low = max(u_low, lower[k, 0] + lower[k, 1] * x[i])
        for m in range(n_upper):
            u_high = min(u_high, upper[m, 0] + upper[m, 1] * x[i])
        if u_low > u_high + _SLACK * (1.0 + abs(u_high)):
            return np.empty(0)
        x[i + 1] = min(max(x[i] + 2.0 * step * u_high, 0.0), high[i + 1])
    x[n - 1] = 0.0
    return x


def time_knots(grid, dq, ddq, max_velocity, max_acceleration):
    """The time-optimal s(t) through the ``grid`` points (N + 1,) of a path whose derivatives
    there are ``dq``, ``ddq`` (N + 1, J), rest to rest: (times, rates), the time at which s
    reaches each grid point and s_dot there (s(t) is quadratic between them: the cubic Hermite
    pieces through (times, grid, rates) are exact); None when there is none."""
    grid = np.asarray(grid, dtype=float)
    x = solve(
        grid,
        np.ascontiguousarray(dq, dtype=float),
        np.ascontiguousarray(ddq, dtype=float),
        np.asarray(max_velocity, dtype=float),
        np.asarray(max_acceleration, dtype=float),
    )
    if len(x) == 0:
        return None
    rate = np.sqrt(x)
    mean = rate[:-1] + rate[1:]
    if np.any(mean <= 0.0):
        return None  # a stop inside the path: no finite time across it
    times = np.concatenate([[0.0], np.cumsum(2.0 * np.diff(grid) / mean)])
    return times, rate


def parameterize(path, grid: np.ndarray, max_velocity, max_acceleration):
    """The time-optimal s(t) along ``path`` (a Drake ``PiecewisePolynomial`` q(s)) under the
    limits at the ``grid`` points, rest to rest, as a ``PiecewisePolynomial`` (piecewise
    quadratic, written as cubic Hermite pieces: exact); None when there is none."""
    from pydrake.trajectories import PiecewisePolynomial

    grid = np.asarray(grid, dtype=float)
    dq = path.MakeDerivative(1).vector_values(grid).T
    ddq = path.MakeDerivative(2).vector_values(grid).T
    knots = time_knots(grid, dq, ddq, max_velocity, max_acceleration)
    if knots is None:
        return None
    times, rate = knots
    return PiecewisePolynomial.CubicHermite(times, grid.reshape(1, -1), rate.reshape(1, -1))


def warm_up() -> None:
    """Compiles (about 2 s, once per machine) or loads ``solve`` now rather than in a request."""
    grid = np.linspace(0.0, 1.0, 3)
    solve(grid, np.tile(np.eye(7)[0], (3, 1)), np.zeros((3, 7)), np.ones(7), np.ones(7))
