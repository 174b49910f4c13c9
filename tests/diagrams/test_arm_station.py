"""Tests of the arm station diagram in both modes, in simulated time: the Panda, and arms from a
description YAML (the xArm 7 of example-robot-data, a two-joint arm with a finger)."""

import dataclasses as dc

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.multibody.inverse_kinematics import InverseKinematics
from pydrake.solvers import Solve
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

import diagrams.arm_station as mut
from diagrams.pickplace_scenario import load_pickplace_scenario
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from planning.model.model_config import RobotModelConfig
from planning.model.planning_model import build_planning_model, named_configurations
from planning.scene_objects import free_body_pose, free_body_positions
from tests.robot_helpers import XARM7_YAML, make_elbow_robot

SCENE = config_dir() / "pickplace.yaml"


@pytest.fixture(scope="module")
def config():
    return load_pickplace_scenario().station_config()


@pytest.fixture(scope="module")
def model(config):
    return build_planning_model(config.model)


def _ik(model, p_WG, q_seed):
    """Arm q (9 values, fingers kept from q_seed) putting the TCP at p_WG, pointing down."""
    plant = model.plant
    tcp = plant.GetFrameByName(model.ee_frame)
    ik = InverseKinematics(plant, with_joint_limits=True)
    q = ik.q()
    p_WG = np.asarray(p_WG)
    ik.AddPositionConstraint(tcp, np.zeros(3), plant.world_frame(), p_WG - 1e-4, p_WG + 1e-4)
    R_WG = RotationMatrix(RollPitchYaw(np.pi, 0.0, 0.0))  # z down, fingers closing along y
    ik.AddOrientationConstraint(tcp, RotationMatrix(), plant.world_frame(), R_WG, 1e-3)
    prog = ik.prog()
    prog.AddBoundingBoxConstraint(q_seed[7:], q_seed[7:], q[7:])
    prog.AddQuadraticErrorCost(np.eye(9), q_seed, q)
    prog.SetInitialGuess(q, q_seed)
    result = Solve(prog)
    assert result.is_success()
    return result.GetSolution(q)


@pytest.mark.parametrize("mode", mut.MODES)
def test_builds_with_documented_ports(config, mode):
    dut = mut.make_arm_station_diagram(config, mode=mode)
    for name in ("panda.position_command",):
        assert dut.HasInputPort(name)
    for name in ("panda.state", "object.pose", "query_object"):
        assert dut.HasOutputPort(name)
    assert dut.GetOutputPort("panda.state").size() == 18
    if mode == "physics":
        for name in ("body_poses", "contact_results", "state"):
            assert dut.HasOutputPort(name)
    else:
        assert dut.GetInputPort("object.position_command").size() == 7


def test_bad_mode_and_values(config):
    with pytest.raises(ConfigError):
        mut.make_arm_station_diagram(config, mode="hardware")
    bad = mut.ArmStationConfig(initial_q=[0.0] * 7, scene=config.scene)
    with pytest.raises(ConfigError):
        mut.make_arm_station_diagram(bad)


def test_unknown_station_key_rejected(tmp_path):
    scenario = tmp_path / "scenario.yaml"
    scenario.write_text(f"scene_file: {SCENE}\nstation: {{finger_force_limt: 70.0}}\n")
    with pytest.raises(ConfigError, match="station.finger_force_limt"):
        load_pickplace_scenario(scenario)


def test_free_body_positions_round_trip():
    X_WB = RigidTransform(RollPitchYaw(0.1, -0.2, 0.3), [0.4, -0.5, 0.6])
    X = free_body_pose(free_body_positions(X_WB))
    assert X.IsNearlyEqualTo(X_WB, 1e-12)


def test_physics_holds_ready_under_gravity(config):
    dut = mut.make_arm_station_diagram(config, mode="physics")
    context = dut.CreateDefaultContext()
    q_ready = np.asarray(config.initial_q)
    dut.GetInputPort("panda.position_command").FixValue(context, q_ready)
    Simulator(dut, context).AdvanceTo(1.0)
    q = dut.GetOutputPort("panda.state").Eval(context)[:9]
    assert np.max(np.abs(q[:7] - q_ready[:7])) < 1e-3


