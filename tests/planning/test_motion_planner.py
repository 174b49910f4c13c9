"""MotionPlanner: every request type on a pick-and-place scene, failures with their codes, and
paths re-checked independently at 0.01 rad."""

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix

import planning.motion_planner as mut
from planning import ErrorCode, Plan, PlanningError, PlanningScene, PlanResult
from planning.planner_options import KtoOptions, RrtConnectOptions, TimingOptions, ValidationOptions

# m, p_WO of the object's centre, 2 mm above the table: a held object touching the table counts
# as a collision (the scene cannot yet allow held-object/support contacts, MoveIt's touch links).
OBJECT = np.array([0.5, -0.2, 0.032])
PLACE = np.array([0.5, 0.2, 0.03])  # m
R_DOWN = RotationMatrix.MakeXRotation(np.pi)  # hand z axis pointing down


@pytest.fixture(scope="module")
def scene():
    """DESIGN.md's pick-and-place scene: table, object box, obstacle box between object and
    place."""
    scene = PlanningScene()
    scene.add_box("object", [0.04, 0.04, 0.06], RigidTransform(OBJECT))
    scene.add_box("obstacle", [0.1, 0.04, 0.3], RigidTransform([0.5, 0.0, 0.15]))
    scene.place_position = PLACE
    return scene


@pytest.fixture
def dut(scene):
    planner = mut.MotionPlanner(scene)
    yield planner
    for name in set(scene.world_objects) - {"table", "object", "obstacle"}:
        scene.remove_object(name)


def assert_fine_collision_free(scene, path, resolution=0.01):
    """Checks the straight-line interpolation with the scene's own single-config query."""
    for a, b in zip(path[:-1], path[1:], strict=True):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / resolution)))
        for s in np.linspace(0.0, 1.0, n + 1):
            assert scene.is_collision_free(a + s * (b - a)), f"collision at {a + s * (b - a)}"


def above(p, height):
    return RigidTransform(R_DOWN, p + [0.0, 0.0, height])


def test_joint_goal_from_current_state(dut, scene):
    goal = dut.state.named("extended")
    result = dut.plan_to_joints(goal)
    assert isinstance(result, PlanResult) and isinstance(result.trajectory, Plan)
    assert result.success and result.code is None
    path = result.trajectory.waypoints
    np.testing.assert_allclose(path[0], dut.state.q)
    np.testing.assert_allclose(path[-1], goal)
    assert result.trajectory.duration > 0
    assert_fine_collision_free(scene, path)


def test_named_goal(dut, scene):
    result = dut.plan_to_named("transport", q_start=dut.state.named("extended"))
    np.testing.assert_allclose(result.trajectory.waypoints[-1], dut.state.named("transport"))
    assert_fine_collision_free(scene, result.trajectory.waypoints)


def test_pose_goals_reach_their_targets(dut, scene):
    target = above(OBJECT, 0.15)
    result = dut.plan_to_pose(target)
    X_WE = dut.state.fk(result.trajectory.waypoints[-1])
    np.testing.assert_allclose(X_WE.translation(), target.translation(), atol=2e-3)
    angle = (X_WE.rotation().inverse() @ R_DOWN).ToAngleAxis().angle()
    assert angle < 0.02
    assert_fine_collision_free(scene, result.trajectory.waypoints)

    result = dut.plan_to_pose(p_WE=PLACE + [0.0, 0.0, 0.2])
    X_WE = dut.state.fk(result.trajectory.waypoints[-1])
    np.testing.assert_allclose(X_WE.translation(), PLACE + [0.0, 0.0, 0.2], atol=2e-3)

    result = dut.plan_to_pose(R_WE=R_DOWN)
    X_WE = dut.state.fk(result.trajectory.waypoints[-1])
    assert (X_WE.rotation().inverse() @ R_DOWN).ToAngleAxis().angle() < 0.02


def test_over_the_obstacle_needs_a_search_and_stays_free(dut, scene):
    q_a = dut.plan_to_pose(above(OBJECT, 0.06)).trajectory.waypoints[-1]
    q_b = dut.plan_to_pose(above(PLACE, 0.06), q_start=q_a).trajectory.waypoints[-1]
    assert not scene.is_edge_collision_free(q_a, q_b)
    result = dut.plan_to_joints(q_b, q_start=q_a)
    assert result.trajectory.info["planner"].startswith("rrt_connect")
    assert_fine_collision_free(scene, result.trajectory.waypoints)


