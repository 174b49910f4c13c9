"""The arm station: a robot of any description, the table, the object and the obstacle, in two
modes.

The robot is the one the ``model`` names (``RobotModelConfig``: the Panda by default, or any
description, ``planning.model.description``), welded at the world origin, with a massless
``<robot>_attachment`` body on its attach link as the planner has. Its ports carry the planning
group's joints and then its fingers (``planning.model.arm_layout``: the Panda's 7 + 2, the
UR5's 6 + 0), named after the robot (``panda.position_command``, ``ur5_robotiq85.state``).

``physics`` (the real robot's role): a discrete MultibodyPlant (SAP) with contact. Every group
and finger joint has a JointActuator with Drake's implicit PD controller (gains and effort limits
from the config: one per group joint, and one for all fingers), which SAP solves together with
contact, so stiff gains stay stable at a 1 ms step. The desired state comes from the position
command through a ``StateInterpolatorWithDiscreteDerivative`` (commanded velocities are the
command's finite difference); the feed-forward actuation is gravity compensation
(``InverseDynamics`` in gravity-compensation mode on the same plant, mapped to the actuators by
Bᵀ). Actuator effort limits clamp PD plus feed-forward, so the fingers are position-controlled
with a force limit, like the Franka hand, and hold the object by friction. A robot with moving
joints outside its group and fingers (a head) has no physics station (nothing would hold them).

``kinematic`` (MoveIt's fake hardware): nothing is simulated. ``MultibodyPositionToGeometryPose``
writes the commanded positions (the other joints at their defaults, and the object's commanded
pose) into its own context of the plant and sends the geometry poses to the SceneGraph;
``<robot>.state`` is the command and its finite-difference velocity.

Settings are an ``ArmStationConfig``, the ``station`` section of the pick-and-place scenario
(``diagrams.pickplace_scenario``), which also fills in its robot model, scene and start.
"""

import numpy as np
from pydrake.geometry import MeshcatVisualizer, MeshcatVisualizerParams, Rgba, SceneGraph
from pydrake.math import RigidTransform
from pydrake.multibody.plant import (
    AddMultibodyPlant,
    CoulombFriction,
    MultibodyPlant,
)
from pydrake.multibody.tree import PdControllerGains, SpatialInertia
from pydrake.systems.controllers import InverseDynamics
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import (
    ConstantVectorSource,
    MatrixGain,
    Multiplexer,
    StateInterpolatorWithDiscreteDerivative,
)
from pydrake.visualization import ApplyVisualizationConfig

from diagrams.arm_station_config import (  # noqa: F401 (the station's API, re-exported)
    MODES,
    ArmStationConfig,
    initial_positions,
    station_layout,
    validate_station_config,
)
from diagrams.scene_boxes import add_scene_box, box_pose
from drake_sim.base.errors import ConfigError
from planning.execution.free_body_pose import FreeBodyPose
from planning.model.arm_layout import ArmLayout
from planning.model.planning_model import (
    apply_disabled_collisions,
    attachment_body_name,
    robot_model,
    touch_links,
)
from planning.scene_objects import FREE_BODY_POSITIONS, free_body_positions

OBJECT = "object"
"""The object's model instance and body name; its ports are ``object.<signal>``."""


def _friction(pair: list[float]) -> CoulombFriction:
    return CoulombFriction(pair[0], pair[1])


def _add_actuators(plant: MultibodyPlant, instance, layout: ArmLayout, config) -> None:
    """One PD-controlled JointActuator per group joint, then per finger."""
    gains = list(zip(config.arm_kp, config.arm_kd, config.arm_effort_limits, strict=True))
    gains += [(config.finger_kp, config.finger_kd, config.finger_force_limit)] * layout.num_fingers
    for name, (kp, kd, limit) in zip(layout.joint_names, gains, strict=True):
        joint = plant.GetJointByName(name, instance)
        actuator = plant.AddJointActuator(name, joint, limit)
        actuator.set_controller_gains(PdControllerGains(p=kp, d=kd))


