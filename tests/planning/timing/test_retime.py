"""Time parameterisation of joint paths (planning.timing.retime): the timed trajectory starts and
ends at rest at the path's ends, passes its waypoints at ``times``, stays within the velocity and
acceleration limits (sampled densely) and near the checked path, slows down in proportion to
scaled limits, and stops where the path turns sharply or repeats a waypoint; a straight segment
is the time-optimal trapezoidal (or triangular) rest-to-rest profile."""

import numpy as np
import pytest

import planning.timing.retime as mut
from planning.timing.rest_to_rest import segment_profile
from planning.timing.spline_section import spline_deviation

V_MAX = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])  # rad/s
A_MAX = np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])  # rad/s^2
READY = np.array([0.0, -0.785398, 0.0, -2.356194, 0.0, 1.570796, 0.785398])
E = np.eye(7)


def gentle_path(n=7, seed=0):
    """n waypoints, each 0.3 rad further along joint 1 with a small random deviation: turns of
    0.4 to 0.6 rad, below the default corner angle, so the whole path is one smooth section."""
    rng = np.random.default_rng(seed)
    steps = 0.3 * E[0] + rng.normal(0.0, 0.05, (n - 1, 7))
    return np.vstack([READY, READY + np.cumsum(steps, axis=0)])


def sample(timing, count):
    ts = np.linspace(0.0, timing.duration, count)
    q, v, a = (np.array(x) for x in zip(*(timing.sample(t) for t in ts), strict=True))
    return ts, q, v, a


def distance_to_polyline(q, waypoints):
    a, d = waypoints[:-1], np.diff(waypoints, axis=0)
    lam = np.clip(np.einsum("kj,kj->k", q - a, d) / np.einsum("kj,kj->k", d, d), 0.0, 1.0)
    return np.min(np.linalg.norm(q - a - lam[:, None] * d, axis=1))


@pytest.fixture(scope="module")
def path():
    return gentle_path()


@pytest.fixture(scope="module")
def dut(path):
    return mut.Timing(path, V_MAX, A_MAX)


def test_starts_and_ends_at_rest_at_the_path_ends(dut, path):
    q0, v0, a0 = dut.sample(0.0)
    np.testing.assert_allclose(q0, path[0], atol=1e-9)
    np.testing.assert_allclose(v0, 0.0, atol=1e-9)
    q1, v1, a1 = dut.sample(dut.duration)
    np.testing.assert_array_equal(q1, path[-1])
    np.testing.assert_array_equal(v1, 0.0)
    np.testing.assert_array_equal(a1, 0.0)
    # Times outside [0, duration] are clamped.
    np.testing.assert_allclose(dut.sample(-1.0)[0], path[0], atol=1e-9)
    np.testing.assert_array_equal(dut.sample(dut.duration + 1.0)[0], path[-1])
    assert dut.stops == [0, len(path) - 1]  # the gentle corners are not stops
    assert dut.smoothed == [(0, len(path) - 1)]


def test_passes_the_waypoints_in_order_at_their_times(dut, path):
    assert len(dut.times) == len(path)
    assert dut.times[0] == 0.0 and dut.times[-1] == dut.duration
    assert np.all(np.diff(dut.times) > 0)
    for t, q in zip(dut.times, path, strict=True):
        np.testing.assert_allclose(dut.sample(t)[0], q, atol=1e-4)
    # Without stopping there: the interior waypoints are passed at speed.
    for t in dut.times[1:-1]:
        assert np.linalg.norm(dut.sample(t)[1]) > 0.1


def test_limits_hold_when_sampled_densely(dut, path):
    ts, q, v, a = sample(dut, 6001)
    assert np.all(np.abs(v) <= V_MAX * (1 + 1e-6))
    assert np.all(np.abs(a) <= A_MAX * (1 + 1e-6))
    # Near time-optimal: some joint reaches a limit.
    assert max(np.max(np.abs(v) / V_MAX), np.max(np.abs(a) / A_MAX)) > 0.9
    # v is the derivative of q, and a integrates to v (a jumps where TOPP-RA switches).
    np.testing.assert_allclose(np.gradient(q, ts, axis=0), v, atol=0.02)
    steps = 0.5 * (a[1:] + a[:-1]) * np.diff(ts)[:, None]
    np.testing.assert_allclose(np.vstack([v[:1], v[:1] + np.cumsum(steps, axis=0)]), v, atol=0.02)
    # The smoothed trajectory stays within the tolerance of the checked straight segments.
    tolerance = mut.RetimeOptions().path_tolerance
    assert max(distance_to_polyline(x, path) for x in q[::5]) <= tolerance
    for i, j, samples in dut.smoothed_paths(0.01):
        assert (i, j) == (0, len(path) - 1)
        assert np.max(np.linalg.norm(np.diff(samples, axis=0), axis=1)) <= 0.011
        assert max(distance_to_polyline(x, path) for x in samples) <= tolerance


