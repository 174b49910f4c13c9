"""ArmCommand and GripperCommand (what the arm and fingers follow in simulated time), and the
ArmCommander and ObjectFollower LeafSystems, each in a small diagram or context of its own."""

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

import planning.execution.commander as mut
from planning import Plan, PlanningScene
from planning.model.panda import ATTACHMENT_BODY
from planning.scene_objects import free_body_pose

V_MAX = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])
A_MAX = np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])
READY = np.array([0.0, -0.785398, 0.0, -2.356194, 0.0, 1.570796, 0.785398])
EXTENDED = np.array([0.0, 0.6, 0.0, -0.9, 0.0, 1.5, 0.785398])
T0 = 2.0  # s, simulated time at which the plan starts


@pytest.fixture(scope="module")
def plan():
    return Plan([READY, EXTENDED], V_MAX, A_MAX)


# ------------------------------------------------------------------------------ ArmCommand ----
def test_without_a_plan_the_arm_holds_still():
    dut = mut.ArmCommand(q_hold=READY, t0=1.0)
    for t in (0.0, 1.0, 5.0):
        np.testing.assert_array_equal(dut.sample(t), READY)
    assert dut.end_time() == 1.0
    assert dut.stopped(3.0, A_MAX) is dut


def test_plan_is_followed_from_t0(plan):
    dut = mut.ArmCommand(q_hold=EXTENDED, plan=plan, t0=T0)
    assert dut.end_time() == pytest.approx(T0 + plan.duration)
    for s in np.linspace(0.0, plan.duration, 7):
        assert dut.plan_time(T0 + s) == pytest.approx(s, abs=1e-12)
        np.testing.assert_allclose(dut.sample(T0 + s), plan.sample(s)[0], atol=1e-12)
    np.testing.assert_allclose(dut.sample(0.0), READY)  # before t0: at the start
    np.testing.assert_allclose(dut.sample(T0 + plan.duration + 1.0), EXTENDED)


def test_stop_slows_down_along_the_path_and_comes_to_rest(plan):
    running = mut.ArmCommand(q_hold=EXTENDED, plan=plan, t0=T0)
    t_stop = T0 + 0.4 * plan.duration
    dut = running.stopped(t_stop, A_MAX)
    assert dut.stop_at == t_stop and dut.stop_duration >= 0.05
    assert dut.end_time() == pytest.approx(t_stop + dut.stop_duration)
    # Path time: unchanged up to the stop, then its rate falls linearly from 1 to 0.
    ts = np.linspace(t_stop, dut.end_time(), 201)
    tau = np.array([dut.plan_time(t) for t in ts])
    assert dut.plan_time(t_stop - 0.1) == pytest.approx(running.plan_time(t_stop - 0.1))
    assert tau[0] == pytest.approx(t_stop - T0)
    rate = np.gradient(tau, ts)[1:-1]  # central differences
    np.testing.assert_allclose(rate, np.linspace(1.0, 0.0, len(ts))[1:-1], atol=1e-9)
    assert tau[-1] == pytest.approx(t_stop - T0 + 0.5 * dut.stop_duration)
    assert dut.plan_time(dut.end_time() + 3.0) == pytest.approx(tau[-1])
    # The commanded joints stay on the plan (the collision-checked path) and end at rest.
    for t in ts[::20]:
        np.testing.assert_array_equal(dut.sample(t), plan.sample(dut.plan_time(t))[0])
    q_rest = dut.sample(dut.end_time())
    np.testing.assert_array_equal(dut.sample(dut.end_time() + 1.0), q_rest)
    assert np.max(np.abs(q_rest - EXTENDED)) > 0.05  # short of the goal
    # The braking term v / stop_duration stays under half of each joint's acceleration limit.
    v = plan.sample(t_stop - T0)[1]
    assert np.all(np.abs(v) / dut.stop_duration <= 0.5 * A_MAX + 1e-12)


