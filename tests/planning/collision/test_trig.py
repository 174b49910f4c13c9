"""``trig.sincos`` and ``sincos_lanes``: within 2 ulp of the C library's sine and cosine over the
joints' range and far beyond, exact where they are exact, NaN for non-finite input, and the
library's values beyond the reduction's range."""

import numpy as np
import pytest

from planning.collision import trig as mut


def _ulps(value, reference):
    """|value - reference| in units of the last place of the reference."""
    return np.abs(value - reference) / np.spacing(np.abs(reference))


def _lanes(x):
    sin_out = np.full(len(x), -7.0)
    cos_out = np.full(len(x), -7.0)
    mut.sincos_lanes(x, sin_out, cos_out, len(x))
    return sin_out, cos_out


@pytest.mark.parametrize("bound", [7.0, 1.0e3, mut.REDUCED_UP_TO])
def test_within_two_ulp_of_numpy(bound):
    rng = np.random.default_rng(3)
    x = rng.uniform(-bound, bound, 200_000)
    sin_x, cos_x = _lanes(x)
    assert _ulps(sin_x, np.sin(x)).max() <= 2.0
    assert _ulps(cos_x, np.cos(x)).max() <= 2.0
    # The scalar form gives the same values as the lanes.
    for k in range(0, len(x), 9973):
        assert mut.sincos(x[k]) == (sin_x[k], cos_x[k])


def test_within_one_ulp_over_the_joints_range_and_at_quadrant_edges():
    x = np.concatenate(
        [np.linspace(-2 * np.pi, 2 * np.pi, 100_001), np.pi / 4 * np.arange(-16, 17)]
    )
    x = np.concatenate([x, np.nextafter(x, np.inf), np.nextafter(x, -np.inf)])
    sin_x, cos_x = _lanes(x)
    # Away from the zeros (where one ulp of a tiny value is tinier still), within one ulp.
    big_sin = np.abs(np.sin(x)) > 1e-3
    big_cos = np.abs(np.cos(x)) > 1e-3
    assert _ulps(sin_x[big_sin], np.sin(x[big_sin])).max() <= 1.0
    assert _ulps(cos_x[big_cos], np.cos(x[big_cos])).max() <= 1.0
    assert np.abs(sin_x - np.sin(x)).max() <= 2.3e-16
    assert np.abs(cos_x - np.cos(x)).max() <= 2.3e-16


def test_exact_values():
    assert mut.sincos(0.0) == (0.0, 1.0)
    assert mut.sincos(-0.0) == (0.0, 1.0)  # the sign of a zero is not kept
    assert mut.sincos(1e-300) == (1e-300, 1.0)
    assert mut.sincos(np.pi / 2) == (1.0, np.cos(np.pi / 2))


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_input_gives_nan(bad):
    s, c = mut.sincos(bad)
    assert np.isnan(s) and np.isnan(c)
    sin_x, cos_x = _lanes(np.array([0.5, bad, -0.5]))
    assert np.isnan(sin_x[1]) and np.isnan(cos_x[1])
    assert sin_x[0] == np.sin(0.5) and cos_x[2] == np.cos(-0.5)


def test_beyond_the_reduction_the_library_answers():
    x = np.array([2.0e6, -3.5e9, 1.0e300, 0.25])
    sin_x, cos_x = _lanes(x)
    np.testing.assert_array_equal(sin_x, np.sin(x))
    np.testing.assert_array_equal(cos_x, np.cos(x))
    assert mut.sincos(1.0e300) == (np.sin(1.0e300), np.cos(1.0e300))


def test_only_the_first_count_lanes_are_written():
    x = np.array([0.1, 0.2, 0.3])
    sin_out = np.full(3, -7.0)
    cos_out = np.full(3, -7.0)
    mut.sincos_lanes(x, sin_out, cos_out, 2)
    assert sin_out[2] == -7.0 and cos_out[2] == -7.0
    assert _ulps(sin_out[:2], np.sin(x[:2])).max() <= 1.0
