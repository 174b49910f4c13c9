"""The Panda station: the Panda with its hand, the table, the object and the obstacle, in two modes.

``physics`` (the real robot's role): a discrete MultibodyPlant (SAP) with contact. Every Panda
joint has a JointActuator with Drake's implicit PD controller (gains and effort limits from the
config), which SAP solves together with contact, so stiff gains stay stable at a 1 ms step. The
desired state comes from the position command through a ``StateInterpolatorWithDiscreteDerivative``
(commanded velocities are the command's finite difference); the feed-forward actuation is gravity
compensation (``InverseDynamics`` in gravity-compensation mode on the same plant, mapped to the
Panda's actuators by Bᵀ). Actuator effort limits clamp PD plus feed-forward, so the fingers are
position-controlled with a force limit, like the Franka hand, and hold the object by friction.

``kinematic`` (Franka's fake hardware): nothing is simulated. ``MultibodyPositionToGeometryPose``
writes the commanded positions (and the object's commanded pose) into its own context of the
plant and sends the geometry poses to the SceneGraph; ``panda.state`` is the command and its
finite-difference velocity.

Settings are a ``PandaStationConfig``, the ``station`` section of the pick-and-place scenario
(``diagrams.pickplace_scenario``), which also fills in its robot model, scene and start.
"""

import dataclasses as dc

import numpy as np
from pydrake.geometry import MeshcatVisualizer, MeshcatVisualizerParams, Rgba, SceneGraph
from pydrake.multibody.plant import (
    AddMultibodyPlant,
    CoulombFriction,
    MultibodyPlant,
    MultibodyPlantConfig,
)
from pydrake.multibody.tree import PdControllerGains
from pydrake.systems.controllers import InverseDynamics
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import (
    MatrixGain,
    Multiplexer,
    StateInterpolatorWithDiscreteDerivative,
)
from pydrake.visualization import ApplyVisualizationConfig, VisualizationConfig

from diagrams.scene_boxes import add_scene_box, box_pose
from drake_sim.base.errors import ConfigError
from planning.execution.free_body_pose import FreeBodyPose
from planning.io.scene_files import SceneFile
from planning.model.layout import (
    FINGER_OPEN,
    NUM_ARM_JOINTS,
    NUM_FINGERS,
    NUM_POSITIONS,
    READY_Q,
)
from planning.model.model_config import RobotModelConfig
from planning.model.panda import (
    ARM_JOINTS,
    FINGER_JOINTS,
    add_panda,
    disabled_collision_pairs,
)
from planning.model.planning_model import apply_disabled_collisions
from planning.scene_objects import FREE_BODY_POSITIONS, free_body_positions

PANDA = "panda"
"""The Panda's model instance name; its ports are ``panda.<signal>``."""
OBJECT = "object"
"""The object's model instance and body name; its ports are ``object.<signal>``."""
MODES = ("physics", "kinematic")


def _default_plant() -> MultibodyPlantConfig:
    return MultibodyPlantConfig(
        time_step=0.001,
        discrete_contact_approximation="sap",
        contact_model="point",
        sap_near_rigid_threshold=0.01,
    )


@dc.dataclass
class PandaStationConfig:
    """Everything the station needs: plant, gains, friction, viewer, and (filled in by the
    scenario) the robot model, the scene and the start.

    Gains are Drake implicit PD gains per joint actuator; effort limits clamp PD plus gravity
    compensation. Arm values are per joint 1..7; finger values are per finger.
    """

    plant: MultibodyPlantConfig = dc.field(default_factory=_default_plant)
    model: RobotModelConfig = dc.field(default_factory=RobotModelConfig)
    arm_kp: list[float] = dc.field(default_factory=lambda: [2000.0] * 4 + [500.0] * 3)  # N m/rad
    arm_kd: list[float] = dc.field(default_factory=lambda: [100.0] * 4 + [20.0] * 3)  # N m s/rad
    arm_effort_limits: list[float] = dc.field(  # N m, Franka's datasheet
        default_factory=lambda: [87.0] * 4 + [12.0] * 3
    )
    finger_kp: float = 10000.0  # N/m
    finger_kd: float = 100.0  # N s/m
    finger_force_limit: float = 70.0  # N, per finger (Franka hand: 70 N continuous)
    finger_friction: list[float] = dc.field(default_factory=lambda: [1.0, 1.0])  # static, dynamic
    object_friction: list[float] = dc.field(default_factory=lambda: [1.0, 1.0])  # unless the scene
    obstacle_friction: list[float] = dc.field(default_factory=lambda: [0.5, 0.5])
    table_friction: list[float] = dc.field(default_factory=lambda: [0.8, 0.6])
    # Point-contact stiffness of the fingers, the object, the table and the obstacle, N/m
    # (pairs combine in series); the plant's default lets 70 N sink a finger ~9 mm in.
    point_stiffness: float = 1.0e6
    # Initial Panda positions: the arm joints (rad) then the fingers (m). In a pick-and-place
    # scenario: its initial_configuration, fingers at robot.model.finger_position.
    initial_q: list[float] = dc.field(
        default_factory=lambda: [*READY_Q, *[FINGER_OPEN] * NUM_FINGERS]
    )
    visualization: VisualizationConfig = dc.field(
        default_factory=lambda: VisualizationConfig(
            publish_contacts=False, publish_proximity=False, publish_inertia=False
        )
    )
    # The scene (table, object, obstacle; place is ignored here). In a pick-and-place
    # scenario: its scene section.
    scene: SceneFile = dc.field(default_factory=SceneFile)


