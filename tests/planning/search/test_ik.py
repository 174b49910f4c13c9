"""Collision-aware inverse kinematics (planning.search.ik): IkSolver places the hand at a position,
an orientation or both within the tolerances, within the joint limits and collision-free, the
same way for the same seed; it rejects missing or non-finite targets, unknown frames and
targets beyond reach, and reports targets reachable only in collision."""

import dataclasses as dc

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix

import planning.search.ik as mut
from planning import ErrorCode, IkOptions, PlanningError, PlanningScene

FRAME = "panda_hand_tcp"
R_DOWN = RotationMatrix.MakeXRotation(np.pi)  # hand z axis pointing down
TARGET = np.array([0.5, 0.1, 0.3])  # m
OPTIONS = IkOptions()


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


@pytest.fixture(scope="module")
def dut(scene):
    return mut.IkSolver(scene)


def fk(scene, q):
    frame = scene.plant.GetFrameByName(FRAME, scene.model.instance)
    return frame.CalcPoseInWorld(scene.plant_context(q))


def angle(R_a, R_b):
    return (R_a.inverse() @ R_b).ToAngleAxis().angle()


def test_position_and_orientation_within_tolerance(scene, dut):
    result = dut.solve(FRAME, p_WE=TARGET, R_WE=R_DOWN, options=OPTIONS)
    assert isinstance(result, mut.IkResult) and result.attempts >= 1
    assert result.q.shape == (7,) and scene.in_joint_limits(result.q)
    assert scene.is_collision_free(result.q)
    X_WE = fk(scene, result.q)  # the reported pose is the one reached
    np.testing.assert_allclose(result.X_WE.GetAsMatrix4(), X_WE.GetAsMatrix4(), atol=1e-12)
    assert np.max(np.abs(X_WE.translation() - TARGET)) <= OPTIONS.position_tolerance * 1.01
    assert angle(X_WE.rotation(), R_DOWN) <= OPTIONS.orientation_tolerance * 1.01
    # Tighter tolerances are met too.
    tight = dc.replace(OPTIONS, position_tolerance=1e-4, orientation_tolerance=1e-3)
    X_tight = fk(scene, dut.solve(FRAME, p_WE=TARGET, R_WE=R_DOWN, options=tight).q)
    assert np.max(np.abs(X_tight.translation() - TARGET)) <= 1.01e-4
    assert angle(X_tight.rotation(), R_DOWN) <= 1.01e-3


def test_position_only_and_orientation_only(scene, dut):
    ready = scene.model.named_configurations["ready"]
    position = dut.solve(FRAME, p_WE=TARGET, options=OPTIONS)
    assert np.max(np.abs(fk(scene, position.q).translation() - TARGET)) <= 1.01e-3
    tilted = R_DOWN @ RotationMatrix.MakeYRotation(0.3)
    orientation = dut.solve(FRAME, R_WE=tilted, q_seed=ready, options=OPTIONS)
    assert angle(fk(scene, orientation.q).rotation(), tilted) <= 1.01e-2
    # The position is free: the solution stays near the seed's.
    seed_position = fk(scene, ready).translation()
    assert np.linalg.norm(fk(scene, orientation.q).translation() - seed_position) < 0.2


def test_the_same_seed_gives_the_same_solution(scene):
    first = mut.IkSolver(scene).solve(FRAME, p_WE=TARGET, R_WE=R_DOWN, options=OPTIONS)
    again = mut.IkSolver(scene).solve(FRAME, p_WE=TARGET, R_WE=R_DOWN, options=OPTIONS)
    np.testing.assert_array_equal(first.q, again.q)
    # A 9-value seed (fingers included) is read as its 7 arm joints.
    ready = scene.model.named_configurations["ready"]
    seeded7 = mut.IkSolver(scene).solve(FRAME, p_WE=TARGET, q_seed=ready, options=OPTIONS)
    seeded9 = mut.IkSolver(scene).solve(
        FRAME, p_WE=TARGET, q_seed=scene.full_q(ready), options=OPTIONS
    )
    np.testing.assert_array_equal(seeded7.q, seeded9.q)


def test_bad_requests_are_rejected(dut):
    def code(**kwargs):
        with pytest.raises(PlanningError) as e:
            dut.solve(kwargs.pop("frame", FRAME), options=OPTIONS, **kwargs)
        return e.value.code, e.value.message

    assert code()[0] == ErrorCode.INVALID_GOAL  # no target at all
    assert code(p_WE=[np.nan, 0.0, 0.3])[0] == ErrorCode.INVALID_GOAL
    assert code(p_WE=[0.5, 0.1])[0] == ErrorCode.INVALID_GOAL
    assert code(frame="no_such_frame", p_WE=TARGET) == (
        ErrorCode.FRAME_NOT_FOUND,
        "panda has no frame 'no_such_frame'",
    )
    far, message = code(p_WE=[2.0, 0.0, 0.5])
    assert far == ErrorCode.NO_IK_SOLUTION and "beyond the reach" in message


def test_targets_reachable_only_in_collision_are_reported(scene, dut):
    scene.add_box("block", [0.2, 0.2, 0.2], RigidTransform(TARGET))
    try:
        few = dc.replace(OPTIONS, max_restarts=2)
        with pytest.raises(PlanningError) as e:
            dut.solve(FRAME, p_WE=TARGET, R_WE=R_DOWN, options=few)
        assert e.value.code == ErrorCode.NO_IK_SOLUTION
        # Without the distance constraint the solver finds solutions, which the check rejects,
        # naming what collides.
        unconstrained = dc.replace(few, minimum_distance=None)
        with pytest.raises(PlanningError, match="solutions collide: block") as e:
            dut.solve(FRAME, p_WE=TARGET, R_WE=R_DOWN, options=unconstrained)
        assert e.value.code == ErrorCode.NO_IK_SOLUTION
        # Without the check as well, a colliding solution is returned.
        unchecked = dc.replace(unconstrained, check_collisions=False)
        result = dut.solve(FRAME, p_WE=TARGET, R_WE=R_DOWN, options=unchecked)
        assert not scene.is_collision_free(result.q)
    finally:
        scene.remove_object("block")


def test_obstacles_near_the_target_are_avoided(scene, dut):
    """A bar just above the target, where the hand would be without it: the solution reaches
    around it."""
    before = dut.solve(FRAME, p_WE=TARGET, options=OPTIONS)
    scene.add_box("bar", [0.04, 0.3, 0.04], RigidTransform(TARGET + [0.0, 0.0, 0.12]))
    try:
        assert not scene.is_collision_free(before.q)
        result = dut.solve(FRAME, p_WE=TARGET, options=OPTIONS)
        assert scene.is_collision_free(result.q)
        assert np.max(np.abs(fk(scene, result.q).translation() - TARGET)) <= 1.01e-3
    finally:
        scene.remove_object("bar")


@pytest.mark.parametrize(
    "target", [TARGET, np.array([0.4, -0.3, 0.5]), np.array([0.3, 0.4, 0.2])], ids=str
)
def test_newton_steps_find_the_programs_answer(scene, dut, monkeypatch, target):
    """The Newton steps (pulled towards the seed) land where the nonlinear program alone goes
    from the seed, within a few milliradians."""
    newton = dut.solve(FRAME, p_WE=target, R_WE=R_DOWN, options=OPTIONS)
    monkeypatch.setattr(mut.PoseNewton, "solve", lambda *args, **kwargs: None)
    program = dut.solve(FRAME, p_WE=target, R_WE=R_DOWN, options=OPTIONS)
    assert np.max(np.abs(newton.q - program.q)) < 0.01