def test_stop_at_rest_is_short_and_a_zero_duration_stop_freezes(plan):
    dut = mut.ArmCommand(q_hold=READY, plan=plan, t0=0.0)
    assert dut.stopped(0.0, A_MAX).stop_duration == pytest.approx(0.05)  # v = 0 at the start
    frozen = mut.ArmCommand(q_hold=READY, plan=plan, t0=0.0, stop_at=0.3)
    assert frozen.plan_time(0.2) == pytest.approx(0.2)
    assert frozen.plan_time(0.3) == frozen.plan_time(9.0) == pytest.approx(0.3)


def test_stop_after_the_end_marks_the_command_stopped_where_it_rests(plan):
    running = mut.ArmCommand(q_hold=EXTENDED, plan=plan, t0=T0)
    t = T0 + plan.duration + 0.5
    dut = running.stopped(t, A_MAX)
    assert dut.stop_at == t and dut.end_time() == t
    np.testing.assert_allclose(dut.sample(t + 1.0), EXTENDED)
    assert dut.stopped(t + 1.0, A_MAX) is dut  # already stopped


# -------------------------------------------------------------------------- GripperCommand ----
@pytest.mark.parametrize("start,target", [(0.04, 0.0), (0.01, 0.035)])
def test_gripper_moves_at_its_speed_between_start_and_target(start, target):
    dut = mut.GripperCommand(start, target, t0=1.0, speed=0.05)
    assert dut.end_time() == pytest.approx(1.0 + abs(target - start) / 0.05)
    assert dut.sample(0.0) == pytest.approx(start)
    assert dut.sample(1.0) == pytest.approx(start)
    assert dut.sample(1.2) == pytest.approx(start + np.sign(target - start) * 0.01)
    assert dut.sample(dut.end_time()) == pytest.approx(target)
    assert dut.sample(dut.end_time() + 5.0) == pytest.approx(target)
    hold = mut.GripperCommand(0.02, 0.02, t0=3.0)
    assert hold.end_time() == 3.0 and hold.sample(10.0) == 0.02


# -------------------------------------------------------------------------- ArmCommander ----
@pytest.fixture
def commander():
    """An ArmCommander alone in a diagram, simulated from t = 0."""
    builder = DiagramBuilder()
    q_arm = READY.copy()
    dut = builder.AddSystem(mut.ArmCommander(q_arm=q_arm, finger=0.04, num_fingers=2))
    q_arm[0] = 1.0  # the commander keeps its own copy
    simulator = Simulator(builder.Build())
    simulator.Initialize()
    return dut, simulator


def command(dut, simulator):
    context = dut.GetMyContextFromRoot(simulator.get_context())
    return dut.get_output_port().Eval(context)


def test_commander_holds_its_initial_configuration(commander):
    dut, simulator = commander
    assert dut.get_output_port().get_name() == "position_command"
    assert dut.get_output_port().size() == 9 and dut.num_input_ports() == 0
    np.testing.assert_array_equal(command(dut, simulator), [*READY, 0.04, 0.04])
    simulator.AdvanceTo(1.0)
    np.testing.assert_array_equal(command(dut, simulator), [*READY, 0.04, 0.04])


def test_commander_plays_the_commands_set_in_its_state(commander, plan):
    dut, simulator = commander
    simulator.AdvanceTo(T0)
    context = dut.GetMyMutableContextFromRoot(simulator.get_mutable_context())
    arm = mut.ArmCommand(q_hold=EXTENDED, plan=plan, t0=T0)
    gripper = mut.GripperCommand(0.04, 0.0, t0=T0, speed=0.05)
    dut.set_arm(context, arm)
    dut.set_gripper(context, gripper)
    assert dut.arm(context) is arm and dut.gripper(context) is gripper
    for t in (T0 + 0.1, T0 + 0.5 * plan.duration, T0 + plan.duration + 1.0):
        simulator.AdvanceTo(t)
        values = command(dut, simulator)
        np.testing.assert_allclose(values[:7], arm.sample(t), atol=1e-12)
        np.testing.assert_allclose(values[7:], gripper.sample(t), atol=1e-12)
    np.testing.assert_allclose(command(dut, simulator), [*EXTENDED, 0.0, 0.0], atol=1e-9)