def validate_station_config(config: PandaStationConfig) -> None:
    """Raises ConfigError for values the builder cannot use."""
    if len(config.initial_q) != NUM_POSITIONS:
        raise ConfigError(f"initial_q has {len(config.initial_q)} values, expected {NUM_POSITIONS}")
    for name in ("arm_kp", "arm_kd", "arm_effort_limits"):
        if len(getattr(config, name)) != NUM_ARM_JOINTS:
            raise ConfigError(f"station.{name} needs {NUM_ARM_JOINTS} values (joints 1..7)")
    scene = config.scene
    for name in ("table", "object", "obstacle"):
        box = getattr(scene, name)
        if box is not None and (len(box.size) != 3 or len(box.position) != 3):
            raise ConfigError(f"scene {name}: size and position need 3 values each")
        if box is not None and min(box.size) <= 0.0:
            raise ConfigError(f"scene {name}: sizes must be positive")
    if scene.object is not None and scene.object.mass <= 0.0:
        raise ConfigError("scene object: mass must be positive (kg)")


def _friction(pair: list[float]) -> CoulombFriction:
    return CoulombFriction(pair[0], pair[1])


def _add_actuators(plant: MultibodyPlant, instance, config: PandaStationConfig) -> None:
    """One PD-controlled JointActuator per Panda joint, arm then fingers."""
    gains = list(zip(config.arm_kp, config.arm_kd, config.arm_effort_limits, strict=True))
    gains += [(config.finger_kp, config.finger_kd, config.finger_force_limit)] * 2
    for name, (kp, kd, limit) in zip((*ARM_JOINTS, *FINGER_JOINTS), gains, strict=True):
        joint = plant.GetJointByName(name, instance)
        actuator = plant.AddJointActuator(name, joint, limit)
        actuator.set_controller_gains(PdControllerGains(p=kp, d=kd))


def _add_world(plant: MultibodyPlant, config: PandaStationConfig, *, physics: bool):
    """Adds the Panda, the table, the obstacle and the object; finalizes; sets defaults.

    Returns:
        (panda instance, object body or None).
    """
    scene = config.scene
    model = dc.replace(config.model, extra_disabled_collisions=[])
    panda = add_panda(plant, model)
    if physics:
        _add_actuators(plant, panda, config)
    stiff = {"point_stiffness": config.point_stiffness}
    if scene.table is not None:
        # planning.model.panda.add_table passes an Rgba where Drake wants an array (a bug).
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
    plant.SetDefaultPositions(panda, np.asarray(config.initial_q, dtype=float))
    return panda, body


def _set_finger_friction(plant: MultibodyPlant, scene_graph: SceneGraph, instance, config) -> None:
    """Gives the fingers' collision geometry the configured friction and stiffness (the URDF
    sets neither)."""
    from pydrake.geometry import ProximityProperties, RoleAssign

    inspector = scene_graph.model_inspector()
    friction = _friction(config.finger_friction)
    for name in ("panda_leftfinger", "panda_rightfinger"):
        body = plant.GetBodyByName(name, instance)
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


def make_panda_station_diagram(
    config: PandaStationConfig, *, meshcat=None, mode: str = "physics"
) -> Diagram:
    """Builds the Panda station.

    Exported ports (both modes):
        panda.position_command (input): 9 positions, the 7 arm joints (rad) then the 2 fingers
            (m each, 0 closed, 0.04 open).
        panda.state (output): 18 values, the Panda's 9 positions then 9 velocities (rad, m,
            rad/s, m/s); physics: the plant's; kinematic: the command and its finite difference.
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
        ConfigError: an unknown mode or bad config values.
    """
    if mode not in MODES:
        raise ConfigError(f"mode {mode!r} is not one of {MODES}")
    validate_station_config(config)
    if mode == "physics":
        diagram = _make_physics(config, meshcat)
    else:
        diagram = _make_kinematic(config, meshcat)
    diagram.set_name(f"panda_station_{mode}")
    return diagram


