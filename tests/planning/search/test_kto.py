"""KTO smoothing (planning.search.kto): kto_refine turns a detour into a shorter dense path with
the same ends, samples at most ``sample_step`` apart within the joint limits, keeps the minimum
distance at its collision-constraint parameters around a wall, and gives None when the solver
fails (a start in collision)."""

import numpy as np
import pytest
from pydrake.math import RigidTransform

import planning.search.kto as mut
from planning import PlanningScene
from planning.paths import path_length

E = np.eye(7)
V_MAX = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])  # rad/s


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


@pytest.fixture(scope="module")
def ends(scene):
    ready = scene.model.named_configurations["ready"]
    return ready - 0.8 * E[0], ready + 0.8 * E[0]


def detour(ends, via):
    """start, start + via, goal + via, goal."""
    return np.vstack([ends[0], ends[0] + via, ends[1] + via, ends[1]])


def at_parameters(path, s):
    """The configurations at path parameters s in [0, 1] (the samples are uniform in it)."""
    x = np.linspace(0.0, 1.0, len(path))
    return np.column_stack([np.interp(s, x, path[:, j]) for j in range(path.shape[1])])


def assert_dense_path(scene, dut, seed_path, sample_step):
    assert dut.ndim == 2 and dut.shape[1] == 7
    np.testing.assert_allclose(dut[0], seed_path[0], atol=1e-9)
    np.testing.assert_allclose(dut[-1], seed_path[-1], atol=1e-9)
    assert np.max(np.linalg.norm(np.diff(dut, axis=0), axis=1)) <= sample_step
    assert all(scene.in_joint_limits(q, tolerance=1e-6) for q in dut)


def test_a_detour_in_free_space_becomes_the_straight_line(scene, ends):
    seed_path = detour(ends, 0.3 * E[1])
    dut = mut.kto_refine(scene, seed_path, max_velocity=V_MAX, control_points=8)
    assert dut is not None
    assert_dense_path(scene, dut, seed_path, 0.005)
    assert path_length(dut) < path_length(seed_path)
    assert path_length(dut) == pytest.approx(np.linalg.norm(ends[1] - ends[0]), rel=1e-3)
    assert all(scene.is_collision_free(q) for q in dut[::10])


def test_the_minimum_distance_holds_at_the_constraint_parameters_around_a_wall(scene, ends):
    ready = scene.model.named_configurations["ready"]
    scene.add_box(
        "wall", [0.1, 0.1, 0.3], RigidTransform(scene.attachment_pose(ready).translation())
    )
    try:
        assert not scene.is_collision_free(ready)
        seed_path = detour(ends, -0.6 * E[1])  # pulled back over the wall
        assert scene.is_collision_free(seed_path[1]) and scene.is_collision_free(seed_path[2])
        distance, samples = 0.01, 20
        dut = mut.kto_refine(
            scene,
            seed_path,
            max_velocity=V_MAX,
            collision_samples=samples,
            minimum_distance=distance,
            sample_step=0.01,
        )
        assert dut is not None
        assert_dense_path(scene, dut, seed_path, 0.01)
        assert path_length(dut) < path_length(seed_path)
        for q in at_parameters(dut, np.linspace(0.0, 1.0, samples)):
            assert scene.clearance(q, 0.05) >= distance - 1e-4
    finally:
        scene.remove_object("wall")


def test_a_start_in_collision_gives_none(scene, ends):
    colliding = np.array([0.0, 1.7, 0.0, -0.5, 0.0, 0.5, 0.0])  # through the table
    assert not scene.is_collision_free(colliding)
    path = np.vstack([colliding, ends[1]])
    assert mut.kto_refine(scene, path, max_velocity=V_MAX, control_points=8) is None


def test_kto_shorter_keeps_the_shorter_free_path(scene, ends):
    from planning.collision.checker import CheckerAdapter
    from planning.planner_options import ValidationOptions

    adapter, validation = CheckerAdapter(scene), ValidationOptions()
    seed_path = detour(ends, 0.3 * E[1])
    path, how = mut.kto_shorter(scene, seed_path, "rrt_connect", V_MAX, adapter, validation)
    assert how == "rrt_connect+kto" and path_length(path) < path_length(seed_path)
    straight = np.vstack(ends)  # nothing shorter: kept as it is
    path, how = mut.kto_shorter(scene, straight, "rrt_connect", V_MAX, adapter, validation)
    assert how == "rrt_connect" and path is straight
