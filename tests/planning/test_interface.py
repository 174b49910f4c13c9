"""MotionPlanningInterface on the Panda station, in simulated time: blocking and asynchronous
use, failures that leave the robot still, cancellation, superseded and overdue actions, closing
(the property and abuse tests: test_interface_robustness.py)."""

import threading
import time

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix

from diagrams.pickplace_scenario import load_pickplace_scenario
from diagrams.planning_station import make_planning_station
from planning import ErrorCode, PlanningError
from planning.model.layout import FINGER_OPEN

R_DOWN = RotationMatrix.MakeXRotation(np.pi)  # the hand's z axis pointing down
X_TARGET = RigidTransform(R_DOWN, [0.45, -0.25, 0.25])  # above the object


@pytest.fixture(scope="module")
def config():
    return load_pickplace_scenario()


@pytest.fixture
def dut(config):
    return make_planning_station(config, mode="kinematic")


def distance_to_path(waypoints, q) -> float:
    """The joint-space distance from q to the polyline through the waypoints, rad."""
    best = np.inf
    for a, b in zip(waypoints[:-1], waypoints[1:], strict=True):
        d = b - a
        s = np.clip((q - a) @ d / max(d @ d, 1e-300), 0.0, 1.0)
        best = min(best, float(np.linalg.norm(a + s * d - q)))
    return best


def assert_pose_reached(X_WE, X_target, position_tol, angle_tol):
    assert np.linalg.norm(X_WE.translation() - X_target.translation()) < position_tol
    angle = X_WE.rotation().InvertAndCompose(X_target.rotation()).ToAngleAxis().angle()
    assert angle < angle_tol


@pytest.mark.parametrize("mode,position_tol", [("kinematic", 1e-3), ("physics", 5e-3)])
def test_move_to_pose_reaches_it(config, mode, position_tol):
    dut = make_planning_station(config, mode=mode)
    result = dut.move_to_pose(X_TARGET)
    assert result.success and result.code is None
    dut.read_state()
    assert_pose_reached(dut.state.hand_pose(), X_TARGET, position_tol, 0.02)


def test_goal_inside_a_box_fails_and_nothing_moves(dut):
    q0 = dut.read_state()[:9]
    dut.scene.add_box("crate", [0.2, 0.2, 0.2], RigidTransform(X_TARGET.translation()))
    with pytest.raises(PlanningError) as error:
        dut.move_to_pose(X_TARGET)
    assert error.value.code is ErrorCode.GOAL_IN_COLLISION
    assert "crate" in error.value.message
    dut.advance(0.5)
    np.testing.assert_array_equal(dut.read_state()[:9], q0)


def test_execute_rechecks_the_plan_against_the_scene_now(dut):
    plan = dut.planner.plan_to_pose(X_TARGET).trajectory
    q0 = dut.read_state()[:9]
    middle = plan.sample(0.5 * plan.duration)[0]
    p_middle = dut.state.hand_pose(middle).translation()
    dut.scene.add_box("late_box", [0.1, 0.1, 0.1], RigidTransform(p_middle))
    with pytest.raises(PlanningError) as error:
        dut.execute(plan)
    assert error.value.code is ErrorCode.INVALID_MOTION_PLAN
    dut.advance(0.3)
    np.testing.assert_array_equal(dut.read_state()[:9], q0)


def test_async_execution_is_polled_while_other_work_goes_on(dut):
    first = dut.planner.plan_to_pose(X_TARGET).trajectory
    handle = dut.execute_async(first)
    # Other work while the arm moves: plan the way back from where this motion ends.
    back = dut.planner.plan_to_named("ready", q_start=first.waypoints[-1])
    assert back.success
    progress = []
    while not handle.done():
        progress.append(handle.progress)
        dut.advance(0.05)
    assert progress == sorted(progress) and 0.0 <= progress[0] < progress[-1] <= 1.0
    result = handle.result()
    assert result.success and handle.status == "succeeded"
    assert result.end_time >= first.duration
    np.testing.assert_allclose(dut.state.q, first.waypoints[-1], atol=1e-3)
    assert dut.execute(back).success


