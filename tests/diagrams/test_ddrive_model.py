"""diagrams.ddrive_model: the robot alone in a continuous plant, its body welded at its standing
pose, its wheels free to pose by hand; frame triads, Meshcat visualisers and joint sliders on
request."""

import numpy as np
import pytest
from pydrake.geometry import Meshcat, Role
from pydrake.math import RigidTransform

import diagrams.ddrive_model as mut
from diagrams.ddrive_world import robot_start_pose
from diagrams.world_scenario import PlanarPose
from drake_sim.robots.ddrive import BODY_LINK, LEFT_WHEEL_JOINT, RIGHT_WHEEL_JOINT
from tests.flip_helpers import default_robot


@pytest.fixture(scope="module")
def robot():
    return default_robot()


@pytest.fixture(scope="module")
def meshcat():
    return Meshcat()


def _illustrations(diagram) -> int:
    inspector = diagram.GetSubsystemByName("scene_graph").model_inspector()
    return inspector.NumGeometriesWithRole(Role.kIllustration)


def test_continuous_plant_welded_at_the_standing_pose(robot):
    dut = mut.make_ddrive_model_diagram(robot)
    assert dut.get_name() == "ddrive_model"
    assert dut.num_input_ports() == 0 and dut.num_output_ports() == 0
    plant = dut.GetSubsystemByName("plant")
    assert plant.time_step() == 0.0
    assert plant.num_positions() == 2 and plant.num_velocities() == 2  # the wheels only
    context = plant.CreateDefaultContext()
    X_WB = plant.EvalBodyPoseInWorld(context, plant.GetBodyByName(BODY_LINK))
    expected = robot_start_pose(PlanarPose(), robot)
    assert X_WB.IsNearlyEqualTo(expected, 1e-12)


def test_wheels_can_be_posed_by_hand(robot):
    dut = mut.make_ddrive_model_diagram(robot)
    plant = dut.GetSubsystemByName("plant")
    context = plant.CreateDefaultContext()
    body = plant.GetBodyByName(BODY_LINK)
    X_WB0 = plant.EvalBodyPoseInWorld(context, body)
    left = plant.GetJointByName(LEFT_WHEEL_JOINT)
    wheel = left.child_body()
    X_WL0 = plant.EvalBodyPoseInWorld(context, wheel)
    left.set_angle(context, 1.0)
    plant.GetJointByName(RIGHT_WHEEL_JOINT).set_angle(context, -0.5)
    np.testing.assert_allclose(plant.GetPositions(context), [1.0, -0.5])
    assert plant.EvalBodyPoseInWorld(context, body).IsNearlyEqualTo(X_WB0, 1e-12)  # welded
    X_WL = plant.EvalBodyPoseInWorld(context, wheel)
    np.testing.assert_allclose(X_WL.translation(), X_WL0.translation(), atol=1e-12)  # spins
    X_LL = X_WL0.InvertAndCompose(X_WL)
    assert X_LL.rotation().ToAngleAxis().angle() == pytest.approx(1.0)
    assert not X_LL.IsNearlyEqualTo(RigidTransform(), 1e-3)


def test_frame_triads_on_each_link_but_the_casters(robot):
    with_triads = mut.make_ddrive_model_diagram(robot, frame_triad_length=0.15)
    without = mut.make_ddrive_model_diagram(robot, frame_triad_length=0.0)
    plant = without.GetSubsystemByName("plant")
    links = [
        plant.get_body(i).name()
        for i in plant.GetBodyIndices(plant.GetModelInstanceByName("ddrive"))
    ]
    triads = [name for name in links if not name.endswith("caster")]
    assert BODY_LINK in triads and len(triads) < len(links)
    assert _illustrations(with_triads) - _illustrations(without) == 3 * len(triads)


def test_meshcat_visualisers_and_joint_sliders(robot, meshcat):
    dut = mut.make_ddrive_model_diagram(robot, meshcat=meshcat, joint_sliders=True)
    names = {system.get_name() for system in dut.GetSystems()}
    assert {"meshcat_visualizer(visualizer)", "meshcat_visualizer(collision)"} <= names
    assert dut.HasSubsystemNamed("joint_sliders")
    plain = mut.make_ddrive_model_diagram(robot, meshcat=meshcat)
    assert not plain.HasSubsystemNamed("joint_sliders")


def test_joint_sliders_need_meshcat(robot):
    with pytest.raises(ValueError, match="joint_sliders needs a Meshcat"):
        mut.make_ddrive_model_diagram(robot, joint_sliders=True)