def test_scaled_limits_slow_it_down_proportionally(dut, path):
    """Velocity limits scaled by k and accelerations by k^2: the same motion, k times slower."""
    k = 0.5
    slow = mut.Timing(path, k * V_MAX, k * k * A_MAX)
    assert slow.duration == pytest.approx(dut.duration / k, rel=1e-6)
    np.testing.assert_allclose(slow.times, dut.times / k, rtol=1e-6, atol=1e-9)
    for t in np.linspace(0.0, dut.duration, 11):
        q, v, a = dut.sample(t)
        q_slow, v_slow, a_slow = slow.sample(t / k)
        np.testing.assert_allclose(q_slow, q, atol=1e-6)
        np.testing.assert_allclose(v_slow, k * v, atol=1e-5)
    # Only the velocity limit scaled: slower too, never faster.
    assert mut.Timing(path, k * V_MAX, A_MAX).duration > dut.duration


def test_a_straight_two_waypoint_path_is_rest_to_rest_and_time_optimal():
    q_b = READY + [1.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0]
    dut = mut.Timing([READY, q_b], V_MAX, A_MAX)
    d = q_b - READY
    duration, ramp, accel = segment_profile(d, V_MAX, A_MAX)
    assert dut.duration == pytest.approx(duration)
    np.testing.assert_allclose(dut.times, [0.0, duration])
    assert dut.smoothed == [] and dut.stops == [0, 1]
    ts, q, v, a = sample(dut, 4001)
    np.testing.assert_allclose(v[[0, -1]], 0.0, atol=1e-12)
    np.testing.assert_allclose(q[0], READY)
    np.testing.assert_allclose(q[-1], q_b)
    # On the straight line, moving forwards only.
    s = (q - READY) @ d / (d @ d)
    np.testing.assert_allclose(q, READY + s[:, None] * d, atol=1e-12)
    assert np.all(np.diff(s) >= -1e-12)
    # Trapezoidal: joint 1 (1 rad at 2.175 rad/s) cruises at its limit; joint 2 (0.5 rad at
    # 7.5 rad/s^2, so 1.0 rad at the same s) accelerates at its limit.
    assert np.all(np.abs(v) <= V_MAX + 1e-9) and np.all(np.abs(a) <= A_MAX + 1e-9)
    assert np.max(np.abs(v[:, 0])) == pytest.approx(V_MAX[0])
    assert np.max(np.abs(a[:, 1])) == pytest.approx(A_MAX[1])
    assert duration == pytest.approx(d[0] / V_MAX[0] + ramp)
    assert accel == pytest.approx(A_MAX[1] / d[1])


def test_sharp_corners_and_repeated_waypoints_are_stops():
    path = np.vstack(
        [
            READY,
            READY + 0.5 * E[0],
            READY + 0.6 * E[0] + 0.05 * E[1],  # gentle: 0.46 rad
            READY + 0.6 * E[0] + 0.8 * E[1],  # sharp: 1.11 rad
            READY + 0.6 * E[0] + 0.8 * E[1],  # repeated
            READY + 0.6 * E[0] + 0.8 * E[1] + 0.4 * E[2],
        ]
    )
    sections = mut.plan_sections(path, mut.RetimeOptions())
    assert [(i, j) for i, j, _, _ in sections] == [(0, 2), (2, 3), (3, 4), (4, 5)]
    dut = mut.Timing(path, V_MAX, A_MAX)
    assert dut.stops == [0, 2, 3, 4, 5] and dut.smoothed == [(0, 2)]
    assert dut.times[3] == dut.times[4]  # no time spent on the repeated waypoint
    for k in dut.stops:
        np.testing.assert_allclose(dut.sample(dut.times[k])[1], 0.0, atol=1e-9)
        np.testing.assert_allclose(dut.sample(dut.times[k])[0], path[k], atol=1e-9)
    _, _, v, a = sample(dut, 4001)
    assert np.all(np.abs(v) <= V_MAX * (1 + 1e-6)) and np.all(np.abs(a) <= A_MAX * (1 + 1e-6))
    # rest_to_rest stops everywhere, and takes longer.
    slow = mut.Timing(path, V_MAX, A_MAX, mut.RetimeOptions(method="rest_to_rest"))
    assert slow.stops == list(range(len(path))) and slow.duration > dut.duration
    # With a wider corner angle the sharp corner is blended too.
    wide = mut.plan_sections(path, mut.RetimeOptions(max_corner_angle=1.2))
    assert [(i, j) for i, j, _, _ in wide] == [(0, 3), (3, 4), (4, 5)]


