"""Cartesian straight-line paths (planning.search.cartesian): interpolate_pose moves the position
linearly and the orientation by slerp; cartesian_path follows the line from the hand's pose to the
goal in small steps (each waypoint's hand pose on the line, joint changes below the jump
threshold), and stops before a collision, at a joint jump or beyond reach, reporting the fraction
achieved and why."""

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.tree import JacobianWrtVariable

import planning.search.cartesian as mut
from planning import PlanningScene
from planning.collision.checker import CheckerAdapter
from planning.paths import densify

STEP = 0.005  # m
OPTIONS = dict(max_step=STEP, max_rotation_step=0.05, jump_threshold=0.2, resolution=0.01)


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


@pytest.fixture(scope="module")
def frame(scene):
    return scene.plant.GetFrameByName(scene.model.ee_frame, scene.model.instance)


@pytest.fixture(scope="module")
def ready(scene):
    return scene.model.named_configurations["ready"]


def pose(scene, frame, q):
    return frame.CalcPoseInWorld(scene.plant_context(q))


def plan(scene, frame, q_start, X_WG, **options):
    return mut.cartesian_path(
        scene, CheckerAdapter(scene), frame, q_start, X_WG, **{**OPTIONS, **options}
    )


def angle(R_a, R_b):
    return (R_a.inverse() @ R_b).ToAngleAxis().angle()


def test_interpolate_pose():
    X_a = RigidTransform(RotationMatrix.MakeXRotation(np.pi), [0.3, 0.0, 0.5])
    X_b = RigidTransform(
        RotationMatrix.MakeXRotation(np.pi) @ RotationMatrix.MakeZRotation(0.8), [0.5, 0.2, 0.3]
    )
    np.testing.assert_allclose(
        mut.interpolate_pose(X_a, X_b, 0.0).GetAsMatrix4(), X_a.GetAsMatrix4(), atol=1e-12
    )
    np.testing.assert_allclose(
        mut.interpolate_pose(X_a, X_b, 1.0).GetAsMatrix4(), X_b.GetAsMatrix4(), atol=1e-12
    )
    for s in (0.25, 0.5, 0.9):
        X = mut.interpolate_pose(X_a, X_b, s)
        np.testing.assert_allclose(X.translation(), [0.3 + 0.2 * s, 0.2 * s, 0.5 - 0.2 * s])
        # About the same axis, a fraction s of the way.
        assert angle(X_a.rotation(), X.rotation()) == pytest.approx(0.8 * s)
        assert angle(X.rotation(), X_b.rotation()) == pytest.approx(0.8 * (1 - s))


def test_a_straight_line_down_is_followed_to_the_end(scene, frame, ready):
    X_WS = pose(scene, frame, ready)
    X_WG = RigidTransform(X_WS.rotation(), X_WS.translation() + [0.0, 0.05, -0.1])
    dut = plan(scene, frame, ready, X_WG)
    assert dut.fraction == 1.0 and dut.reason == ""
    path = dut.waypoints
    np.testing.assert_array_equal(path[0], ready)
    assert len(path) == 1 + int(np.ceil(np.linalg.norm([0.05, 0.1]) / STEP))
    X_end = pose(scene, frame, path[-1])
    np.testing.assert_allclose(X_end.translation(), X_WG.translation(), atol=2e-4)
    assert angle(X_end.rotation(), X_WG.rotation()) < 2e-3
    # Every waypoint's hand pose is on the line, with the start's orientation.
    direction = (X_WG.translation() - X_WS.translation()) / 0.05 / np.sqrt(5)
    for k, q in enumerate(path):
        X = pose(scene, frame, q)
        offset = X.translation() - X_WS.translation()
        assert np.linalg.norm(offset - (offset @ direction) * direction) < 2e-4
        assert offset @ direction == pytest.approx(k * np.sqrt(0.0125) / (len(path) - 1), abs=2e-4)
        assert angle(X.rotation(), X_WS.rotation()) < 2e-3
    assert np.max(np.abs(np.diff(path, axis=0))) <= OPTIONS["jump_threshold"]
    assert all(scene.is_collision_free(q) for q in densify(path, 0.01)[0])


def test_a_rotation_in_place(scene, frame, ready):
    X_WS = pose(scene, frame, ready)
    R_WG = X_WS.rotation() @ RotationMatrix.MakeZRotation(0.5)
    dut = plan(scene, frame, ready, RigidTransform(R_WG, X_WS.translation()))
    assert dut.fraction == 1.0
    assert len(dut.waypoints) == 1 + 10  # 0.5 rad in steps of at most 0.05 rad
    X_end = pose(scene, frame, dut.waypoints[-1])
    assert angle(X_end.rotation(), R_WG) < 2e-3
    for q in dut.waypoints:
        np.testing.assert_allclose(
            pose(scene, frame, q).translation(), X_WS.translation(), atol=2e-4
        )


