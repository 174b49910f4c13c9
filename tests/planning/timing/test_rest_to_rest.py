"""Rest-to-rest timing of straight segments (planning.timing.rest_to_rest): triangular when
short, continuous from rest to rest, and ``stopping_time`` the sum of the segments' durations
(the trapezoidal profile's optimality is tested through ``retime.Timing``)."""

import numpy as np
import pytest

import planning.timing.rest_to_rest as mut

V_MAX = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])  # rad/s
A_MAX = np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])  # rad/s^2
E = np.eye(7)


def test_a_short_segment_has_a_triangular_profile():
    d = 0.01 * E[1]
    duration, ramp, accel = mut.segment_profile(d, V_MAX, A_MAX)
    assert ramp == pytest.approx(duration / 2)  # accelerate, then brake: no cruise
    assert duration == pytest.approx(2.0 * np.sqrt(d[1] / A_MAX[1]))
    peak = mut.sample_segment(ramp, duration, ramp, accel)[1] * d[1]
    assert peak < V_MAX[1]
    assert mut.segment_profile(np.zeros(7), V_MAX, A_MAX) == (0.0, 0.0, 0.0)


def test_sample_segment_goes_from_rest_to_rest_continuously():
    duration, ramp, accel = mut.segment_profile(1.5 * E[0], V_MAX, A_MAX)
    ts = np.linspace(-0.1, duration + 0.1, 2001)
    s, s_dot, s_ddot = np.array([mut.sample_segment(t, duration, ramp, accel) for t in ts]).T
    assert s[0] == 0.0 and s[-1] == 1.0 and s_dot[0] == 0.0 and s_dot[-1] == 0.0
    assert np.all(np.diff(s) >= 0) and np.all(np.abs(np.diff(s)) < 2e-3)  # no jumps
    assert np.max(s_dot) == pytest.approx(V_MAX[0] / 1.5)
    inside = (ts > 0) & (ts < duration)
    np.testing.assert_allclose(np.gradient(s, ts)[inside][5:-5], s_dot[inside][5:-5], atol=0.02)
    assert set(np.round(s_ddot[inside] / accel, 9)) <= {-1.0, 0.0, 1.0}
    assert mut.sample_segment(0.3, 0.0, 0.0, 0.0) == (1.0, 0.0, 0.0)  # no motion: at the end


def test_stopping_time_is_the_sum_of_the_rest_to_rest_segments():
    rng = np.random.default_rng(3)
    waypoints = np.cumsum(rng.normal(0.0, 0.3, (9, 7)), axis=0)
    waypoints[4] = waypoints[3]  # a repeat: no time
    waypoints[6, 1:] = waypoints[5, 1:]  # one joint alone moves
    expected = sum(
        mut.Segment(a, b, V_MAX, A_MAX).duration
        for a, b in zip(waypoints[:-1], waypoints[1:], strict=True)
    )
    assert mut.stopping_time(waypoints, V_MAX, A_MAX) == pytest.approx(expected, rel=1e-12)
