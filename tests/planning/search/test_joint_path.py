"""The planner's joint path pipeline (planning.search.joint_path): the straight line when free,
RRT-Connect around an obstacle, every returned path valid at the fine resolution, a colliding
segment repaired, the adapters the options ask for, and a timeout reported as TIMED_OUT."""

import time

import numpy as np
import pytest
from pydrake.math import RigidTransform

import planning.search.joint_path as mut
from planning import ErrorCode, MotionPlannerOptions, PlanningError, PlanningScene
from planning.collision.checker import CheckerAdapter, first_invalid_segment
from planning.collision.sphere_checker import SphereCheckerAdapter

E = np.eye(7)
FINE = 0.01  # rad


@pytest.fixture(scope="module")
def scene():
    """The table and a wall around the hand at "ready", between the two ends."""
    scene = PlanningScene()
    ready = scene.model.named_configurations["ready"]
    scene.add_box(
        "wall", [0.1, 0.1, 0.3], RigidTransform(scene.attachment_pose(ready).translation())
    )
    return scene


@pytest.fixture(scope="module")
def ends(scene):
    ready = scene.model.named_configurations["ready"]
    return ready - 0.8 * E[0], ready + 0.8 * E[0]


@pytest.fixture(scope="module")
def dut(scene):
    return mut.JointPathSearch(scene, MotionPlannerOptions())


def deadline(seconds=30.0):
    return time.perf_counter() + seconds


def test_a_free_straight_line_is_the_path(scene, dut, ends):
    start = ends[0]
    goal = start - 0.2 * E[0]
    path, how = dut.find(start, goal, deadline())
    assert how == "straight"
    np.testing.assert_array_equal(path, [start, goal])


def test_around_the_wall_the_path_is_valid_at_the_fine_resolution(scene, dut, ends):
    assert not scene.is_edge_collision_free(*ends)
    path, how = dut.find(*ends, deadline())
    assert how.startswith("rrt_connect")
    np.testing.assert_array_equal(path[[0, -1]], ends)
    assert first_invalid_segment(CheckerAdapter(scene), path, FINE) is None


def test_a_colliding_segment_is_repaired(scene, dut, ends):
    straight = np.vstack(ends)  # through the wall
    rng = np.random.default_rng(0)
    path, how = dut._validated(dut.adapter(FINE), straight, "test", deadline(), rng)
    assert "+repaired" in how or "+replanned" in how
    assert first_invalid_segment(CheckerAdapter(scene), path, FINE) is None


def test_adapters_follow_the_options(scene):
    options = MotionPlannerOptions()
    search = mut.JointPathSearch(scene, options).adapter(search=True)
    assert isinstance(search, SphereCheckerAdapter)
    assert search.resolution == options.spheres.search_resolution
    options.spheres.enabled = False
    plain = mut.JointPathSearch(scene, options).adapter(FINE)
    assert type(plain) is CheckerAdapter and plain.resolution == FINE


def test_no_time_left_is_timed_out(dut, ends):
    with pytest.raises(PlanningError) as info:
        dut.find(*ends, time.perf_counter() - 1.0)
    assert info.value.code is ErrorCode.TIMED_OUT
