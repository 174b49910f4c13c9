"""The robot in its world (diagrams.ddrive_world, diagrams.ddrive_model)."""

import dataclasses as dc

import numpy as np
import pytest
from pydrake.math import RollPitchYaw
from pydrake.systems.analysis import Simulator

import diagrams.ddrive_world as mut
from diagrams.flip_scenario import load_flip_scenario
from drake_sim.base.resources import config_dir
from drake_sim.robots.ddrive import default_robot_file
from drake_sim.robots.ddrive_params import load_robot_params


@pytest.fixture(scope="module")
def robot():
    return load_robot_params(default_robot_file())


@pytest.fixture(scope="module")
def scenario():
    return load_flip_scenario(config_dir() / "view.yaml").scene


def _rest(diagram, seconds):
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    diagram.GetInputPort("ddrive.actuation").FixValue(context, np.zeros(2))
    simulator.AdvanceTo(seconds)
    plant = diagram.GetSubsystemByName("plant")
    plant_context = plant.GetMyContextFromRoot(context)
    body = plant.GetBodyByName("base_link")
    return plant, plant_context, plant.EvalBodyPoseInWorld(plant_context, body)


def test_robot_dropped_on_the_asphalt_rests_upright(scenario, robot):
    """Dropped from 5 cm, the robot settles level on its wheels and bottom caster."""
    start = dc.replace(scenario.robot_pose)
    dropped = dc.replace(scenario, robot_pose=start)
    diagram = mut.make_ddrive_world_diagram(dropped, robot)
    plant = diagram.GetSubsystemByName("plant")
    body = plant.GetBodyByName("base_link")
    X_WB0 = mut.robot_start_pose(start, robot)
    X_WB0.set_translation(X_WB0.translation() + [0, 0, 0.05])
    plant.SetDefaultFloatingBaseBodyPose(body, X_WB0)
    plant, plant_context, X_WB = _rest(diagram, 2.0)
    rpy = RollPitchYaw(X_WB.rotation())
    assert abs(rpy.roll_angle()) < 0.02 and abs(rpy.pitch_angle()) < 0.02
    assert X_WB.rotation().matrix()[2, 2] > 0.999  # upright, not upside down
    assert X_WB.translation()[2] == pytest.approx(robot.wheel.radius, abs=3e-3)
    np.testing.assert_allclose(X_WB.translation()[:2], [start.x, start.y], atol=0.02)
    caster = plant.EvalBodyPoseInWorld(plant_context, plant.GetBodyByName("bottom_caster"))
    assert caster.translation()[2] == pytest.approx(robot.caster.radius, abs=3e-3)
    assert np.linalg.norm(plant.GetVelocities(plant_context)) < 0.05


def test_bare_ground_and_exported_ports(scenario, robot):
    bare = dc.replace(scenario, world="")
    diagram = mut.make_ddrive_world_diagram(bare, robot)
    for name in ("ddrive.state", "body_poses", "contact_results"):
        assert diagram.HasOutputPort(name)
    assert diagram.get_input_port(0).get_name() == "ddrive.actuation"
    plant, _, X_WB = _rest(diagram, 0.5)
    assert X_WB.translation()[2] == pytest.approx(robot.wheel.radius, abs=3e-3)