def test_kinematic_plant_positions_equal_command(config, model):
    dut = mut.make_arm_station_diagram(config, mode="kinematic")
    context = dut.CreateDefaultContext()
    q = np.array([0.3, 0.6, -0.2, -0.9, 0.1, 1.5, 0.7, 0.02, 0.03])
    X_WO = RigidTransform(RollPitchYaw(0.0, 0.0, 0.5), [0.3, 0.2, 0.3])
    dut.GetInputPort("panda.position_command").FixValue(context, q)
    dut.GetInputPort("object.position_command").FixValue(context, free_body_positions(X_WO))
    Simulator(dut, context).AdvanceTo(0.05)
    np.testing.assert_allclose(dut.GetOutputPort("panda.state").Eval(context)[:9], q)
    assert dut.GetOutputPort("object.pose").Eval(context).IsNearlyEqualTo(X_WO, 1e-12)
    # The geometry the SceneGraph holds is where the plant puts it at q.
    plant = model.plant
    plant_context = plant.CreateDefaultContext()
    plant.SetPositions(plant_context, q)
    query = dut.GetOutputPort("query_object").Eval(context)
    inspector = query.inspector()
    frames = {inspector.GetName(f): f for f in inspector.GetAllFrameIds()}
    for name in ("panda_hand", "panda_leftfinger", "panda_rightfinger", "panda_link4"):
        X_WB = plant.EvalBodyPoseInWorld(plant_context, plant.GetBodyByName(name))
        assert query.GetPoseInWorld(frames[f"panda::{name}"]).IsNearlyEqualTo(X_WB, 1e-9)
    assert query.GetPoseInWorld(frames["object::object"]).IsNearlyEqualTo(X_WO, 1e-9)


def test_physics_grasp_lift_and_hold(config, model):
    """Joint-space interpolation: above the object, descend, close, lift 0.1 m, hold 1 s."""
    box = config.scene.object
    p_WO = np.asarray(box.position)
    p_grasp = p_WO + [0.0, 0.0, box.size[2] / 2 - 0.03]  # fingertips 3 cm below the top
    q_start = np.asarray(config.initial_q)
    q_above = _ik(model, p_grasp + [0.0, 0.0, 0.12], q_start)
    q_grasp = _ik(model, p_grasp, q_above)
    q_lift = _ik(model, p_grasp + [0.0, 0.0, 0.1], q_grasp)

    def closed(q):
        return np.r_[q[:7], 0.0, 0.0]  # the force limit stops the fingers on the object

    times = [0.0, 2.0, 3.0, 3.5, 4.0, 5.0, 6.0]
    knots = [q_start, q_above, q_grasp, q_grasp, closed(q_grasp), closed(q_lift), closed(q_lift)]
    trajectory = PiecewisePolynomial.FirstOrderHold(times, np.array(knots).T)

    builder = DiagramBuilder()
    dut = builder.AddSystem(mut.make_arm_station_diagram(config, mode="physics"))
    source = builder.AddSystem(TrajectorySource(trajectory))
    builder.Connect(source.get_output_port(), dut.GetInputPort("panda.position_command"))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = dut.GetMyContextFromRoot(simulator.get_mutable_context())
    pose = dut.GetOutputPort("object.pose")
    z_start = pose.Eval(context).translation()[2]
    simulator.AdvanceTo(5.0)
    z_lifted = pose.Eval(context).translation()[2]
    fingers = dut.GetOutputPort("panda.state").Eval(context)[7:9]
    simulator.AdvanceTo(6.0)
    z_held = pose.Eval(context).translation()[2]
    assert z_lifted - z_start > 0.08
    assert abs(z_held - z_lifted) < 2e-3
    # The fingers rest on the object's faces, not inside it.
    np.testing.assert_allclose(fingers, box.size[1] / 2, atol=1e-3)