def test_cancel_midway_stops_the_arm_on_its_path(dut):
    plan = dut.planner.plan_to_pose(X_TARGET).trajectory
    handle = dut.execute_async(plan)
    dut.advance(0.4 * plan.duration)
    handle.cancel()
    result = handle.result()
    assert not result.success and result.code is ErrorCode.PREEMPTED
    assert handle.status == "cancelled"
    x = dut.read_state()
    np.testing.assert_allclose(x[9:], 0.0, atol=1e-6)  # at rest
    q = dut.state.q
    np.testing.assert_allclose(q, x[:7])  # the shared state is the robot's
    assert np.max(np.abs(q - plan.waypoints[-1])) > 0.05  # stopped before the goal
    assert distance_to_path(plan.waypoints, q) < 1e-3  # on the collision-checked path
    dut.advance(0.5)
    np.testing.assert_allclose(dut.state.q, q, atol=1e-9)  # and it stays there
    with pytest.raises(PlanningError) as error:  # the old plan no longer starts here
        dut.execute(dut.planner.plan_to_named("extended", q_start=plan.waypoints[0]))
    assert error.value.code is ErrorCode.INVALID_START
    assert dut.move_to_pose(X_TARGET).success  # and planning from here works


def test_plan_async_matches_blocking_and_can_be_cancelled(dut):
    blocking = dut.planner.plan_to_pose(X_TARGET).trajectory
    handle = dut.plan_async(dut.planner.plan_to_pose, X_TARGET)
    result = handle.result(timeout=60.0)
    assert handle.done() and handle.status == "succeeded" and handle.progress == 1.0
    np.testing.assert_array_equal(result.trajectory.waypoints, blocking.waypoints)
    cancelled = dut.plan_async(dut.planner.plan_to_named, "extended")
    cancelled.cancel()
    with pytest.raises(PlanningError) as error:
        cancelled.result()
    assert error.value.code is ErrorCode.PREEMPTED


def test_busy_arm_refuses_a_second_plan(dut):
    plan = dut.planner.plan_to_pose(X_TARGET).trajectory
    handle = dut.execute_async(plan)
    with pytest.raises(PlanningError, match="still executing"):
        dut.execute_async(plan)
    assert handle.result().success


def test_gripper_closes_on_nothing_and_on_the_object(dut):
    empty = dut.close_gripper()
    assert empty.success and not empty.grasped and empty.finger_position == pytest.approx(0.0)
    assert dut.open_gripper().finger_position == pytest.approx(FINGER_OPEN)
    with pytest.raises(PlanningError):
        dut.move_gripper(0.05)
    # Kinematic grasp: fingers stop at the object's faces and the object follows the hand.
    p_WO = dut.object_pose().translation()
    above = RigidTransform(R_DOWN, p_WO + [0.0, 0.0, 0.12])
    grasp = RigidTransform(R_DOWN, p_WO + [0.0, 0.0, 0.01])
    assert dut.move_to_pose(above).success
    assert dut.move_cartesian(grasp).success
    held = dut.close_gripper()
    assert held.success and held.grasped
    assert held.finger_position == pytest.approx(0.5 * 0.045, abs=1e-4)
    dut.scene.remove_object("object")  # held now: the planner must not see it on the table
    assert dut.move_cartesian(above).success
    np.testing.assert_allclose(dut.object_pose().translation(), p_WO + [0, 0, 0.11], atol=1e-3)


def test_monitor_sees_every_poll(dut):
    times = []
    dut.add_monitor(lambda mpi: times.append(mpi.time))
    dut.advance(0.1)
    np.testing.assert_allclose(np.diff(times), dut.options.poll_period)
    assert len(times) == 10


def test_gripper_move_can_be_cancelled(dut):
    handle = dut.move_gripper_async(0.0)
    dut.advance(0.2)
    assert 0.0 < handle.progress < 1.0
    handle.cancel()
    result = handle.result()
    assert result.code is ErrorCode.PREEMPTED and handle.status == "cancelled"
    assert 0.02 < result.finger_position < FINGER_OPEN  # stopped part way
    dut.advance(0.3)
    assert dut.read_state()[7] == pytest.approx(result.finger_position, abs=1e-6)


