"""Path shortcutting (planning.search.shortcut): shortcut never lengthens a path, keeps its ends,
keeps it collision-free at the checking resolution, straightens a detour through free space to
one segment, shortens an RRT-Connect path around a wall, and is deterministic for a seed."""

import time

import numpy as np
import pytest

import planning.search.shortcut as mut
from planning.collision.sphere_checker import SphereCheckerAdapter
from planning.paths import densify, path_length
from planning.search.rrt import rrt_connect

E = np.eye(7)
FINE = 0.01  # rad


@pytest.fixture(scope="module")
def rrt_paths(scene, ends):
    """Jagged collision-free paths around the wall, from RRT-Connect with short steps."""
    paths = []
    for seed in range(3):
        paths.append(
            rrt_connect(
                SphereCheckerAdapter(scene, FINE),
                *ends,
                step=0.3,
                goal_bias=0.05,
                deadline=time.perf_counter() + 60.0,
                rng=np.random.default_rng(seed),
                max_rounds=5000,
            )
        )
    return paths


def shortened(scene, path, seed=0, iterations=40, deadline=None):
    return mut.shortcut(
        SphereCheckerAdapter(scene, FINE),
        path,
        iterations=iterations,
        deadline=deadline if deadline is not None else time.perf_counter() + 60.0,
        rng=np.random.default_rng(seed),
    )


def assert_fine_collision_free(scene, path):
    samples, _ = densify(path, FINE)
    assert all(scene.is_collision_free(q) for q in samples)


def test_rrt_paths_get_shorter_keep_their_ends_and_stay_collision_free(scene, rrt_paths):
    for path in rrt_paths:
        dut = shortened(scene, path)
        np.testing.assert_array_equal(dut[0], path[0])
        np.testing.assert_array_equal(dut[-1], path[-1])
        assert path_length(dut) < path_length(path)
        assert len(dut) < len(path)
        assert_fine_collision_free(scene, dut)
        assert np.all(np.linalg.norm(np.diff(dut, axis=0), axis=1) > 1e-12)  # no repeats


def test_never_longer_whatever_the_seed(scene, rrt_paths):
    path = rrt_paths[0]
    for seed in range(4):
        dut = shortened(scene, path, seed=seed, iterations=16)
        assert path_length(dut) <= path_length(path) + 1e-12
        np.testing.assert_array_equal(dut[[0, -1]], path[[0, -1]])
        assert_fine_collision_free(scene, dut)
    # Shortening a shortened path again cannot lengthen it either.
    once = shortened(scene, path)
    assert path_length(shortened(scene, once, seed=1)) <= path_length(once) + 1e-12


def test_a_detour_through_free_space_becomes_one_segment(scene, ends):
    start = ends[0]
    goal = start - 0.4 * E[0]
    detour = np.vstack([start, start + 0.2 * E[1], start - 0.2 * E[0] + 0.3 * E[1], goal])
    assert scene.is_edge_collision_free(start, goal)
    dut = shortened(scene, detour)
    np.testing.assert_array_equal(dut, [start, goal])


def test_a_path_that_cannot_be_shortened_is_kept(scene, ends):
    start = ends[0]
    straight = np.vstack([start, start - 0.4 * E[0]])
    np.testing.assert_array_equal(shortened(scene, straight), straight)
    # Out of time: the input, unchanged.
    path = np.vstack([start, start + 0.2 * E[1], start - 0.4 * E[0]])
    np.testing.assert_array_equal(shortened(scene, path, deadline=time.perf_counter() - 1.0), path)


def test_the_same_seed_gives_the_same_path(scene, rrt_paths):
    path = rrt_paths[1]
    np.testing.assert_array_equal(shortened(scene, path, seed=5), shortened(scene, path, seed=5))