def _make_physics(config: PandaStationConfig, meshcat) -> Diagram:
    if config.plant.time_step <= 0.0:
        raise ConfigError("physics mode needs a discrete plant: plant.time_step > 0")
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(config.plant, builder)
    panda, body = _add_world(plant, config, physics=True)
    apply_disabled_collisions(plant, scene_graph, panda, disabled_collision_pairs(config.model))
    _set_finger_friction(plant, scene_graph, panda, config)

    interpolator = builder.AddSystem(
        StateInterpolatorWithDiscreteDerivative(
            NUM_POSITIONS, config.plant.time_step, suppress_initial_transient=True
        )
    )
    interpolator.set_name("command_interpolator")
    builder.ExportInput(interpolator.get_input_port(), f"{PANDA}.position_command")
    builder.Connect(interpolator.get_output_port(), plant.get_desired_state_input_port(panda))

    gravity = builder.AddSystem(InverseDynamics(plant, InverseDynamics.kGravityCompensation))
    gravity.set_name("gravity_compensation")
    to_actuation = builder.AddSystem(MatrixGain(plant.MakeActuationMatrix().T))
    to_actuation.set_name("generalized_force_to_actuation")
    builder.Connect(plant.get_state_output_port(), gravity.get_input_port_estimated_state())
    builder.Connect(gravity.get_output_port_generalized_force(), to_actuation.get_input_port())
    builder.Connect(to_actuation.get_output_port(), plant.get_actuation_input_port(panda))

    builder.ExportOutput(plant.get_state_output_port(panda), f"{PANDA}.state")
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


def _make_kinematic(config: PandaStationConfig, meshcat) -> Diagram:
    from pydrake.systems.rendering import MultibodyPositionToGeometryPose

    builder = DiagramBuilder()
    scene_graph = builder.AddSystem(SceneGraph())
    scene_graph.set_name("scene_graph")
    plant = MultibodyPlant(0.0)
    plant.set_name("plant")
    plant.RegisterAsSourceForSceneGraph(scene_graph)
    panda, body = _add_world(plant, config, physics=False)
    apply_disabled_collisions(plant, scene_graph, panda, disabled_collision_pairs(config.model))

    # The plant's q from [panda q (9); object q (7)], whatever order the plant keeps them in.
    columns = [
        plant.GetJointByName(n, panda).position_start() for n in (*ARM_JOINTS, *FINGER_JOINTS)
    ]
    if body is not None:
        columns += list(range(body.floating_positions_start(), body.floating_positions_start() + 7))
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

    sizes = [NUM_POSITIONS] + ([FREE_BODY_POSITIONS] if body is not None else [])
    mux = builder.AddSystem(Multiplexer(sizes))
    builder.Connect(mux.get_output_port(), to_q.get_input_port())
    interpolator = builder.AddSystem(
        StateInterpolatorWithDiscreteDerivative(
            NUM_POSITIONS, config.plant.time_step or 0.001, suppress_initial_transient=True
        )
    )
    interpolator.set_name("command_interpolator")
    command = f"{PANDA}.position_command"
    builder.ExportInput(mux.get_input_port(0), command)
    builder.ConnectInput(command, interpolator.get_input_port())
    builder.ExportOutput(interpolator.get_output_port(), f"{PANDA}.state")
    if body is not None:
        pose = builder.AddSystem(FreeBodyPose(input_size=7))
        pose.set_name("object_pose")
        object_command = f"{OBJECT}.position_command"
        builder.ExportInput(mux.get_input_port(1), object_command)
        builder.ConnectInput(object_command, pose.get_input_port())
        builder.ExportOutput(pose.get_output_port(), f"{OBJECT}.pose")
    builder.ExportOutput(scene_graph.get_query_output_port(), "query_object")
    if meshcat is not None:
        params = MeshcatVisualizerParams(prefix="station")
        MeshcatVisualizer.AddToBuilder(builder, scene_graph, meshcat, params)
    return builder.Build()


def default_object_positions(config: PandaStationConfig) -> np.ndarray:
    """The object's 7 positions at its scene pose (for ``object.position_command``)."""
    if config.scene.object is None:
        raise ConfigError("the scene has no object")
    return free_body_positions(box_pose(config.scene.object))