def _add_world(plant: MultibodyPlant, config: ArmStationConfig, layout, *, physics: bool):
    """Adds the robot, the table, the obstacle and the object; finalizes; sets defaults.

    Returns:
        (robot instance, object body or None).
    """
    scene = config.scene
    robot = robot_model(config.model)
    instance = robot.add_to(plant)
    attachment = plant.AddRigidBody(
        attachment_body_name(robot.name), instance, SpatialInertia.Zero()
    )
    link = plant.GetFrameByName(robot.attach_link, instance)
    plant.WeldFrames(link, attachment.body_frame(), RigidTransform())
    if physics:
        _add_actuators(plant, instance, layout, config)
    stiff = {"point_stiffness": config.point_stiffness}
    if scene.table is not None:
        color = Rgba(0.55, 0.4, 0.25, 1.0)
        friction = _friction(config.table_friction)
        add_scene_box(
            plant, "table", scene.table, friction=friction, color=color, free=False, **stiff
        )
    if scene.obstacle is not None:
        color = Rgba(0.7, 0.2, 0.2, 1.0)
        friction = _friction(config.obstacle_friction)
        add_scene_box(
            plant, "obstacle", scene.obstacle, friction=friction, color=color, free=False, **stiff
        )
    body = None
    if scene.object is not None:
        mu = config.object_friction
        if scene.object.friction > 0.0:
            mu = [scene.object.friction, scene.object.friction]
        color = Rgba(0.1, 0.4, 0.9, 1.0)
        body = add_scene_box(
            plant, OBJECT, scene.object, friction=_friction(mu), color=color, free=True, **stiff
        )
    plant.Finalize()
    q = plant.GetDefaultPositions()  # all of the plant's (the object's too), by joint
    q[layout.plant_indices(plant, instance)] = initial_positions(config)
    q[layout.plant_indices(plant, instance, layout.others)] = layout.other_positions
    plant.SetDefaultPositions(q)
    return instance, body


def _disabled_pairs(config: ArmStationConfig) -> list[tuple[str, str]]:
    """The SRDF's disabled pairs, and held objects against the touch links (the fingers)."""
    robot = robot_model(config.model)
    attachment = attachment_body_name(robot.name)
    return list(robot.disabled_pairs) + [(attachment, b) for b in touch_links(robot)]


def _set_finger_friction(plant, scene_graph: SceneGraph, instance, layout, config) -> None:
    """Gives the fingers' collision geometry the configured friction and stiffness (URDFs set
    neither)."""
    from pydrake.geometry import ProximityProperties, RoleAssign

    inspector = scene_graph.model_inspector()
    friction = _friction(config.finger_friction)
    for name in layout.fingers:
        body = plant.GetJointByName(name, instance).child_body()
        for geometry in plant.GetCollisionGeometriesForBody(body):
            props = ProximityProperties(inspector.GetProximityProperties(geometry))
            if props.HasProperty("material", "coulomb_friction"):
                props.UpdateProperty("material", "coulomb_friction", friction)
            else:
                props.AddProperty("material", "coulomb_friction", friction)
            stiffness = ("material", "point_contact_stiffness")
            if props.HasProperty(*stiffness):
                props.UpdateProperty(*stiffness, config.point_stiffness)
            else:
                props.AddProperty(*stiffness, config.point_stiffness)
            scene_graph.AssignRole(plant.get_source_id(), geometry, props, RoleAssign.kReplace)


