"""The check before motion: each violation is refused with a message naming it, the robot of a
kinematic station then has not moved and still executes a valid plan, and every arm motion of
the interface and of the pick-and-place task goes through the check."""

import json

import numpy as np
import pytest
from pydrake.math import RigidTransform

import planning.execution.gate as mut
import planning.interface
from diagrams.pickplace_scenario import load_pickplace_scenario
from diagrams.planning_station import make_planning_station
from planning import ErrorCode, Plan, PlanningError, PlanningScene
from planning.model.layout import FINGER_CLOSED, FINGER_OPEN, READY_Q
from planning.model.model_config import RobotModelConfig
from planning.model.planning_model import robot_model
from planning.planner_options import TimingOptions
from planning.task.pick_place import PickPlaceTask

# The Panda's datasheet limits (its description's joint_limits.yaml).
LIMITS = TimingOptions().with_robot_limits(robot_model(RobotModelConfig()))
V_MAX = np.array(LIMITS.max_velocity)
A_MAX = np.array(LIMITS.max_acceleration)
READY = np.array(READY_Q)
STEP = np.array([0.0, 0.2, 0.0, 0.0, 0.0, 0.0, 0.0])  # rad: the shoulder forward
OPEN = np.full(2, FINGER_OPEN)


@pytest.fixture
def mpi():
    """A kinematic pick-and-place station, its arm at rest at READY, the fingers open."""
    return make_planning_station(load_pickplace_scenario(), mode="kinematic")


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


def line(q_start, step=STEP, scale: float = 1.0, **kwargs) -> Plan:
    """A straight plan from q_start by step (rad), timed within scale times the Panda's limits."""
    q_start = np.asarray(q_start, dtype=float)
    return Plan([q_start, q_start + step], scale * V_MAX, scale * A_MAX, **kwargs)


def refuse(mpi, plan, code=ErrorCode.INVALID_MOTION_PLAN) -> str:
    """Executes ``plan`` expecting a refusal with ``code``; checks that the robot did not move
    and that a valid plan still executes; returns the refusal's message."""
    x0 = mpi.read_state()
    t0 = mpi.time
    with pytest.raises(PlanningError) as error:
        mpi.execute(plan)
    assert error.value.code is code
    assert mpi.time == t0  # refused before any simulation
    mpi.advance(0.2)
    np.testing.assert_array_equal(mpi.read_state(), x0)  # its state after equals before
    result = mpi.execute(line(x0[:7], -STEP))  # the station still works
    assert result.success, result.message
    np.testing.assert_allclose(mpi.read_state()[:7], x0[:7] - STEP, atol=1e-6)
    return error.value.message


def check(plan, scene, q=READY, fingers=OPEN):
    mut.check_before_motion(plan, scene, q, fingers, LIMITS, start_tolerance=0.02)


# -------------------------------------------------------------- the cases of the issue ----
def test_waypoint_beyond_a_joint_limit_is_refused(mpi):
    q = mpi.state.q
    beyond = q.copy()
    beyond[0] = 5.85
    message = refuse(mpi, Plan([q, beyond], V_MAX, A_MAX))
    assert "waypoint 1: panda_joint1 at 5.8500 rad is outside its limits" in message
    assert "[-2.8973, 2.8973] rad" in message


def test_limits_scaled_by_50_are_refused(mpi, tmp_path):
    plan = line(mpi.state.q)
    data = plan.to_dict()
    for key in ("max_velocity", "max_acceleration"):
        data[key] = [50.0 * v for v in data[key]]
    (tmp_path / "fast.json").write_text(json.dumps(data))
    fast = Plan.load(tmp_path / "fast.json")  # a valid file: the limits are the robot's to judge
    assert fast.duration < plan.duration / 7.0
    message = refuse(mpi, fast)
    assert "panda_joint1: the plan's max_velocity 108.7 rad/s" in message
    assert "above the robot's limit 2.175 rad/s" in message


def test_nan_limit_is_refused_and_the_station_stays_alive(mpi, tmp_path):
    plan = line(mpi.state.q)
    data = plan.to_dict()
    data["max_velocity"][2] = float("nan")
    (tmp_path / "nan.json").write_text(json.dumps(data))  # json writes NaN
    with pytest.raises(PlanningError, match=r"max_velocity\[2\] must be a finite number, got nan"):
        Plan.load(tmp_path / "nan.json")
    plan.max_velocity[2] = np.nan  # the same plan in memory, changed after it was timed
    assert "the plan's max_velocity[2] is nan, not finite" in refuse(mpi, plan)


def test_nan_duration_is_refused(mpi):
    class Endless(Plan):
        @property
        def duration(self) -> float:
            return float("nan")

    plan = Endless([mpi.state.q, mpi.state.q + STEP], V_MAX, A_MAX)
    assert "the plan's duration is nan s" in refuse(mpi, plan)


def test_closed_finger_plan_is_checked_with_the_open_fingers_measured(mpi):
    scene, q = mpi.scene, mpi.state.q
    np.testing.assert_allclose(mpi.read_state()[7:9], OPEN)
    # A small box where the open left fingertip will be (the closed fingers pass beside it).
    X_WF = scene.plant.EvalBodyPoseInWorld(
        scene.plant_context(np.concatenate([q + STEP, OPEN])),
        scene.plant.GetBodyByName("panda_leftfinger"),
    )
    scene.add_box("small_box", [0.012] * 3, RigidTransform(X_WF @ np.array([0.0, 0.0, 0.045])))
    scene.finger_positions = FINGER_CLOSED
    result = mpi.planner.plan_to_joints(q + STEP)  # planned with the fingers closed
    scene.finger_positions = FINGER_OPEN
    assert result.success, result.message
    plan = result.trajectory
    np.testing.assert_array_equal(plan.finger_positions, [FINGER_CLOSED] * 2)
    plan.validate(scene)  # free with the fingers it was planned with: the old check passed it
    message = refuse(mpi, plan)
    assert "with the fingers as measured (0.0400, 0.0400)" in message
    assert "panda_leftfinger <-> small_box" in message