def test_one_extension_per_query_also_finds_a_free_path(dut, scene):
    """rrt.batch 1: the classic RRT-Connect (planning.search.rrt.rrt_connect) instead of batches."""
    q_a = dut.plan_to_pose(above(OBJECT, 0.06)).trajectory.waypoints[-1]
    q_b = dut.plan_to_pose(above(PLACE, 0.06), q_start=q_a).trajectory.waypoints[-1]
    planner = mut.MotionPlanner(scene, mut.MotionPlannerOptions(rrt=RrtConnectOptions(batch=1)))
    path = planner.plan_to_joints(q_b, q_start=q_a).trajectory.waypoints
    np.testing.assert_array_equal(path[[0, -1]], [q_a, q_b])
    assert_fine_collision_free(scene, path)


def test_cartesian_descent_is_complete(dut, scene):
    q_pre = dut.plan_to_pose(above(OBJECT, 0.15)).trajectory.waypoints[-1]
    result = dut.plan_cartesian(above(OBJECT, 0.08), q_start=q_pre)
    assert result.success and result.fraction == 1.0
    X_WE = dut.state.fk(result.trajectory.waypoints[-1])
    np.testing.assert_allclose(X_WE.translation(), OBJECT + [0, 0, 0.08], atol=1e-3)
    # The hand moves along the line: every waypoint's position is on the segment.
    for q in result.trajectory.waypoints:
        p = dut.state.fk(q).translation()
        assert np.linalg.norm(p[:2] - OBJECT[:2]) < 2e-3
    assert_fine_collision_free(scene, result.trajectory.waypoints)


def test_cartesian_through_the_obstacle_is_partial_not_success(dut, scene):
    q_a = dut.plan_to_pose(above(OBJECT, 0.06)).trajectory.waypoints[-1]
    result = dut.plan_cartesian(above(PLACE, 0.06), q_start=q_a)
    assert not result.success
    assert result.code == ErrorCode.PLANNING_FAILED
    assert 0.0 < result.fraction < 1.0
    assert "obstacle" in result.message
    assert_fine_collision_free(scene, result.trajectory.waypoints)


def test_goal_inside_an_added_box_fails_with_goal_in_collision(dut, scene):
    goal = dut.state.named("extended")
    X_WE = dut.state.fk(goal)
    scene.add_box("crate", [0.1, 0.1, 0.1], X_WE)
    with pytest.raises(PlanningError) as e:
        dut.plan_to_joints(goal)
    assert e.value.code == ErrorCode.GOAL_IN_COLLISION
    assert "crate" in e.value.message
    with pytest.raises(PlanningError) as e:
        dut.plan_to_pose(X_WE)
    assert e.value.code == ErrorCode.GOAL_IN_COLLISION
    assert "crate" in e.value.message


def test_start_in_collision(dut, scene):
    start = dut.state.named("ready")
    scene.add_box("crate", [0.1, 0.1, 0.1], dut.state.fk(start))
    with pytest.raises(PlanningError) as e:
        dut.plan_to_named("extended", q_start=start)
    assert e.value.code == ErrorCode.START_IN_COLLISION
    assert "crate" in e.value.message


@pytest.mark.parametrize(
    "goal", [[np.nan] * 7, [0.0] * 6, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 5.0]], ids=str
)
def test_invalid_goals(dut, goal):
    with pytest.raises(PlanningError) as e:
        dut.plan_to_joints(goal)
    assert e.value.code == ErrorCode.INVALID_GOAL


def test_unknown_named_goal(dut):
    with pytest.raises(PlanningError) as e:
        dut.plan_to_named("nowhere")
    assert e.value.code == ErrorCode.INVALID_GOAL


def test_timeout(dut):
    q_a = dut.plan_to_pose(above(OBJECT, 0.06)).trajectory.waypoints[-1]
    q_b = dut.plan_to_pose(above(PLACE, 0.06), q_start=q_a).trajectory.waypoints[-1]
    with pytest.raises(PlanningError) as e:
        dut.plan_to_joints(q_b, q_start=q_a, timeout=1e-6)
    assert e.value.code == ErrorCode.TIMED_OUT


