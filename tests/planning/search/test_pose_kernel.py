"""The compiled Newton steps' pieces (planning.search.pose_kernel): the rotation error is the
rotation vector (near a half turn too), the frame's pose and Jacobian are Drake's, and the
steps reach reachable targets and give up on unreachable or non-finite ones."""

import numpy as np
import pytest
from pydrake.common.eigen_geometry import AngleAxis, Quaternion
from pydrake.math import RotationMatrix
from pydrake.multibody.tree import JacobianWrtVariable

from planning import PlanningScene
from planning.collision.checker import CheckerAdapter
from planning.collision.sphere_fk import BatchedKinematics
from planning.search import pose_kernel as mut


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


def random_rotation(rng):
    q = rng.normal(size=4)
    return RotationMatrix(Quaternion(q / np.linalg.norm(q)))


def chain_of(scene, name):
    """(the frame, its chain's arrays, its body's step, X_BE (3, 4), the arm's indices)."""
    frame = scene.plant.GetFrameByName(name, scene.model.instance)
    kinematics = BatchedKinematics(scene.plant, [frame.body().index()])
    X_BE = frame.GetFixedPoseInBodyFrame().GetAsMatrix34()
    arm = np.asarray(scene.model.arm_indices, dtype=np.int64)
    return frame, kinematics.arrays(), int(kinematics.out[0]), X_BE, arm


@pytest.mark.parametrize("turn", [0.0, 1e-10, 0.3, 2.0, 3.0, 3.1, np.pi])
def test_the_rotation_error_is_the_rotation_vector(turn):
    rng = np.random.default_rng(1)
    R = random_rotation(rng)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    R_target = RotationMatrix(AngleAxis(turn, axis)) @ R
    vector = np.empty(3)
    angle = mut.rotation_error(R_target.matrix(), R.matrix(), vector)
    assert angle == pytest.approx(turn, abs=1e-7)
    if 1e-6 < turn < np.pi - 1e-6:
        np.testing.assert_allclose(vector, turn * axis, atol=1e-7)
    else:  # a half turn either way round is the same rotation
        assert np.linalg.norm(vector) == pytest.approx(turn, abs=1e-7)
        if turn > 3.0:
            np.testing.assert_allclose(np.abs(vector), turn * np.abs(axis), atol=1e-6)


@pytest.mark.parametrize("name", ["panda_hand_tcp", "panda_link4", "panda_leftfinger"])
def test_the_frame_pose_and_jacobian_are_drakes(scene, name):
    plant = scene.plant
    frame, chain, body, X_BE, arm = chain_of(scene, name)
    T, X, J = np.empty((len(chain[0]), 3, 4)), np.empty((3, 4)), np.empty((6, 7))
    adapter = CheckerAdapter(scene)
    rng = np.random.default_rng(3)
    for _ in range(10):
        full = scene.full_q(rng.uniform(adapter.lower, adapter.upper))
        mut.frame_pose(full, *chain, body, X_BE, T, X)
        mut.frame_jacobian(full, *chain, T, X, arm, J)
        context = scene.plant_context(full[arm])
        np.testing.assert_allclose(X, frame.CalcPoseInWorld(context).GetAsMatrix34(), atol=1e-12)
        expected = plant.CalcJacobianSpatialVelocity(
            context,
            JacobianWrtVariable.kQDot,
            frame,
            np.zeros(3),
            plant.world_frame(),
            plant.world_frame(),
        )[:, arm]
        np.testing.assert_allclose(J, expected, atol=1e-12)


def test_newton_reaches_reachable_targets_and_gives_up_on_others(scene):
    frame, chain, body, X_BE, arm = chain_of(scene, scene.model.ee_frame)
    adapter = CheckerAdapter(scene)
    lower, upper = adapter.lower, adapter.upper
    data = (scene.full_q(np.zeros(7)), arm, *chain, body, X_BE, lower, upper)
    rng = np.random.default_rng(4)
    T, X = np.empty((len(chain[0]), 3, 4)), np.empty((3, 4))
    reached = 0
    for _ in range(20):
        q_goal = rng.uniform(lower, upper)
        mut.frame_pose(scene.full_q(q_goal), *chain, body, X_BE, T, X)
        R_T, p_T = X[:, :3].copy(), X[:, 3].copy()
        q0 = np.clip(q_goal + rng.normal(scale=0.2, size=7), lower, upper)
        found, q = mut.newton(q0, data, R_T, p_T, True, True, 100, q0, False)
        if found:
            reached += 1
            pose = frame.CalcPoseInWorld(scene.plant_context(q))
            assert np.linalg.norm(pose.translation() - p_T) < 1e-4
            assert (RotationMatrix(R_T).inverse() @ pose.rotation()).ToAngleAxis().angle() < 1e-3
            assert np.all(q >= lower) and np.all(q <= upper)
    assert reached >= 18  # from 0.2 rad away, nearly always
    q0 = scene.model.named_configurations["ready"]
    for p_T in (np.array([3.0, 0.0, 0.5]), np.array([np.nan, 0.0, 0.5])):  # out of reach; NaN
        found, _ = mut.newton(q0, data, np.eye(3), p_T, False, True, 50, q0, False)
        assert not found


def test_a_line_of_poses_is_solved_step_by_step_and_stops_at_a_jump_or_a_miss(scene):
    frame, chain, body, X_BE, arm = chain_of(scene, scene.model.ee_frame)
    adapter = CheckerAdapter(scene)
    lower, upper = adapter.lower, adapter.upper
    q0 = scene.model.named_configurations["ready"][:7].astype(float)
    T, X = np.empty((len(chain[0]), 3, 4)), np.empty((3, 4))
    mut.frame_pose(scene.full_q(q0), *chain, body, X_BE, T, X)
    steps = 10
    p = X[:, 3] + np.outer(np.arange(1, steps + 1) / steps, [0.0, 0.0, -0.1])  # 10 cm down
    R = np.repeat(X[None, :, :3], steps, axis=0)
    data = (scene.full_q(np.zeros(7)), arm, *chain, body, X_BE, lower, upper)

    def run(p_targets, jump):
        return mut.line(q0, data, R[: len(p_targets)], p_targets, jump, 30)

    path, status = run(p, 0.2)
    assert status == 0 and len(path) == steps + 1
    for k in range(1, len(path)):
        mut.frame_pose(scene.full_q(path[k]), *chain, body, X_BE, T, X)
        assert np.linalg.norm(X[:, 3] - p[k - 1]) < 1e-4
    assert np.max(np.abs(np.diff(path, axis=0))) <= 0.2
    path, status = run(p, 1e-4)  # every step moves some joint more than that
    assert status == 2 and len(path) == 1
    far = p.copy()
    far[5:] += [2.0, 0.0, 0.0]  # out of reach from the sixth pose on
    path, status = run(far, 0.2)
    assert status == 1 and len(path) == 6