def test_stops_before_an_obstacle_on_the_line(scene, frame, ready):
    X_WS = pose(scene, frame, ready)
    X_WG = RigidTransform(X_WS.rotation(), X_WS.translation() + [0.0, 0.0, -0.1])
    scene.add_box("block", [0.1, 0.1, 0.02], RigidTransform(X_WS.translation() + [0, 0, -0.08]))
    try:
        dut = plan(scene, frame, ready, X_WG)
        assert 0.0 < dut.fraction < 1.0
        assert dut.reason.startswith("collision") and "block" in dut.reason
        path = dut.waypoints
        steps = np.ceil(np.linalg.norm(X_WG.translation() - X_WS.translation()) / STEP)
        assert dut.fraction == pytest.approx((len(path) - 1) / steps)
        assert all(scene.is_collision_free(q) for q in densify(path, 0.01)[0])
        # It stopped at the last step before the block, not earlier.
        assert pose(scene, frame, path[-1]).translation()[2] < X_WS.translation()[2] - 0.04
    finally:
        scene.remove_object("block")


def test_stops_at_a_joint_jump_and_beyond_reach(scene, frame, ready):
    X_WS = pose(scene, frame, ready)
    X_WG = RigidTransform(X_WS.rotation(), X_WS.translation() + [0.0, 0.0, -0.1])
    jumpy = plan(scene, frame, ready, X_WG, jump_threshold=1e-4)
    assert jumpy.fraction == 0.0 and "joint jump" in jumpy.reason
    np.testing.assert_array_equal(jumpy.waypoints, [ready])
    far = plan(scene, frame, ready, RigidTransform(X_WS.rotation(), [1.5, 0.0, 0.5]))
    assert 0.0 < far.fraction < 1.0 and "no IK solution" in far.reason
    adapter = CheckerAdapter(scene)
    assert np.all((far.waypoints >= adapter.lower) & (far.waypoints <= adapter.upper))


def random_rotation(rng):
    q = rng.normal(size=4)
    from pydrake.common.eigen_geometry import Quaternion

    return RotationMatrix(Quaternion(q / np.linalg.norm(q)))


def test_the_line_slerps_as_drake_does_the_shorter_way():
    from pydrake.common.eigen_geometry import Quaternion

    rng = np.random.default_rng(0)
    for _ in range(20):  # pairs more than a quarter turn apart among them (dot < 0)
        R_a, R_b = random_rotation(rng), random_rotation(rng)
        X_a, X_b = RigidTransform(R_a, rng.normal(size=3)), RigidTransform(R_b, rng.normal(size=3))
        s = rng.uniform(size=5)
        R, p = mut._line(X_a, X_b, s)
        for k in range(len(s)):
            quat = R_a.ToQuaternion().slerp(s[k], R_b.ToQuaternion())
            expected = RotationMatrix(Quaternion(quat.wxyz() / np.linalg.norm(quat.wxyz())))
            np.testing.assert_allclose(R[k], expected.matrix(), atol=1e-12)
            np.testing.assert_allclose(
                p[k], (1 - s[k]) * X_a.translation() + s[k] * X_b.translation()
            )


def test_pose_newton_with_rest_finds_the_nearest_joints_on_the_target(scene, frame, ready):
    adapter = CheckerAdapter(scene)
    context = scene.plant.CreateDefaultContext()
    dut = mut.PoseNewton(
        scene.plant,
        frame,
        adapter.full,
        scene.model.arm_indices,
        adapter.lower,
        adapter.upper,
    )
    X = pose(scene, frame, ready)
    np.testing.assert_allclose(dut.pose(ready).GetAsMatrix4(), X.GetAsMatrix4(), atol=1e-12)
    target = RigidTransform(X.rotation(), X.translation() + [0.1, -0.15, -0.2])
    plain = dut.solve(ready, target.rotation().matrix(), target.translation(), 100)
    rest = dut.solve(ready, target.rotation().matrix(), target.translation(), 100, rest=ready)
    for q in (plain, rest):
        X_q = pose(scene, frame, q)
        np.testing.assert_allclose(X_q.translation(), target.translation(), atol=1e-4)
        assert angle(X_q.rotation(), target.rotation()) < 1e-3
    # Moving along the self-motion (the Jacobian's null space) gets no nearer the rest.
    scene.plant.SetPositions(context, adapter.full(rest))
    J = scene.plant.CalcJacobianSpatialVelocity(
        context,
        JacobianWrtVariable.kQDot,
        frame,
        np.zeros(3),
        scene.plant.world_frame(),
        scene.plant.world_frame(),
    )[:, scene.model.arm_indices]
    null = np.linalg.svd(J)[2][-1]
    assert abs(null @ (ready - rest)) < 1e-3
    assert np.linalg.norm(rest - ready) <= np.linalg.norm(plain - ready) + 1e-9
    # Position alone, and a target out of reach.
    q = dut.solve(ready, None, target.translation() + [0.0, 0.0, 0.1], 100)
    np.testing.assert_allclose(
        pose(scene, frame, q).translation(), target.translation() + [0, 0, 0.1], atol=1e-4
    )
    assert dut.solve(ready, None, np.array([3.0, 0.0, 0.5]), 50) is None