def test_same_seed_same_path(scene):
    q_a = mut.MotionPlanner(scene).plan_to_pose(above(OBJECT, 0.06)).trajectory.waypoints[-1]
    goal = mut.MotionPlanner(scene).state.named("extended")
    paths = [
        mut.MotionPlanner(scene).plan_to_joints(goal, q_start=q_a).trajectory.waypoints
        for _ in range(2)
    ]
    np.testing.assert_array_equal(paths[0], paths[1])


def test_pick_and_place_sequence(dut, scene):
    """ready -> pre-grasp -> grasp (Cartesian) -> lift -> pre-place over the obstacle -> place."""
    X_WO = scene.object_pose("object")
    q = dut.state.named("ready")
    steps = []
    try:
        steps.append(dut.plan_to_pose(above(OBJECT, 0.12), q_start=q))
        steps.append(dut.plan_cartesian(above(OBJECT, 0.0), q_start=steps[-1].plan.waypoints[-1]))
        q_grasp = steps[-1].plan.waypoints[-1]
        scene.attach("object", q_grasp)
        steps.append(dut.plan_cartesian(above(OBJECT, 0.15), q_start=q_grasp))
        steps.append(dut.plan_to_pose(above(PLACE, 0.15), q_start=steps[-1].plan.waypoints[-1]))
        steps.append(dut.plan_cartesian(above(PLACE, 0.005), q_start=steps[-1].plan.waypoints[-1]))
        assert all(step.success for step in steps)
        for step in steps:
            assert_fine_collision_free(scene, step.plan.waypoints)
        q_place = steps[-1].plan.waypoints[-1]
        np.testing.assert_allclose(
            scene.object_pose("object", q_place).translation(), PLACE + [0, 0, 0.005], atol=2e-3
        )
    finally:
        if "object" in scene.attached_objects:
            scene.remove_object("object")
            scene.add_object(scene_object_at(X_WO))


def scene_object_at(X_WO):
    from planning import SceneObject

    return SceneObject("object", "box", (0.04, 0.04, 0.06), X_WO)


def test_bad_options_are_rejected(scene):
    with pytest.raises(ValueError, match="timing.velocity_scaling"):
        timing = TimingOptions(velocity_scaling=1.5)
        mut.MotionPlanner(scene, mut.MotionPlannerOptions(timing=timing))
    with pytest.raises(ValueError, match="validation.resolution"):
        validation = ValidationOptions(resolution=0.05)
        mut.MotionPlanner(scene, mut.MotionPlannerOptions(validation=validation))


def test_scaling_slows_the_plan(dut):
    timing = TimingOptions(velocity_scaling=0.5, acceleration_scaling=0.25)
    slow = mut.MotionPlanner(dut.scene, mut.MotionPlannerOptions(timing=timing))
    goal = dut.state.named("extended")
    fast_plan, slow_plan = dut.plan_to_joints(goal).plan, slow.plan_to_joints(goal).plan
    assert slow_plan.duration == pytest.approx(2.0 * fast_plan.duration)


def test_kto_refinement_keeps_a_valid_path(scene):
    options = mut.MotionPlannerOptions(kto=KtoOptions(enabled=True))
    dut = mut.MotionPlanner(scene, options)
    q_a = dut.plan_to_pose(above(OBJECT, 0.06)).trajectory.waypoints[-1]
    q_b = dut.plan_to_pose(above(PLACE, 0.06), q_start=q_a).trajectory.waypoints[-1]
    result = dut.plan_to_joints(q_b, q_start=q_a)
    assert result.trajectory.info["planner"].startswith("rrt_connect")
    assert_fine_collision_free(scene, result.trajectory.waypoints)


@pytest.mark.parametrize("timeout", [float("nan"), float("inf"), 0.0, -1.0])
def test_a_timeout_that_is_not_finite_seconds_is_an_invalid_request(dut, scene, timeout):
    ready = scene.model.named_configurations["ready"]
    requests = [
        lambda: dut.plan_to_joints(ready, timeout=timeout),
        lambda: dut.plan_path(ready, ready, timeout=timeout),
        lambda: dut.plan_to_pose(scene.attachment_pose(ready), timeout=timeout),
    ]
    for request in requests:
        with pytest.raises(PlanningError) as raised:
            request()
        assert raised.value.code is ErrorCode.INVALID_MOTION_PLAN  # not "found no path"
        assert "timeout" in raised.value.message
