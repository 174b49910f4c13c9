"""RobotState: forward and inverse kinematics, named configurations, reading a diagram."""

from types import SimpleNamespace

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

import planning as mut
import planning.search.ik as ik_module
from planning import ErrorCode, PlanningError

N_POSES = 100


@pytest.fixture(scope="module")
def scene():
    return mut.PlanningScene()


@pytest.fixture
def dut(scene):
    return mut.RobotState(scene)


def random_reachable_poses(scene, dut, count, seed):
    """Collision-free random configurations and their end-effector poses."""
    rng = np.random.default_rng(seed)
    lower = scene.plant.GetPositionLowerLimits()[:7]
    upper = scene.plant.GetPositionUpperLimits()[:7]
    samples = []
    while len(samples) < count:
        q = rng.uniform(lower, upper)
        if scene.is_collision_free(q):
            samples.append((q, dut.fk(q)))
    return samples


def test_fk_at_ready_matches_the_franka_ready_pose(dut):
    """Franka's "ready" pose puts the flange at (0.307, 0, 0.590) m pointing down, and the
    TCP 0.1034 m further down."""
    X_WE = dut.fk(dut.named("ready"))
    np.testing.assert_allclose(X_WE.translation(), [0.30689, 0.0, 0.48688], atol=1e-4)
    np.testing.assert_allclose(X_WE.rotation().col(2), [0, 0, -1], atol=1e-5)
    np.testing.assert_allclose(
        dut.fk(frame="panda_link8").translation(), [0.30689, 0, 0.59028], atol=1e-4
    )
    np.testing.assert_allclose(
        dut.fk(np.zeros(7)).translation(), [0.088, 0, 0.8226], atol=1e-4
    )  # 0.926 - 0.1034
    assert dut.hand_pose().IsExactlyEqualTo(dut.fk())


def test_current_q_and_named(dut):
    np.testing.assert_allclose(dut.q, dut.named("ready"))
    dut.set_q(dut.named("extended"))
    np.testing.assert_allclose(dut.q, dut.named("extended"))
    assert dut.q_full.shape == (9,)
    with pytest.raises(PlanningError) as info:
        dut.named("dance")
    assert info.value.code == ErrorCode.INVALID_GOAL and "ready" in info.value.message
    with pytest.raises(PlanningError, match="frame"):
        dut.fk(frame="panda_link99")
    with pytest.raises(ValueError, match="7"):
        dut.set_q([0.0, 1.0])
    with pytest.raises(ValueError, match="finite"):
        dut.set_q([np.nan] * 7)


@pytest.mark.parametrize("mode", ["pose", "position", "orientation"])
def test_ik_round_trips_fk(scene, dut, mode):
    options = mut.IkOptions(time_budget=1.0, max_restarts=10, seed=3)
    solved, times = 0, []
    for _q, X_WE in random_reachable_poses(scene, dut, N_POSES, seed=7):
        kwargs = {
            "pose": {"X_WE": X_WE},
            "position": {"p_WE": X_WE.translation()},
            "orientation": {"R_WE": X_WE.rotation()},
        }[mode]
        try:
            result = dut.ik(**kwargs, options=options)
        except PlanningError as e:
            assert e.code == ErrorCode.NO_IK_SOLUTION
            continue
        solved += 1
        times.append(result.solve_time)
        X = dut.fk(result.q)
        if mode != "orientation":
            assert np.max(np.abs(X.translation() - X_WE.translation())) < 1.1e-3
        if mode != "position":
            angle = (X.rotation().inverse() @ X_WE.rotation()).ToAngleAxis().angle()
            assert angle < 0.0101
        assert scene.is_collision_free(result.q)
    print(f"IK {mode}: {solved}/{N_POSES} solved, median {np.median(times) * 1e3:.1f} ms")
    assert solved >= 0.95 * N_POSES


def test_ik_is_deterministic_and_seeded(scene, monkeypatch):
    """Same target and seed, same answer; the solver is made once per RobotState."""
    made = []

    def solver(*args):
        made.append(ik_module.IkSolver(*args))
        return made[-1]

    monkeypatch.setattr(mut.robot_state, "IkSolver", solver)
    dut = mut.RobotState(scene)
    X_WE = dut.fk(dut.named("extended"))
    a = dut.ik(X_WE, q_seed=dut.named("transport"))
    b = dut.ik(X_WE, q_seed=dut.named("transport"))
    np.testing.assert_array_equal(a.q, b.q)
    assert a.attempts >= 1 and a.solve_time > 0
    assert len(made) == 1
    np.testing.assert_allclose(dut.q, dut.named("ready"))  # ik does not move the state


def test_ik_without_target_solves_the_current_pose(dut):
    result = dut.ik()
    assert dut.fk(result.q).translation() == pytest.approx(dut.fk().translation(), abs=1.1e-3)


class SolveSpy:
    """Counts the nonlinear programs IK solves (wraps ``planning.search.ik.Solve``)."""

    def __init__(self, monkeypatch):
        self.calls = 0
        self._solve = ik_module.Solve
        monkeypatch.setattr(ik_module, "Solve", self)

    def __call__(self, prog):
        self.calls += 1
        return self._solve(prog)


class FakeClock:
    """``time.perf_counter`` for the IK module: each reading is ``step`` s after the last."""

    def __init__(self, monkeypatch, step):
        self.now, self.step = 0.0, step
        monkeypatch.setattr(ik_module, "time", SimpleNamespace(perf_counter=self))

    def __call__(self):
        self.now += self.step
        return self.now


def test_pose_beyond_reach_is_rejected_before_any_solve(dut, monkeypatch):
    solves = SolveSpy(monkeypatch)
    with pytest.raises(PlanningError) as info:
        dut.ik(RigidTransform([1.5, 0.0, 0.3]))
    assert info.value.code == ErrorCode.NO_IK_SOLUTION
    assert "reach" in info.value.message
    assert solves.calls == 0


