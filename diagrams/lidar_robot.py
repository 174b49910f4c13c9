"""The lidar robot in its arena, as both the mapping and the navigation diagrams need it: the
plant with the arena and the TurtleBot3 at its start, the diff-drive controller on ``cmd_vel``,
the encoder odometry, the true pose and the lidar.

``add_lidar_robot`` adds them to a builder; the caller connects ``cmd_vel`` and adds what uses
the scan (SLAM, or AMCL and the navigator).
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlant
from pydrake.systems.framework import DiagramBuilder, InputPort, OutputPort
from pydrake.systems.primitives import MatrixGain

from drake_sim.base.checks import fields_of, require_positive
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.mcap_files import McapLogWriter
from drake_sim.robots.turtlebot3 import (
    add_turtlebot3,
    drive_limits,
    frame_names,
    start_pose,
    wheel_signs,
    wheel_state_selector,
)
from drake_sim.robots.turtlebot3_params import Turtlebot3Params
from drake_sim.systems.control.diff_drive_controller import DiffDriveConfig, DiffDriveController
from drake_sim.systems.estimation.encoder_odometry import (
    EncoderOdometry,
    PlanarGroundTruth,
    check_config,
)
from drake_sim.systems.recording.ros_log import RosLogFrames, RosLogRecorder
from drake_sim.systems.sensors.lidar import add_lidar, check_lidar_config
from drake_sim.worlds.arena import Arena
from drake_sim.worlds.arena_world import add_arena

ROBOT_NAME = "turtlebot3"


@dc.dataclass
class LidarRobotParts:
    """What ``add_lidar_robot`` added: the plant and its scene graph, and the ports the rest of
    a diagram connects to."""

    plant: MultibodyPlant
    scene_graph: object
    cmd_vel: InputPort  # [v, omega] m/s, rad/s: the DiffDriveController's command.
    true_pose: OutputPort  # [x, y, yaw] of base_footprint (m, m, rad): the truth.
    odometry_pose: OutputPort  # [x, y, yaw] from the wheel encoders.
    odometry_twist: OutputPort  # [v, omega] from the wheel encoders.
    scan: OutputPort  # LaserScan.
    X_base_sensor: tuple[float, float, float]  # The lidar's planar pose on the base.
    frames: RosLogFrames  # The robot's base and lidar frame names, for a ROS log.


def check_lidar_robot_scenario(scenario, where: str) -> None:
    """Checks what a ``MappingScenario`` and a ``NavigationScenario`` share: the lidar, the
    odometry, a discrete plant, the drive rate, the log period and the seed.

    Raises:
        ConfigError: naming ``where`` and the first bad key.
    """
    check_lidar_config(scenario.lidar, f"{where}: lidar")
    check_config(scenario.odometry, where, prefix="odometry.")
    if not (math.isfinite(scenario.plant.time_step) and scenario.plant.time_step > 0):
        raise ConfigError(f"{where}: 'plant.time_step' must be > 0 (a discrete plant)")
    require_positive(where, fields_of(scenario, ("drive_rate", "log_period")))
    if scenario.random_seed < 0:
        raise ConfigError(f"{where}: 'random_seed' must be >= 0, got {scenario.random_seed}")


def add_lidar_robot(
    builder: DiagramBuilder, scenario, *, robot: Turtlebot3Params, world: Arena, start
) -> LidarRobotParts:
    """Adds the arena ``world`` and the robot standing at ``start`` (``[x, y, yaw]``, m, m, rad)
    with its controller (at ``scenario.drive_rate`` Hz, the robot's own limits), odometry
    (``scenario.odometry``, starting at ``start``), true pose and lidar (``scenario.lidar``), on
    a plant of ``scenario.plant``; noise and odometry errors are drawn from
    ``scenario.random_seed``. ``scenario`` is a ``MappingScenario`` or a ``NavigationScenario``.
    Systems are named ``plant``, ``scene_graph``, ``wheel_state``, ``diff_drive``,
    ``odometry``, ``true_pose`` and ``lidar``."""
    seed = scenario.random_seed
    plant, scene_graph = AddMultibodyPlant(scenario.plant, builder)
    add_arena(plant, world)
    instance = add_turtlebot3(plant, robot, name=ROBOT_NAME)
    plant.Finalize()
    names, signs = frame_names(robot), wheel_signs(robot)
    start = np.asarray(start, dtype=float)
    base = plant.GetFrameByName(names["base"], instance).body()
    plant.SetDefaultFloatingBaseBodyPose(base, start_pose(*start))

    selector = wheel_state_selector(plant, instance, (names["left"], names["right"]), signs)
    wheels = builder.AddNamedSystem("wheel_state", MatrixGain(selector))
    builder.Connect(plant.get_state_output_port(), wheels.get_input_port())
    drive = DiffDriveConfig(rate=scenario.drive_rate, **drive_limits(robot))
    controller = builder.AddNamedSystem(
        "diff_drive", DiffDriveController(robot=robot, config=drive, upside_down_aware=False)
    )
    builder.Connect(wheels.get_output_port(), controller.GetInputPort("wheel_state"))
    torques = controller.GetOutputPort("wheel_torques")
    if np.any(signs < 0):  # a wheel whose joint turns backwards when the robot drives forward
        flip = builder.AddNamedSystem("wheel_torque_signs", MatrixGain(np.diag(signs)))
        builder.Connect(torques, flip.get_input_port())
        torques = flip.get_output_port()
    builder.Connect(torques, plant.get_actuation_input_port(instance))
    encoder_odometry = builder.AddNamedSystem(
        "odometry",
        EncoderOdometry(
            wheel_radius=robot.wheel.radius,
            wheel_separation=robot.wheel_separation,
            config=scenario.odometry,
            initial_pose=start,
            seed=seed,
        ),
    )
    builder.Connect(wheels.get_output_port(), encoder_odometry.GetInputPort("wheel_state"))
    truth = builder.AddNamedSystem("true_pose", PlanarGroundTruth(plant=plant, body=base))
    builder.Connect(plant.get_body_poses_output_port(), truth.get_input_port())
    sensor = add_lidar(
        builder,
        plant,
        scene_graph,
        frame=plant.GetFrameByName(names["lidar"], instance),
        config=scenario.lidar,
        ignore=[instance],
        seed=seed,
    )
    return LidarRobotParts(
        plant=plant,
        scene_graph=scene_graph,
        cmd_vel=controller.GetInputPort("command"),
        true_pose=truth.get_output_port(),
        odometry_pose=encoder_odometry.GetOutputPort("pose"),
        odometry_twist=encoder_odometry.GetOutputPort("twist"),
        scan=sensor.GetOutputPort("scan"),
        X_base_sensor=(robot.lidar.x, robot.lidar.y, 0.0),
        frames=RosLogFrames(base=names["base"], laser=names["lidar"]),
    )


def add_ros_log(
    builder: DiagramBuilder,
    writer: McapLogWriter,
    scenario,
    robot: Turtlebot3Params,
    parts: LidarRobotParts,
    *,
    estimate: OutputPort | None = None,
    map_port: OutputPort | None = None,
    static_map: OccupancyMap | None = None,
) -> RosLogRecorder:
    """Adds a ``RosLogRecorder`` (named ``ros_log``) writing the robot's scans, odometry, true
    pose, ``estimate`` (SLAM's or AMCL's pose in the map) and map (``map_port``'s maps, or the
    fixed ``static_map``) to ``writer``."""
    recorder = builder.AddNamedSystem(
        "ros_log",
        RosLogRecorder(
            writer=writer,
            scan_period=1.0 / scenario.lidar.rate,
            frames=parts.frames,
            X_base_sensor=parts.X_base_sensor,
            sensor_height=robot.scan_height,
            static_map=static_map,
        ),
    )
    builder.Connect(parts.scan, recorder.GetInputPort("scan"))
    builder.Connect(parts.odometry_pose, recorder.GetInputPort("odometry_pose"))
    builder.Connect(parts.odometry_twist, recorder.GetInputPort("odometry_twist"))
    builder.Connect(parts.true_pose, recorder.GetInputPort("true_pose"))
    if estimate is not None:
        builder.Connect(estimate, recorder.GetInputPort("estimated_pose"))
    if map_port is not None and static_map is None:
        builder.Connect(map_port, recorder.GetInputPort("map"))
    return recorder