def make_arm_station_diagram(
    config: ArmStationConfig, *, meshcat=None, mode: str = "physics"
) -> Diagram:
    """Builds the arm station.

    Exported ports (both modes), ``<robot>`` the robot's name (``station_layout(config).robot``,
    the Panda's "panda"):
        <robot>.position_command (input): the group's joints (rad or m) then the fingers (m
            each; the Panda's: 0 closed, 0.04 open).
        <robot>.state (output): those positions then their velocities; physics: the plant's;
            kinematic: the command and its finite difference.
        object.pose (output, when the scene has an object): X_WO, an abstract RigidTransform of
            the object's centre frame O in the world frame W.
        query_object (output): the SceneGraph's QueryObject.
    Physics mode only:
        body_poses (output): the plant's body poses; contact_results (output): its
        ContactResults; state (output): the plant's full state.
    Kinematic mode only (when the scene has an object):
        object.position_command (input): the object's 7 positions [qw, qx, qy, qz, x, y, z]
            (``free_body_positions(X_WO)``); it must be connected or fixed.

    The plant is the subsystem named "plant" in physics mode; in kinematic mode it is not in
    the diagram (``MultibodyPositionToGeometryPose`` holds it).

    Args:
        config: the station (``PickPlaceScenario.station_config()``).
        meshcat: where to draw (illustration geometry), or None.
        mode: "physics" or "kinematic".

    Raises:
        ConfigError: an unknown mode, bad config values, or a robot the mode cannot simulate.
    """
    if mode not in MODES:
        raise ConfigError(f"mode {mode!r} is not one of {MODES}")
    validate_station_config(config, mode)
    layout = station_layout(config)
    if mode == "physics":
        diagram = _make_physics(config, layout, meshcat)
    else:
        diagram = _make_kinematic(config, layout, meshcat)
    diagram.set_name(f"{layout.robot}_station_{mode}")
    return diagram


def _make_physics(config: ArmStationConfig, layout: ArmLayout, meshcat) -> Diagram:
    if config.plant.time_step <= 0.0:
        raise ConfigError("physics mode needs a discrete plant: plant.time_step > 0")
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(config.plant, builder)
    robot, body = _add_world(plant, config, layout, physics=True)
    apply_disabled_collisions(plant, scene_graph, robot, _disabled_pairs(config))
    _set_finger_friction(plant, scene_graph, robot, layout, config)

    interpolator = builder.AddSystem(
        StateInterpolatorWithDiscreteDerivative(
            layout.num_positions, config.plant.time_step, suppress_initial_transient=True
        )
    )
    interpolator.set_name("command_interpolator")
    builder.ExportInput(interpolator.get_input_port(), layout.port("position_command"))
    builder.Connect(interpolator.get_output_port(), plant.get_desired_state_input_port(robot))

    gravity = builder.AddSystem(InverseDynamics(plant, InverseDynamics.kGravityCompensation))
    gravity.set_name("gravity_compensation")
    to_actuation = builder.AddSystem(MatrixGain(plant.MakeActuationMatrix().T))
    to_actuation.set_name("generalized_force_to_actuation")
    builder.Connect(plant.get_state_output_port(), gravity.get_input_port_estimated_state())
    builder.Connect(gravity.get_output_port_generalized_force(), to_actuation.get_input_port())
    builder.Connect(to_actuation.get_output_port(), plant.get_actuation_input_port(robot))

    # The robot's state in the layout's order, whatever order the plant keeps its joints in.
    joints = [plant.GetJointByName(name, robot) for name in layout.joint_names]
    rows = [j.position_start() for j in joints]
    rows += [plant.num_positions() + j.velocity_start() for j in joints]
    select = np.zeros((len(rows), plant.num_multibody_states()))
    select[np.arange(len(rows)), rows] = 1.0
    to_state = builder.AddSystem(MatrixGain(select))
    to_state.set_name("robot_state")
    builder.Connect(plant.get_state_output_port(), to_state.get_input_port())
    builder.ExportOutput(to_state.get_output_port(), layout.port("state"))
    if body is not None:
        pose = builder.AddSystem(FreeBodyPose(input_size=13))
        pose.set_name("object_pose")
        builder.Connect(plant.get_state_output_port(body.model_instance()), pose.get_input_port())
        builder.ExportOutput(pose.get_output_port(), f"{OBJECT}.pose")
    builder.ExportOutput(scene_graph.get_query_output_port(), "query_object")
    builder.ExportOutput(plant.get_body_poses_output_port(), "body_poses")
    builder.ExportOutput(plant.get_contact_results_output_port(), "contact_results")
    builder.ExportOutput(plant.get_state_output_port(), "state")
    if meshcat is not None:
        ApplyVisualizationConfig(config.visualization, builder, meshcat=meshcat)
    return builder.Build()