# ---------------------------------------------------------------- never hangs or dies ----
def test_plan_async_accepts_a_planning_timeout(dut):
    handle = dut.plan_async(dut.planner.plan_to_pose, X_TARGET, timeout=30.0)
    result = handle.result(timeout=60.0)
    assert result.success and dut.execute(result).success


def test_a_superseded_gripper_move_finishes_cancelled_with_the_reason(dut):
    first = dut.move_gripper_async(0.0)
    dut.advance(0.2)
    second = dut.move_gripper_async(0.03)
    assert first.done() and first.status == "cancelled"  # at once, no waiting
    t = dut.time
    outcome = first.result()
    assert dut.time == t  # returned without advancing
    assert outcome.code is ErrorCode.PREEMPTED and "superseded" in outcome.message
    assert 0.02 < outcome.finger_position < FINGER_OPEN and outcome.end_time == t
    final = second.result()
    assert final.success and final.finger_position == pytest.approx(0.03, abs=2e-3)


def test_an_arm_action_never_judged_is_stopped_at_its_deadline(dut):
    plan = dut.planner.plan_to_pose(X_TARGET).trajectory
    handle = dut.execute_async(plan)
    assert handle.deadline >= plan.duration + dut.options.settle_timeout
    context = dut._context(dut._commander)  # the arm's command now starts 100 s later
    command = dut._commander.arm(context)
    dut._commander.set_arm(context, type(command)(command.q_hold, plan, command.t0 + 100.0))
    outcome = handle.result()
    assert handle.status == "failed" and outcome.code is ErrorCode.TIMED_OUT
    assert handle.deadline - 0.011 <= outcome.end_time <= handle.deadline
    assert dut._commander.arm(context).stop_at == pytest.approx(outcome.end_time)  # stopped
    dut.advance(0.5)
    np.testing.assert_allclose(dut.read_state()[9:], 0.0, atol=1e-9)
    assert dut.move_to_pose(X_TARGET).success  # and the arm works again


def test_close_ends_actions_and_planning_then_every_call_raises(dut):
    finished = dut.plan_async(dut.planner.plan_to_pose, X_TARGET)
    arm = dut.execute_async(finished.result(timeout=60.0))
    fingers = dut.move_gripper_async(0.0)
    dut.advance(0.1)
    started, release, ran = threading.Event(), threading.Event(), []

    def running(*args, **kwargs):
        started.set()
        return release.wait(60.0)

    first = dut.plan_async(running)
    assert started.wait(60.0)
    queued = dut.plan_async(lambda **kwargs: ran.append(kwargs))

    def release_once_queued_is_cancelled():  # close() waits for the running request
        for _ in range(60000):
            if queued.done():
                break
            time.sleep(0.001)
        release.set()

    threading.Thread(target=release_once_queued_is_cancelled, daemon=True).start()
    dut.close()
    for handle in (arm, fingers):
        outcome = handle.result()
        assert handle.status == "cancelled" and outcome.code is ErrorCode.PREEMPTED
        assert "the interface was closed" in outcome.message
    for handle in (first, queued):
        with pytest.raises(PlanningError, match="the interface was closed") as error:
            handle.result(timeout=60.0)
        assert error.value.code is ErrorCode.PREEMPTED
    assert ran == []  # the queued request never ran
    assert finished.result().success  # one over before closing keeps its result
    calls = [
        lambda: dut.execute_async(arm.plan),
        lambda: dut.move_to_pose(X_TARGET),
        lambda: dut.plan_async(dut.planner.plan_to_named, "ready"),
        dut.close_gripper,
        lambda: dut.advance(0.1),
    ]
    for call in calls:
        with pytest.raises(RuntimeError, match="^the interface is closed$"):
            call()
    dut.close()  # closing again does nothing


def test_planning_station_is_a_context_manager(config):
    with make_planning_station(config, mode="kinematic") as mpi:
        assert mpi.close_gripper().success
    with pytest.raises(RuntimeError, match="closed"):
        mpi.open_gripper()