def test_start_far_from_the_measured_joints_is_refused(mpi):
    q = mpi.state.q + [0.0, 0.0, 0.3, 0.0, 0.0, 0.0, 0.0]
    message = refuse(mpi, line(q), ErrorCode.INVALID_START)
    assert "the plan starts 0.300 rad from the robot's current joints" in message
    assert "panda_joint3" in message and "tolerance 0.02 rad" in message


def test_every_arm_motion_goes_through_the_check(mpi, monkeypatch):
    """The pick-and-place task's arm steps, and a plan replayed from a file: the commander only
    ever receives plans the check has passed, one check per plan."""
    checked, commanded = [], []
    gate = planning.interface.check_before_motion

    def spy_gate(plan, *args, **kwargs):
        gate(plan, *args, **kwargs)
        checked.append(plan)

    commander = mpi._commander
    set_arm = commander.set_arm

    def spy_set_arm(context, command):
        if command.stop_at is None:
            commanded.append(command.plan)
        set_arm(context, command)

    monkeypatch.setattr(planning.interface, "check_before_motion", spy_gate)
    monkeypatch.setattr(commander, "set_arm", spy_set_arm)
    report = PickPlaceTask(mpi).run()
    assert report.success, report.reason
    assert len(commanded) >= 5 and [id(p) for p in commanded] == [id(p) for p in checked]


# ---------------------------------------------------------------- the check on its own ----
def test_a_slower_plan_passes_and_nothing_changes_in_the_scene(scene):
    fingers, version = scene.finger_positions, scene.version
    check(line(READY, scale=0.5), scene)
    np.testing.assert_array_equal(scene.finger_positions, fingers)
    assert scene.version >= version


class Tampered(Plan):
    """A plan whose trajectory, in the middle fifth of its duration, is not the one its
    waypoints and limits give: joint 1 offset by ``q`` rad, velocities and accelerations scaled
    by ``v`` and ``a``."""

    offsets = (0.0, 1.0, 1.0)

    def sample(self, t):
        q, v, a = Plan.sample(self, t)
        if 0.4 * self.duration < t < 0.6 * self.duration:
            dq, kv, ka = self.offsets
            q = q + [dq, 0, 0, 0, 0, 0, 0]
            v, a = kv * v, ka * a
        return q, v, a


@pytest.mark.parametrize(
    "offsets,expected",
    [
        ((4.0, 1.0, 1.0), "panda_joint1 at 4.0000 rad is outside its limits"),
        ((0.0, 50.0, 1.0), "velocity"),
        ((0.0, 1.0, 50.0), "acceleration"),
        ((np.nan, 1.0, 1.0), "the position of panda_joint1 is nan"),
    ],
    ids=["position", "velocity", "acceleration", "nan"],
)
def test_the_sampled_trajectory_is_checked_not_only_the_waypoints(scene, offsets, expected):
    plan = Tampered([READY, READY + 4 * STEP], V_MAX, A_MAX)
    plan.offsets = offsets
    with pytest.raises(PlanningError) as error:
        check(plan, scene)
    assert error.value.code is ErrorCode.INVALID_MOTION_PLAN
    assert error.value.message.startswith("at t = ") and expected in error.value.message
    t = float(error.value.message.split()[3])
    assert 0.4 * plan.duration < t < 0.6 * plan.duration  # the time of the first violation


def test_the_first_violation_is_named(scene):
    plan = line(READY + [0.0, 0.0, 0.3, 0.0, 0.0, 0.0, 0.0], scale=60.0)  # too fast, and away
    with pytest.raises(PlanningError, match="max_velocity") as error:
        check(plan, scene)
    assert error.value.code is ErrorCode.INVALID_MOTION_PLAN
    plan = line(READY, scale=2.0)
    plan.max_acceleration[6] = A_MAX[6] * 2.0 + 1.0
    with pytest.raises(PlanningError, match="panda_joint1: the plan's max_velocity 4.35"):
        check(plan, scene)


@pytest.mark.parametrize(
    "change,expected",
    [
        (lambda p: p.robot.update(joints=["a"] * 7), "the plan is for panda group arm (a, a,"),
        (lambda p: setattr(p, "finger_positions", np.zeros(3)), "finger_positions has shape"),
        (lambda p: p.waypoints.__setitem__((1, 4), np.inf), "waypoints[1][4] is inf"),
    ],
    ids=["joints", "fingers", "waypoint"],
)
def test_plans_not_for_this_robot_are_refused(scene, change, expected):
    plan = line(READY)
    change(plan)
    with pytest.raises(PlanningError) as error:
        check(plan, scene)
    assert error.value.code is ErrorCode.INVALID_MOTION_PLAN and expected in error.value.message
    with pytest.raises(PlanningError, match="not a Plan: dict"):
        check(plan.to_dict(), scene)


def test_a_measured_state_that_is_not_finite_refuses_to_start(scene):
    with pytest.raises(PlanningError, match="measured state is not finite") as error:
        check(line(READY), scene, q=READY + [np.nan, 0, 0, 0, 0, 0, 0])
    assert error.value.code is ErrorCode.INVALID_START
