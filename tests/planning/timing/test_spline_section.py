"""A spline section timed by TOPP-RA (planning.timing.spline_section): the compiled spline is
Drake's, its TOPP-RA grid is Drake's, its deviation from the chords is measured, and a timed
section starts and ends at rest within the limits (the rest through ``retime.Timing``)."""

import numpy as np
import pytest

import planning.timing.spline_section as mut

V_MAX = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])  # rad/s
A_MAX = np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])  # rad/s^2
E = np.eye(7)


@pytest.mark.parametrize("seed", range(6))
def test_the_fast_spline_is_drakes_spline(seed):
    rng = np.random.default_rng(seed)
    waypoints = np.cumsum(rng.normal(0.0, rng.uniform(0.01, 0.5), (rng.integers(2, 30), 7)), 0)
    drake, knots = mut.drake_spline(waypoints)
    fast, fast_knots = mut.compiled_spline(waypoints)
    np.testing.assert_array_equal(fast_knots, knots)
    s = np.linspace(0.0, knots[-1], 500)
    for order in range(3):
        expected = (drake if order == 0 else drake.MakeDerivative(order)).vector_values(s).T
        np.testing.assert_allclose(fast(s, order), expected, atol=1e-9 * 10**order)


@pytest.mark.parametrize("seed", range(6))
def test_grid_points_are_drakes(seed):
    from pydrake.multibody.optimization import CalcGridPointsOptions, Toppra

    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 30))
    waypoints = np.cumsum(rng.normal(0.0, rng.uniform(0.005, 0.4), (n, 7)), axis=0)
    options = CalcGridPointsOptions(
        max_err=1e-4, max_iter=100, max_seg_length=0.02, min_points=2 * n
    )
    drake, knots = mut.drake_spline(waypoints)
    fast, _ = mut.compiled_spline(waypoints)
    expected = Toppra.CalcGridPoints(drake, options)
    np.testing.assert_allclose(mut.grid_points(fast.derivative(2), knots[-1], options), expected)


def test_spline_deviation_measures_how_far_the_spline_strays_from_the_chords():
    line = np.linspace(0.0, 1.0, 4)[:, None] * E[0]
    np.testing.assert_allclose(mut.spline_deviation(line), 0.0, atol=1e-12)
    corner = np.vstack([np.zeros(7), 0.5 * E[0], 0.5 * E[0] + 0.5 * E[1]])
    deviation = mut.spline_deviation(corner)
    assert deviation.shape == (2,) and np.all(deviation > 0.01)


def test_a_smooth_section_starts_and_ends_at_rest_within_the_limits():
    rng = np.random.default_rng(2)
    waypoints = np.cumsum(0.3 * E[0] + rng.normal(0.0, 0.05, (6, 7)), axis=0)
    dut = mut.SmoothSection(waypoints, V_MAX, A_MAX, margin=0.01)
    assert dut.duration > 0 and dut.waypoint_times[0] == 0.0
    assert dut.waypoint_times[-1] == pytest.approx(dut.duration)
    ts = np.linspace(0.0, dut.duration, 2001)
    q, v, a = (np.array(x) for x in zip(*(dut.sample(t) for t in ts), strict=True))
    np.testing.assert_allclose(q[0], waypoints[0], atol=1e-9)
    np.testing.assert_allclose(q[-1], waypoints[-1], atol=1e-9)
    np.testing.assert_allclose(v[[0, -1]], 0.0, atol=1e-9)
    assert np.all(np.abs(v) <= V_MAX * (1 + 1e-6)) and np.all(np.abs(a) <= A_MAX * (1 + 1e-6))
    samples = dut.path_samples(0.01)
    assert np.all(np.linalg.norm(np.diff(samples, axis=0), axis=1) <= 0.011)


def test_the_chain_plant_has_the_joints_asked_for():
    assert mut.chain_plant(7).num_positions() == 7 and mut.chain_plant(6).num_positions() == 6
    assert mut.chain_plant(7) is mut.chain_plant(7)  # made once per count
