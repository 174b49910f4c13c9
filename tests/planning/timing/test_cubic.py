"""Compiled piecewise cubics (planning.timing.cubic): the clamped spline and the Hermite pieces
are scipy's, evaluated like scipy's PPoly (derivatives, points on the knots and beyond the
ends)."""

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline, CubicSpline

from planning.timing import cubic as mut


def random_curve(rng, dims=7):
    n = int(rng.integers(1, 30))
    knots = np.concatenate([[0.0], np.cumsum(rng.uniform(0.01, 0.5, n))])
    values = np.cumsum(rng.normal(0.0, 0.3, (n + 1, dims)), axis=0)
    return knots, values


def points(rng, knots):
    """Points inside, on the knots, and beyond both ends."""
    inside = rng.uniform(knots[0], knots[-1], 200)
    return np.concatenate([inside, knots, [knots[0] - 0.1, knots[-1] + 0.1]])


@pytest.mark.parametrize("seed", range(8))
def test_the_clamped_spline_is_scipys(seed):
    rng = np.random.default_rng(seed)
    knots, values = random_curve(rng)
    first, last = rng.normal(size=7), rng.normal(size=7)
    expected = CubicSpline(knots, values, bc_type=((1, first), (1, last)))
    curve = mut.Curve(knots, mut.clamped(knots, values, first, last))
    x = points(rng, knots)
    for order in range(4):
        np.testing.assert_allclose(curve(x, order), expected(x, order), atol=1e-9, rtol=1e-9)
        np.testing.assert_allclose(curve.derivative(order)(x), expected(x, order), atol=1e-9)


@pytest.mark.parametrize("seed", range(4))
def test_the_hermite_pieces_are_scipys(seed):
    rng = np.random.default_rng(seed)
    knots, values = random_curve(rng, dims=1)
    slopes = rng.normal(size=values.shape)
    expected = CubicHermiteSpline(knots, values, slopes)
    c = mut.hermite(knots, values, slopes)
    x = points(rng, knots)
    for order in range(4):
        np.testing.assert_allclose(mut.evaluate(c, knots, x, order), expected(x, order), atol=1e-9)


def test_a_cubic_has_derivatives_up_to_the_third():
    knots, values = np.array([0.0, 1.0]), np.array([[0.0], [1.0]])
    curve = mut.Curve(knots, mut.clamped(knots, values, np.ones(1), np.ones(1)))
    np.testing.assert_allclose(curve(np.array([0.25, 0.5])), [[0.25], [0.5]])  # a line
    with pytest.raises(ValueError, match="order 0 to 3"):
        curve.derivative(2).derivative(2)
    with pytest.raises(ValueError, match="order 0 to 3"):
        curve(np.zeros(1), 4)


@pytest.mark.parametrize("seed", range(4))
def test_the_chord_deviation_is_the_largest_sampled_distance_from_each_chord(seed):
    rng = np.random.default_rng(seed)
    knots, values = random_curve(rng)
    first, last = rng.normal(size=7), rng.normal(size=7)
    c = mut.clamped(knots, values, first, last)
    got = mut.chord_deviation(c, knots, values, 16)
    for k in range(len(knots) - 1):
        x = knots[k] + np.arange(1, 16) / 16 * (knots[k + 1] - knots[k])
        q = mut.evaluate(c, knots, x, 0)
        a, d = values[k], values[k + 1] - values[k]
        lam = np.clip((q - a) @ d / (d @ d), 0.0, 1.0)
        assert got[k] == pytest.approx(np.linalg.norm(q - a - lam[:, None] * d, axis=1).max())
    # Through points on a line, with slopes along it: the spline is the line.
    line = np.outer(knots, np.ones(7) / np.sqrt(7))
    slope = (line[1] - line[0]) / (knots[1] - knots[0])
    flat = mut.clamped(knots, line, slope, slope)
    np.testing.assert_allclose(mut.chord_deviation(flat, knots, line, 16), 0.0, atol=1e-12)


def test_the_grid_halves_long_and_curved_intervals_then_fills_up_to_min_points():
    knots = np.array([0.0, 1.0])
    line = mut.hermite(knots, np.array([[0.0], [1.0]]), np.ones((2, 1)))  # q'' = 0
    points = mut.grid(line, knots, 2, 1.0, 1e-4, 100, 0.3, 3)
    np.testing.assert_allclose(points, np.linspace(0.0, 1.0, 5))  # 1 -> 0.5 -> 0.25 < 0.3
    points = mut.grid(line, knots, 2, 1.0, 1e-4, 100, 2.0, 9)
    np.testing.assert_allclose(points, np.linspace(0.0, 1.0, 9))  # straight: min_points alone
    bent = mut.hermite(knots, np.array([[0.0], [0.0]]), np.array([[1.0], [-1.0]]))
    points = mut.grid(bent, knots, 2, 1.0, 1e-4, 100, 2.0, 2)
    mid = 0.5 * (points[:-1] + points[1:])
    error = 0.5 * np.diff(points) ** 2 * np.abs(mut.evaluate(bent, knots, mid, 2)[:, 0])
    assert np.all(error <= 1e-4) and np.all(np.diff(points) > 0)