def _make_kinematic(config: ArmStationConfig, layout: ArmLayout, meshcat) -> Diagram:
    from pydrake.systems.rendering import MultibodyPositionToGeometryPose

    builder = DiagramBuilder()
    scene_graph = builder.AddSystem(SceneGraph())
    scene_graph.set_name("scene_graph")
    plant = MultibodyPlant(0.0)
    plant.set_name("plant")
    plant.RegisterAsSourceForSceneGraph(scene_graph)
    robot, body = _add_world(plant, config, layout, physics=False)
    apply_disabled_collisions(plant, scene_graph, robot, _disabled_pairs(config))

    # The plant's q from [command; other joints; object q (7)], whatever order the plant keeps.
    columns = list(layout.plant_indices(plant, robot))
    columns += list(layout.plant_indices(plant, robot, layout.others))
    if body is not None:
        start = body.floating_positions_start()
        columns += list(range(start, start + FREE_BODY_POSITIONS))
    if len(columns) != plant.num_positions():
        raise ConfigError(f"kinematic station: expected {len(columns)} plant positions")
    P = np.zeros((plant.num_positions(), len(columns)))
    P[columns, np.arange(len(columns))] = 1.0
    to_q = builder.AddSystem(MatrixGain(P))
    to_q.set_name("positions_to_plant_q")
    to_pose = builder.AddSystem(MultibodyPositionToGeometryPose(plant))
    to_pose.set_name("plant_positions_to_geometry_pose")
    builder.Connect(to_q.get_output_port(), to_pose.get_input_port())
    builder.Connect(
        to_pose.get_output_port(), scene_graph.get_source_pose_port(plant.get_source_id())
    )

    sizes = [layout.num_positions]
    if layout.others:
        sizes.append(len(layout.others))
    if body is not None:
        sizes.append(FREE_BODY_POSITIONS)
    mux = builder.AddSystem(Multiplexer(sizes))
    builder.Connect(mux.get_output_port(), to_q.get_input_port())
    if layout.others:
        others = builder.AddSystem(ConstantVectorSource(np.asarray(layout.other_positions)))
        others.set_name("other_joints")
        builder.Connect(others.get_output_port(), mux.get_input_port(1))
    interpolator = builder.AddSystem(
        StateInterpolatorWithDiscreteDerivative(
            layout.num_positions, config.plant.time_step or 0.001, suppress_initial_transient=True
        )
    )
    interpolator.set_name("command_interpolator")
    command = layout.port("position_command")
    builder.ExportInput(mux.get_input_port(0), command)
    builder.ConnectInput(command, interpolator.get_input_port())
    builder.ExportOutput(interpolator.get_output_port(), layout.port("state"))
    if body is not None:
        pose = builder.AddSystem(FreeBodyPose(input_size=FREE_BODY_POSITIONS))
        pose.set_name("object_pose")
        object_command = f"{OBJECT}.position_command"
        builder.ExportInput(mux.get_input_port(len(sizes) - 1), object_command)
        builder.ConnectInput(object_command, pose.get_input_port())
        builder.ExportOutput(pose.get_output_port(), f"{OBJECT}.pose")
    builder.ExportOutput(scene_graph.get_query_output_port(), "query_object")
    if meshcat is not None:
        params = MeshcatVisualizerParams(prefix="station")
        MeshcatVisualizer.AddToBuilder(builder, scene_graph, meshcat, params)
    return builder.Build()


def default_object_positions(config: ArmStationConfig) -> np.ndarray:
    """The object's 7 positions at its scene pose (for ``object.position_command``)."""
    if config.scene.object is None:
        raise ConfigError("the scene has no object")
    return free_body_positions(box_pose(config.scene.object))