def test_commander_output_is_a_function_of_state_and_time(plan):
    """Two contexts with the same state and time give the same command."""
    dut = mut.ArmCommander(q_arm=READY, finger=0.04, num_fingers=2)
    contexts = [dut.CreateDefaultContext() for _ in range(2)]
    for context in contexts:
        dut.set_arm(context, mut.ArmCommand(q_hold=EXTENDED, plan=plan, t0=0.0))
        context.SetTime(0.3)
    a, b = (dut.get_output_port().Eval(c) for c in contexts)
    np.testing.assert_array_equal(a, b)
    contexts[1].SetTime(0.6)
    assert not np.array_equal(dut.get_output_port().Eval(contexts[1]), a)


# -------------------------------------------------------------------------- ObjectFollower ----
@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


def panda_state(scene, q_arm):
    return np.concatenate([scene.full_q(q_arm), np.zeros(9)])


def follower_pose(dut, context) -> RigidTransform:
    return free_body_pose(dut.get_output_port().Eval(context))


def test_follower_carries_the_object_between_grab_and_release(scene):
    plant = scene.plant
    X_WO = RigidTransform(RollPitchYaw(0.0, 0.0, 0.4), [0.31, 0.0, 0.38])
    dut = mut.ObjectFollower(
        plant=plant,
        body=plant.GetBodyByName(ATTACHMENT_BODY),
        X_WO=X_WO,
        indices=np.arange(9),
        q_rest=scene.full_q(READY),
    )
    assert dut.get_input_port().get_name() == "robot_state" and dut.get_input_port().size() == 18
    assert dut.get_output_port().get_name() == "object_positions"
    context = dut.CreateDefaultContext()
    arm_at = lambda q: dut.get_input_port().FixValue(context, panda_state(scene, q))  # noqa: E731
    arm_at(READY)
    # Resting: the object stays put whatever the arm does.
    assert follower_pose(dut, context).IsNearlyEqualTo(X_WO, 1e-12)
    arm_at(EXTENDED)
    assert follower_pose(dut, context).IsNearlyEqualTo(X_WO, 1e-12)
    # Grabbed at READY: it keeps its pose relative to the attachment frame A.
    arm_at(READY)
    dut.grab(context)
    assert follower_pose(dut, context).IsNearlyEqualTo(X_WO, 1e-12)
    X_AO = scene.attachment_pose(READY).inverse() @ X_WO
    arm_at(EXTENDED)
    X_carried = follower_pose(dut, context)
    assert X_carried.IsNearlyEqualTo(scene.attachment_pose(EXTENDED) @ X_AO, 1e-9)
    assert np.linalg.norm(X_carried.translation() - X_WO.translation()) > 0.2
    assert dut.pose(context).IsNearlyEqualTo(X_carried, 1e-12)
    # Released at EXTENDED: it stays there when the arm goes back.
    dut.release(context)
    arm_at(READY)
    assert follower_pose(dut, context).IsNearlyEqualTo(X_carried, 1e-9)


def test_follower_attachment_pose_matches_the_scene(scene):
    plant = scene.plant
    body = plant.GetBodyByName(ATTACHMENT_BODY)
    dut = mut.ObjectFollower(
        plant=plant, body=body, X_WO=RigidTransform(), indices=np.arange(9), q_rest=np.zeros(9)
    )
    for q in (READY, EXTENDED):
        assert dut.X_WA(scene.full_q(q)).IsNearlyEqualTo(scene.attachment_pose(q), 1e-12)
