"""Piecewise-linear joint paths (planning.paths): densify keeps the ends and every waypoint,
spaces samples at most the resolution apart on the path's segments and labels each sample's
segment; path_length sums the segment lengths; drop_duplicates removes repeated waypoints."""

import numpy as np
import pytest

import planning.paths as mut


def random_path(n, seed=0):
    return np.random.default_rng(seed).uniform(-1.0, 1.0, (n, 7))


def distance_to_segment(q, a, b):
    d = b - a
    lam = np.clip((q - a) @ d / (d @ d), 0.0, 1.0)
    return np.linalg.norm(q - a - lam * d)


def test_densify_spaces_samples_within_the_resolution_and_keeps_the_waypoints():
    path = random_path(5)
    resolution = 0.05
    samples, segment = mut.densify(path, resolution)
    assert samples.shape[1] == 7 and len(segment) == len(samples)
    np.testing.assert_array_equal(samples[0], path[0])
    np.testing.assert_allclose(samples[-1], path[-1], atol=1e-12)
    steps = np.linalg.norm(np.diff(samples, axis=0), axis=1)
    assert np.all(steps <= resolution + 1e-12)
    # Every waypoint is one of the samples, in order.
    for q in path:
        assert np.min(np.linalg.norm(samples - q, axis=1)) < 1e-12
    # The samples add no length: they lie on the straight segments.
    assert mut.path_length(samples) == pytest.approx(mut.path_length(path))


def test_densify_labels_each_sample_with_its_segment():
    path = random_path(4, seed=1)
    samples, segment = mut.densify(path, 0.1)
    assert segment[0] == 0 and segment[-1] == len(path) - 2
    assert np.all(np.diff(segment) >= 0)  # in order along the path
    assert set(segment) == set(range(len(path) - 1))
    for q, i in zip(samples, segment, strict=True):
        assert distance_to_segment(q, path[i], path[i + 1]) < 1e-12
    # Each segment's samples are its smallest equal division within the resolution.
    for i in range(len(path) - 1):
        n = int(np.ceil(np.linalg.norm(path[i + 1] - path[i]) / 0.1))
        assert np.count_nonzero(segment[1:] == i) == n


def test_densify_of_short_segments_and_a_single_waypoint():
    path = np.vstack([np.zeros(7), np.full(7, 1e-3)])
    samples, segment = mut.densify(path, 1.0)
    np.testing.assert_array_equal(samples, path)  # shorter than the resolution: the two ends
    np.testing.assert_array_equal(segment, [0, 0])
    one, segment = mut.densify(path[:1], 0.1)
    np.testing.assert_array_equal(one, path[:1])
    np.testing.assert_array_equal(segment, [0])


def test_path_length_sums_the_segments():
    path = np.zeros((3, 7))
    path[1, 0] = 3.0
    path[2, :2] = [3.0, 4.0]
    assert mut.path_length(path) == pytest.approx(7.0)
    assert mut.path_length(path[::-1]) == pytest.approx(7.0)
    assert mut.path_length(path[:1]) == 0.0
    assert mut.path_length(np.vstack([path[0], path[0]])) == 0.0
    # The straight line is the shortest path between the ends.
    assert mut.path_length(path[[0, 2]]) == pytest.approx(5.0)


def test_drop_duplicates_removes_waypoints_equal_to_their_predecessor():
    a, b = np.zeros(7), np.ones(7)
    path = np.vstack([a, a, b, b + 1e-14, a, b])
    out = mut.drop_duplicates(path)
    np.testing.assert_array_equal(out, np.vstack([a, b, a, b]))  # only consecutive repeats go
    assert mut.path_length(out) == pytest.approx(mut.path_length(path))
    # The tolerance is a joint-space distance in rad.
    near = np.vstack([a, a + 1e-4, b])
    assert len(mut.drop_duplicates(near)) == 3
    assert len(mut.drop_duplicates(near, tolerance=1e-3)) == 2
    np.testing.assert_array_equal(mut.drop_duplicates(a[None]), a[None])


def test_densify_refuses_a_non_finite_path():
    path = random_path(3)
    path[1, 2] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        mut.densify(path, 0.1)
