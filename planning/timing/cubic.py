"""Piecewise cubic curves, compiled (numba): the splines that ``planning.timing.retime`` builds
and evaluates many times per plan.

A curve is its knots s_0 < ... < s_n and coefficients ``c`` (4, n, J), highest power first in
(s - s_k) on [s_k, s_k+1) (scipy's ``PPoly`` layout, and its rule at the ends: the first and
last pieces extend beyond the knots). Built and evaluated here, a plan's timing makes a few
dozen such calls; through scipy each cost 20 to 50 us of Python overhead (measured: 0.6 ms of
the 4 ms a 30-waypoint Cartesian plan took to time).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def evaluate(c, knots, x, order):
    """The ``order``-th derivative (0 to 3) of the curve at the points x (M,): (M, J)."""
    n = c.shape[1]
    out = np.empty((len(x), c.shape[2]))
    for m in range(len(x)):
        k = np.searchsorted(knots, x[m], side="right") - 1
        k = min(max(k, 0), n - 1)
        h = x[m] - knots[k]
        for j in range(c.shape[2]):
            a, b, d, e = c[0, k, j], c[1, k, j], c[2, k, j], c[3, k, j]
            if order == 0:
                out[m, j] = ((a * h + b) * h + d) * h + e
            elif order == 1:
                out[m, j] = (3.0 * a * h + 2.0 * b) * h + d
            elif order == 2:
                out[m, j] = 6.0 * a * h + 2.0 * b
            else:
                out[m, j] = 6.0 * a
    return out


@njit(cache=True)
def hermite(knots, values, slopes):
    """The cubic Hermite pieces through ``values`` (n + 1, J) with ``slopes`` (n + 1, J) at the
    knots: coefficients (4, n, J)."""
    n = len(knots) - 1
    c = np.empty((4, n, values.shape[1]))
    for k in range(n):
        h = knots[k + 1] - knots[k]
        for j in range(values.shape[1]):
            chord = (values[k + 1, j] - values[k, j]) / h
            c[0, k, j] = (slopes[k, j] + slopes[k + 1, j] - 2.0 * chord) / (h * h)
            c[1, k, j] = (3.0 * chord - 2.0 * slopes[k, j] - slopes[k + 1, j]) / h
            c[2, k, j] = slopes[k, j]
            c[3, k, j] = values[k, j]
    return c


@njit(cache=True)
def clamped(knots, values, first, last):
    """The cubic spline with continuous second derivatives through ``values`` (n + 1, J) at the
    knots, with the slopes ``first`` and ``last`` (J,) at its ends: coefficients (4, n, J).

    The knots' slopes m solve h_i m_(i-1) + 2 (h_(i-1) + h_i) m_i + h_(i-1) m_(i+1) =
    3 (h_i d_(i-1) + h_(i-1) d_i), h the knot intervals and d the chords' slopes: a
    tridiagonal, diagonally dominant system, solved by elimination without pivoting
    (the Thomas algorithm); the pieces are then the Hermite cubics through their ends."""
    n = len(knots) - 1
    dims = values.shape[1]
    slopes = np.empty((n + 1, dims))
    if n == 1:
        slopes[0] = first
        slopes[1] = last
        return hermite(knots, values, slopes)
    h = np.empty(n)
    for k in range(n):
        h[k] = knots[k + 1] - knots[k]
    # Rows 1..n-1 after the known ends are moved to the right-hand side.
    lower = np.empty(n + 1)
    diag = np.empty(n + 1)
    upper = np.empty(n + 1)
    rhs = np.empty((n + 1, dims))
    for i in range(1, n):
        lower[i] = h[i]
        diag[i] = 2.0 * (h[i - 1] + h[i])
        upper[i] = h[i - 1]
        for j in range(dims):
            before = (values[i, j] - values[i - 1, j]) / h[i - 1]
            after = (values[i + 1, j] - values[i, j]) / h[i]
            rhs[i, j] = 3.0 * (h[i] * before + h[i - 1] * after)
    for j in range(dims):
        rhs[1, j] -= lower[1] * first[j]
        rhs[n - 1, j] -= upper[n - 1] * last[j]
    for i in range(2, n):  # forward elimination
        w = lower[i] / diag[i - 1]
        diag[i] -= w * upper[i - 1]
        for j in range(dims):
            rhs[i, j] -= w * rhs[i - 1, j]
    slopes[0] = first
    slopes[n] = last
    for i in range(n - 1, 0, -1):  # back substitution
        for j in range(dims):
            x = rhs[i, j]
            if i < n - 1:
                x -= upper[i] * slopes[i + 1, j]
            slopes[i, j] = x / diag[i]
    return hermite(knots, values, slopes)


@njit(cache=True)
def grid(c, knots, order, end, max_err, max_iter, max_seg_length, min_points):
    """Grid points on [0, end] by the rule of Drake's ``Toppra.CalcGridPoints`` for the curve's
    ``order``-th derivative q'' (the path's second): rounds that halve every interval longer
    than ``max_seg_length`` or whose linear interpolation errs by more than ``max_err``
    (0.5 h^2 max |q''(midpoint)|), at most ``max_iter`` rounds, then halving all intervals
    until there are ``min_points`` points."""
    points = np.array([0.0, end])
    for _ in range(max_iter):
        mid = 0.5 * (points[:-1] + points[1:])
        ddq = evaluate(c, knots, mid, order)
        split = np.zeros(len(mid), dtype=np.bool_)
        for k in range(len(mid)):
            length = points[k + 1] - points[k]
            peak = 0.0
            for j in range(ddq.shape[1]):
                peak = max(peak, abs(ddq[k, j]))
            split[k] = length > max_seg_length or 0.5 * length * length * peak > max_err
        if not split.any():
            break
        points = _insert(points, mid, split)
    while len(points) < min_points:
        mid = 0.5 * (points[:-1] + points[1:])
        points = _insert(points, mid, np.ones(len(mid), dtype=np.bool_))
    return points


@njit(cache=True)
def _insert(points, mid, split):
    """The sorted points with the midpoints ``mid[k]`` of the intervals where ``split``."""
    out = np.empty(len(points) + split.sum())
    n = 0
    for k in range(len(points)):
        out[n] = points[k]
        n += 1
        if k < len(mid) and split[k]:
            out[n] = mid[k]
            n += 1
    return out


@njit(cache=True)
def chord_deviation(c, knots, values, samples):
    """Per knot interval, the largest distance of the curve from the chord between its values
    at the ends (``values`` (n + 1, J)), at ``samples`` - 1 points evenly spaced inside."""
    n = len(knots) - 1
    dims = values.shape[1]
    out = np.zeros(n)
    x = np.empty(1)
    for k in range(n):
        length2 = 0.0
        for j in range(dims):
            length2 += (values[k + 1, j] - values[k, j]) ** 2
        for m in range(1, samples):
            x[0] = knots[k] + (m / samples) * (knots[k + 1] - knots[k])
            q = evaluate(c, knots, x, 0)[0]
            along = 0.0
            for j in range(dims):
                along += (q[j] - values[k, j]) * (values[k + 1, j] - values[k, j])
            lam = min(max(along / length2, 0.0), 1.0) if length2 > 0.0 else 0.0
            gap = 0.0
            for j in range(dims):
                gap += (q[j] - values[k, j] - lam * (values[k + 1, j] - values[k, j])) ** 2
            out[k] = max(out[k], np.sqrt(gap))
    return out


class Curve:
    """A piecewise cubic (knots (n + 1,), coefficients (4, n, J)), or one of its derivatives
    (``order``): called on points (M,) it returns (M, J) (its ``nu``-th derivative with
    ``nu``), like scipy's ``PPoly``."""

    def __init__(self, knots, c, order: int = 0):
        self.knots, self.c, self.order = knots, c, order

    def __call__(self, x, nu: int = 0) -> np.ndarray:
        x = np.ascontiguousarray(np.atleast_1d(x), dtype=float)
        return evaluate(self.c, self.knots, x, self._order(nu))

    def derivative(self, nu: int = 1) -> Curve:
        return Curve(self.knots, self.c, self._order(nu))

    def _order(self, nu: int) -> int:
        if not 0 <= self.order + nu <= 3:
            raise ValueError(f"a cubic has derivatives of order 0 to 3, not {self.order + nu}")
        return self.order + nu


def warm_up() -> None:
    """Compiles (first run on a machine) or loads these functions now rather than in a request."""
    knots = np.array([0.0, 1.0, 2.0])
    values = np.zeros((3, 7))
    c = clamped(knots, values, values[0], values[0])
    evaluate(c, knots, knots, 0)
    grid(c, knots, 2, 2.0, 1e-4, 100, 0.02, 4)
    chord_deviation(c, knots, values, 16)