@pytest.mark.parametrize("mode", mut.MODES)
def test_draws_in_meshcat(config, mode):
    from pydrake.geometry import Meshcat

    meshcat = Meshcat()
    dut = mut.make_arm_station_diagram(config, meshcat=meshcat, mode=mode)
    context = dut.CreateDefaultContext()
    dut.GetInputPort("panda.position_command").FixValue(context, np.asarray(config.initial_q))
    if mode == "kinematic":
        q_object = mut.default_object_positions(config)
        dut.GetInputPort("object.position_command").FixValue(context, q_object)
    Simulator(dut, context).AdvanceTo(0.01)
    assert meshcat.HasPath("/drake")


@pytest.fixture(scope="module")
def xarm_config(config, tmp_path_factory):
    """The station of the Panda's scene with the xArm 7 (no finger joints) at its home."""
    arm = tmp_path_factory.mktemp("xarm") / "xarm7.yaml"
    arm.write_text(XARM7_YAML)
    model = RobotModelConfig(description=str(arm))
    return mut.ArmStationConfig(model=model, scene=config.scene)


def test_another_arm_has_ports_named_after_it_and_sized_by_its_group(xarm_config):
    layout = mut.station_layout(xarm_config)
    assert (layout.robot, layout.num_joints, layout.num_fingers) == ("UF_ROBOT", 7, 0)
    dut = mut.make_arm_station_diagram(xarm_config, mode="kinematic")
    assert dut.GetInputPort("UF_ROBOT.position_command").size() == 7
    assert dut.GetOutputPort("UF_ROBOT.state").size() == 14
    assert not dut.HasInputPort("panda.position_command")
    # Its start is the model's home (no initial_q given).
    home = named_configurations(xarm_config.model)["home"]
    np.testing.assert_array_equal(mut.initial_positions(xarm_config), home)
    context = dut.CreateDefaultContext()
    q = home + 0.1
    dut.GetInputPort("UF_ROBOT.position_command").FixValue(context, q)
    dut.GetInputPort("object.position_command").FixValue(
        context, mut.default_object_positions(xarm_config)
    )
    Simulator(dut, context).AdvanceTo(0.05)
    np.testing.assert_allclose(dut.GetOutputPort("UF_ROBOT.state").Eval(context)[:7], q)


def test_another_arm_holds_its_pose_in_physics(xarm_config):
    """The xArm's 7 joints take the station's 7 default gains; gravity compensation holds it."""
    dut = mut.make_arm_station_diagram(xarm_config, mode="physics")
    context = dut.CreateDefaultContext()
    home = mut.initial_positions(xarm_config)
    dut.GetInputPort("UF_ROBOT.position_command").FixValue(context, home)
    Simulator(dut, context).AdvanceTo(0.5)
    q = dut.GetOutputPort("UF_ROBOT.state").Eval(context)[:7]
    assert np.max(np.abs(q - home)) < 2e-3


def test_physics_refuses_gains_of_another_size_and_unheld_joints(xarm_config, tmp_path):
    short = dc.replace(xarm_config, arm_kp=[100.0] * 6)
    with pytest.raises(ConfigError, match=r"station.arm_kp needs 7 values.*joint1"):
        mut.make_arm_station_diagram(short, mode="physics")
    mut.make_arm_station_diagram(short, mode="kinematic")  # gains are not used there
    # The elbow arm's block slides on the arm, not below its attach link (the tool): a joint
    # outside the group and the fingers, held at its default in the kinematic station only.
    description = make_elbow_robot(tmp_path, 1.0, finger=True)
    scene = dc.replace(xarm_config.scene, object=None, obstacle=None)
    elbow = mut.ArmStationConfig(model=RobotModelConfig(description=str(description)), scene=scene)
    assert mut.station_layout(elbow).others == ("slide",)
    with pytest.raises(ConfigError, match=r"elbow has moving joints .*\(slide\).*kinematic"):
        mut.make_arm_station_diagram(elbow, mode="physics")
    dut = mut.make_arm_station_diagram(elbow, mode="kinematic")
    assert dut.GetInputPort("elbow.position_command").size() == 2