# Within the reach bound but unreachable in that orientation (hand z up, at the workspace's edge).
X_UNREACHABLE = RigidTransform(RotationMatrix(), [0.0, 0.0, 1.3])


def test_failing_ik_makes_every_restart_within_the_budget(dut, monkeypatch):
    solves = SolveSpy(monkeypatch)
    with pytest.raises(PlanningError) as info:
        dut.ik(X_UNREACHABLE, options=mut.IkOptions(max_restarts=3, time_budget=1e6))
    assert info.value.code == ErrorCode.NO_IK_SOLUTION
    assert "after 4 attempts" in info.value.message
    assert solves.calls == 4  # the seeded attempt and 3 restarts


def test_time_budget_stops_the_restarts(dut, monkeypatch):
    """On a clock where every reading is 1 s later, a 0.5 s budget allows the first attempt."""
    solves = SolveSpy(monkeypatch)
    FakeClock(monkeypatch, step=1.0)
    with pytest.raises(PlanningError) as info:
        dut.ik(X_UNREACHABLE, options=mut.IkOptions(max_restarts=20, time_budget=0.5))
    assert info.value.code == ErrorCode.NO_IK_SOLUTION
    assert "after 1 attempts" in info.value.message
    assert solves.calls == 1


def test_ik_rejects_bad_targets(dut):
    with pytest.raises(PlanningError) as info:
        dut.ik(p_WE=[np.nan, 0, 0.5])
    assert info.value.code == ErrorCode.INVALID_GOAL
    with pytest.raises(PlanningError):
        dut.ik(p_WE=[0.4, 0.0])
    with pytest.raises(PlanningError) as info:
        dut.ik(p_WE=[0.4, 0, 0.4], frame="no_frame")
    assert info.value.code == ErrorCode.FRAME_NOT_FOUND


def test_ik_avoids_obstacles(scene, dut):
    """A target inside a box has no collision-free solution; IK says what collides."""
    p = np.array([0.5, 0.0, 0.3])
    scene.add_box("ik_block", [0.2, 0.2, 0.2], RigidTransform(p))
    try:
        with pytest.raises(PlanningError) as info:
            dut.ik(p_WE=p, options=mut.IkOptions(time_budget=0.5, max_restarts=3))
        assert info.value.code == ErrorCode.NO_IK_SOLUTION
    finally:
        scene.remove_object("ik_block")
    assert dut.ik(p_WE=p).q.shape == (7,)


def test_reader_reports_the_latest_joints_from_a_diagram(dut):
    q = np.concatenate([dut.named("extended"), [0.02, 0.02]])
    builder = DiagramBuilder()
    source = builder.AddSystem(ConstantVectorSource(np.concatenate([q, np.zeros(9)])))
    reader = builder.AddSystem(dut.make_reader(input_size=18))
    assert isinstance(reader, mut.RobotStateReader)
    builder.Connect(source.get_output_port(), reader.get_input_port())
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    reader_context = reader.GetMyContextFromRoot(context)
    np.testing.assert_allclose(reader.GetOutputPort("q").Eval(reader_context), q)
    X_WE_port = reader.GetOutputPort("X_WE").Eval(reader_context)
    assert X_WE_port.IsNearlyEqualTo(dut.fk(q), 1e-12)
    q_read, X_WE = dut.read(context)
    np.testing.assert_allclose(q_read, q[:7])
    np.testing.assert_allclose(dut.q_full, q)
    assert X_WE.IsNearlyEqualTo(dut.fk(q), 1e-12)


def test_read_plant_context(scene, dut):
    plant = scene.plant
    context = plant.CreateDefaultContext()
    q = np.concatenate([dut.named("transport"), [0.01, 0.01]])
    plant.SetPositions(context, q)
    q_read, X_WE = dut.read_plant_context(plant, context, scene.model.instance)
    np.testing.assert_allclose(q_read, q[:7])
    assert X_WE.IsNearlyEqualTo(dut.fk(q), 1e-12)


def test_reader_needs_the_panda_positions(scene):
    frame = scene.plant.GetFrameByName("panda_hand_tcp")
    with pytest.raises(ValueError, match="at least 9 values"):
        mut.RobotStateReader(plant=scene.plant, frame=frame, input_size=8)


def test_reader_of_another_robot_takes_its_plant_positions(tmp_path):
    """The reader is sized by the scene's plant, not the Panda's 9 positions: the two-joint
    elbow arm's station state is 2 positions and 2 velocities."""
    from tests.robot_helpers import elbow_scene

    scene = elbow_scene(tmp_path, 1.5)
    state = mut.RobotState(scene)
    q = np.array([0.4, -0.3])
    builder = DiagramBuilder()
    source = builder.AddSystem(ConstantVectorSource(np.concatenate([q, np.zeros(2)])))
    reader = builder.AddSystem(state.make_reader())
    builder.Connect(source.get_output_port(), reader.get_input_port())
    context = builder.Build().CreateDefaultContext()
    q_read, X_WE = state.read(context)
    np.testing.assert_allclose(q_read, q)
    assert X_WE.IsNearlyEqualTo(state.fk(q), 1e-12)
    plant_context = scene.plant.CreateDefaultContext()
    scene.plant.SetPositions(plant_context, -q)
    q_read, _ = state.read_plant_context(scene.plant, plant_context)  # found by its name
    np.testing.assert_allclose(q_read, -q)
    with pytest.raises(ValueError, match="at least 2 values"):
        mut.RobotStateReader(plant=scene.plant, frame=scene.plant.world_frame(), input_size=1)