def test_blend_knots_round_corners_within_the_tolerance():
    path = np.vstack([READY, READY + 0.5 * E[0], READY + 0.5 * E[0] + 0.5 * E[1]])
    tolerance = 0.002
    assert np.max(spline_deviation(path)) > tolerance  # the spline alone strays
    knots, mask = mut.blend_knots(path, tolerance)
    np.testing.assert_array_equal(knots[mask], path)
    assert len(knots) == len(path) + 6  # 3 on each side of the one interior corner
    for q in knots:
        assert distance_to_polyline(q, path) < 1e-12  # on the straight segments
    assert np.max(spline_deviation(knots)) <= tolerance
    # Straight through: the spline is the line itself.
    line = READY + np.linspace(0.0, 1.0, 4)[:, None] * E[0]
    np.testing.assert_allclose(spline_deviation(line), 0.0, atol=1e-12)


def test_timing_is_deterministic(path):
    a, b = mut.Timing(path, V_MAX, A_MAX), mut.Timing(path, V_MAX, A_MAX)
    assert a.duration == b.duration
    for t in np.linspace(0.0, a.duration, 9):
        for x, y in zip(a.sample(t), b.sample(t), strict=True):
            np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize(
    "kwargs",
    [{"method": "fastest"}, {"max_corner_angle": -0.1}, {"path_tolerance": -1.0}, {"margin": 0.5}],
)
def test_bad_options_are_rejected(kwargs):
    with pytest.raises(ValueError):
        mut.RetimeOptions(**kwargs)


# The path that the pick-and-place's move over the wall took in random scene 51 (kinematic mode,
# ``config/sweeps/pickplace_random_scenes.yaml``): its timing peaked 0.04 % over joint 3's
# acceleration limit at a waypoint, between the samples the timing checked, and the execution
# gate refused the plan.
SCENE_51_PATH = np.array(
    [
        [
            -0.3985439662784397,
            0.37136780078878695,
            -0.06789040295390109,
            -2.306908530669515,
            0.05497222841699949,
            2.676890173693412,
            -0.3683930267599648,
        ],
        [
            -0.36164221386322737,
            0.3363348092816471,
            -0.012893139248906609,
            -2.2508152386030043,
            0.005581131362556828,
            2.6833748523854153,
            -0.3309808506248699,
        ],
        [
            -0.1529306592146309,
            0.24355429667957051,
            0.16290670661426987,
            -2.1501102505928484,
            -0.14425975872501368,
            2.706346990747488,
            -0.034848936606411474,
        ],
        [
            -0.0075932227956590215,
            0.2647511430666732,
            0.17517390925056378,
            -2.2563403994172284,
            -0.14313204657450107,
            2.7111831096079078,
            0.24020708187431075,
        ],
        [
            0.18869561454185899,
            0.3034951706025968,
            0.17875510530789565,
            -2.420603852648349,
            -0.12917439313998955,
            2.716398837060527,
            0.6198067080352199,
        ],
    ]
)


def test_limits_hold_at_the_waypoints_where_the_acceleration_peaks():
    # The acceleration has a corner where the path passes a knot (a waypoint of a smoothed
    # section), and the execution gate samples the trajectory there.
    dut = mut.Timing(SCENE_51_PATH, V_MAX, A_MAX)
    assert dut.smoothed  # the case in point: one smoothed section
    ts = np.concatenate([np.linspace(0.0, dut.duration, 20001), dut.times])
    a = np.array([dut.sample(t)[2] for t in ts])
    assert np.all(np.abs(a) <= A_MAX * (1 + 1e-6)), np.max(np.abs(a) / A_MAX)
