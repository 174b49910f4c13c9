"""Assembles the diff-drive robot and its world into a Drake Diagram (the launch file's job)."""

import dataclasses as dc
import logging
import math

from pydrake.geometry import AddContactMaterial, HalfSpace, Meshcat, ProximityProperties, SceneGraph
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import AddMultibodyPlant, CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.visualization import AddFrameTriadIllustration, ApplyVisualizationConfig

from diagrams.world_scenario import GroundConfig, PlanarPose, WorldScenario
from drake_sim.base.resources import make_parser
from drake_sim.robots.ddrive import BODY_LINK, add_robot
from drake_sim.robots.ddrive_params import RobotParams

ROBOT_NAME = "ddrive"
"""The robot's model instance name; exported ports are named ``ddrive.<signal>``."""


@dc.dataclass
class DdriveWorld:
    """Handles to what ``add_ddrive_world`` added to a builder."""

    plant: MultibodyPlant
    scene_graph: SceneGraph
    robot: ModelInstanceIndex


def robot_start_pose(pose: PlanarPose, robot: RobotParams) -> RigidTransform:
    """X_WB of the robot standing on its wheels and bottom caster at ``pose`` (or on its top
    caster, turned over about its x axis, if ``pose.upside_down``).

    The body is lifted 1 mm so the first contact step does not start in penetration.
    """
    roll = math.pi if pose.upside_down else 0.0
    p_WB = [pose.x, pose.y, robot.wheel.radius + 1e-3]
    return RigidTransform(RollPitchYaw(roll, 0, pose.yaw), p_WB)


class _HalfSpaceWarningFilter(logging.Filter):
    """Drops Drake's warning that deformable bodies cannot touch a rigid half-space: there are
    no deformable bodies here, and it would print on every context created."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "half spaces are not currently supported for deformable" not in record.getMessage()


def _quiet_half_space_warning() -> None:
    logger = logging.getLogger("drake")
    if not any(isinstance(f, _HalfSpaceWarningFilter) for f in logger.filters):
        logger.addFilter(_HalfSpaceWarningFilter())


def add_ground(plant: MultibodyPlant, ground: GroundConfig) -> None:
    """Registers the ground, a half-space whose surface is z = 0, on the plant's world body.

    World files draw the street but leave its collision to this function: a half-space is only
    safe on the world body itself (see ``models/asphalt_ground/model.sdf``).
    """
    props = ProximityProperties()
    friction = CoulombFriction(ground.mu_static, ground.mu_dynamic)
    AddContactMaterial(friction=friction, properties=props)
    plant.RegisterCollisionGeometry(
        plant.world_body(), RigidTransform(), HalfSpace(), "ground", props
    )
    _quiet_half_space_warning()


def add_ddrive_world(
    builder: DiagramBuilder, scenario: WorldScenario, robot: RobotParams
) -> DdriveWorld:
    """Adds the plant, the ground, the world from ``scenario.world`` and the robot to
    ``builder``.

    The plant is finalised, and the robot's default pose is its start pose, so a default
    context starts the robot standing on the ground at ``scenario.robot_pose``.
    """
    plant, scene_graph = AddMultibodyPlant(scenario.plant, builder)
    add_ground(plant, scenario.ground)
    if scenario.world:
        parser = make_parser(plant)
        if "://" in scenario.world:
            parser.AddModels(url=scenario.world)
        else:
            parser.AddModels(file_name=scenario.world)
    instance = add_robot(plant, robot, name=ROBOT_NAME)
    plant.Finalize()
    body = plant.GetBodyByName(BODY_LINK, instance)
    plant.SetDefaultFloatingBaseBodyPose(body, robot_start_pose(scenario.robot_pose, robot))
    add_link_frames(plant, scene_graph, instance, scenario.frame_triad_length)
    return DdriveWorld(plant=plant, scene_graph=scene_graph, robot=instance)


def add_link_frames(plant, scene_graph, instance, length: float) -> None:
    """Draws a frame triad of ``length`` m on every link of the robot but its casters (RViz's
    TF display); nothing when ``length`` is 0."""
    if length <= 0:
        return
    for index in plant.GetBodyIndices(instance):
        link = plant.get_body(index)
        if not link.name().endswith("caster"):
            AddFrameTriadIllustration(
                scene_graph=scene_graph, body=link, length=length, radius=length / 40
            )


def make_ddrive_world_diagram(
    scenario: WorldScenario, robot: RobotParams, *, meshcat: Meshcat | None = None
) -> Diagram:
    """Builds the robot in its world.

    Exported ports:
        ddrive.actuation (input): wheel torques [left, right], N m.
        ddrive.state (output): the robot's positions and velocities.
        body_poses (output): poses of every body in the plant.
        contact_results (output): the plant's contact results.

    Args:
        scenario: the world, the robot's start pose and the plant/visualisation configs.
        robot: the robot's dimensions.
        meshcat: where to draw, or None for no visualisation.
    """
    builder = DiagramBuilder()
    world = add_ddrive_world(builder, scenario, robot)
    plant = world.plant
    builder.ExportInput(plant.get_actuation_input_port(world.robot), f"{ROBOT_NAME}.actuation")
    builder.ExportOutput(plant.get_state_output_port(world.robot), f"{ROBOT_NAME}.state")
    builder.ExportOutput(plant.get_body_poses_output_port(), "body_poses")
    builder.ExportOutput(plant.get_contact_results_output_port(), "contact_results")
    if meshcat is not None:
        ApplyVisualizationConfig(scenario.visualization, builder, meshcat=meshcat)
    diagram = builder.Build()
    diagram.set_name("ddrive_world")
    return diagram
