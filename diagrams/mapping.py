"""The lidar robot mapping an arena: the arena, the TurtleBot3 at its start with its diff-drive
controller and wheel odometry, the lidar, the SLAM, and a route follower (or teleop) on
``cmd_vel``; with a Meshcat, the robot, the map, the scan and the trails.

``make_mapping_diagram`` builds it; a pure builder (nothing is simulated here).
"""

import numpy as np
from pydrake.geometry import Meshcat, MeshcatVisualizer, MeshcatVisualizerParams, Role
from pydrake.multibody.plant import AddMultibodyPlant
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, MatrixGain

from diagrams.mapping_scenario import MappingScenario
from drake_sim.robots.turtlebot3 import (
    BASE_FOOTPRINT,
    LIDAR_FRAME,
    add_turtlebot3,
    drive_limits,
    start_pose,
    wheel_state_selector,
)
from drake_sim.robots.turtlebot3_params import Turtlebot3Params
from drake_sim.systems.control.diff_drive_controller import DiffDriveConfig, DiffDriveController
from drake_sim.systems.control.route_follower import RouteFollower
from drake_sim.systems.estimation.encoder_odometry import EncoderOdometry, PlanarGroundTruth
from drake_sim.systems.estimation.slam import SCAN_DELAY, SlamSystem
from drake_sim.systems.sensors.lidar import add_lidar
from drake_sim.systems.viewer.map_view import MapView
from drake_sim.systems.viewer.teleop import MeshcatTeleop, TeleopConfig
from drake_sim.systems.viewer.trails import TrailVisualizer
from drake_sim.worlds.arena import Arena
from drake_sim.worlds.arena_world import add_arena

ROBOT_NAME = "turtlebot3"


def make_mapping_diagram(
    scenario: MappingScenario,
    robot: Turtlebot3Params,
    arena: Arena,
    waypoints,
    *,
    meshcat: Meshcat | None = None,
    teleop: bool = False,
    keyframes: bool = False,
) -> Diagram:
    """Builds the mapping diagram for ``scenario`` in ``arena``.

    The ``RouteFollower`` (named ``route_follower``) drives ``waypoints`` ([[x, y], ...] m)
    from the arena's start using the true pose; with ``teleop`` the ``MeshcatTeleop``'s keys
    drive instead (needs ``meshcat``). With ``keyframes`` a Meshcat recording keeps the map
    and the scan as they grow (see ``MapView``). The SLAM (``slam``, a ``SlamSystem``) starts at the
    arena's start pose, so its map frame is the arena's.

    Exported outputs: ``true_pose``, ``odometry_pose``, ``slam_pose`` (``[x, y, yaw]``),
    ``scan`` (``LaserScan``), ``map`` (``OccupancyMap``), ``command`` (``cmd_vel``) and, with a
    route, ``route_done``. ``log_true_pose`` logs the true pose every ``scenario.log_period``.
    """
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(scenario.plant, builder)
    add_arena(plant, arena)
    instance = add_turtlebot3(plant, robot, name=ROBOT_NAME)
    plant.Finalize()
    start = np.array(arena.start_pose())
    base = plant.GetBodyByName(BASE_FOOTPRINT, instance)
    plant.SetDefaultFloatingBaseBodyPose(base, start_pose(*start))

    wheels = builder.AddNamedSystem(
        "wheel_state", MatrixGain(wheel_state_selector(plant, instance))
    )
    builder.Connect(plant.get_state_output_port(), wheels.get_input_port())
    drive = DiffDriveConfig(rate=scenario.drive_rate, **drive_limits(robot))
    controller = builder.AddNamedSystem(
        "diff_drive", DiffDriveController(robot=robot, config=drive, upside_down_aware=False)
    )
    builder.Connect(wheels.get_output_port(), controller.GetInputPort("wheel_state"))
    builder.Connect(
        controller.GetOutputPort("wheel_torques"), plant.get_actuation_input_port(instance)
    )
    odometry = builder.AddNamedSystem(
        "odometry",
        EncoderOdometry(
            wheel_radius=robot.wheel.radius,
            wheel_separation=robot.wheel_separation,
            config=scenario.odometry,
            initial_pose=start,
            seed=scenario.random_seed,
        ),
    )
    builder.Connect(wheels.get_output_port(), odometry.GetInputPort("wheel_state"))
    truth = builder.AddNamedSystem("true_pose", PlanarGroundTruth(plant=plant, body=base))
    builder.Connect(plant.get_body_poses_output_port(), truth.get_input_port())

    lidar = add_lidar(
        builder,
        plant,
        scene_graph,
        frame=plant.GetFrameByName(LIDAR_FRAME, instance),
        config=scenario.lidar,
        ignore=[instance],
        seed=scenario.random_seed,
    )
    X_base_sensor = (robot.lidar.x, robot.lidar.y, 0.0)
    slam = builder.AddNamedSystem(
        "slam",
        SlamSystem(
            config=scenario.slam,
            period=1.0 / scenario.lidar.rate,
            initial_pose=start,
            X_base_sensor=X_base_sensor,
        ),
    )
    builder.Connect(lidar.GetOutputPort("scan"), slam.GetInputPort("scan"))
    builder.Connect(odometry.GetOutputPort("pose"), slam.GetInputPort("odometry"))

    if teleop:
        driver = builder.AddNamedSystem(
            "teleop", MeshcatTeleop(meshcat=meshcat, config=TeleopConfig(linear_step=0.05))
        )
    else:
        driver = builder.AddNamedSystem(
            "route_follower", RouteFollower(waypoints=waypoints, config=scenario.route_follower)
        )
        builder.Connect(truth.get_output_port(), driver.GetInputPort("pose"))
        builder.ExportOutput(driver.GetOutputPort("done"), "route_done")
    builder.Connect(driver.GetOutputPort("command"), controller.GetInputPort("command"))

    for name, port in (
        ("true_pose", truth.get_output_port()),
        ("odometry_pose", odometry.GetOutputPort("pose")),
        ("slam_pose", slam.GetOutputPort("pose")),
        ("scan", lidar.GetOutputPort("scan")),
        ("map", slam.GetOutputPort("map")),
        ("command", driver.GetOutputPort("command")),
    ):
        builder.ExportOutput(port, name)
    logger = LogVectorOutput(truth.get_output_port(), builder, scenario.log_period)
    logger.set_name("log_true_pose")
    if meshcat is not None:
        _add_views(builder, scene_graph, meshcat, scenario, robot, (slam, lidar, truth), keyframes)
    diagram = builder.Build()
    diagram.set_name("mapping")
    return diagram


def _add_views(builder, scene_graph, meshcat, scenario, robot, systems, keyframes) -> None:
    """The robot and arena, the map, the scan and the SLAM pose against the truth."""
    slam, lidar, truth = systems
    MeshcatVisualizer.AddToBuilder(
        builder, scene_graph, meshcat, MeshcatVisualizerParams(role=Role.kIllustration)
    )
    view = builder.AddNamedSystem(
        "map_view",
        MapView(
            meshcat=meshcat,
            map_period=scenario.record_map_period if keyframes else scenario.map_view_period,
            scan_period=1.0 / scenario.lidar.rate,
            scan_offset=2 * SCAN_DELAY,
            X_base_sensor=(robot.lidar.x, robot.lidar.y, 0.0),
            scan_height=robot.scan_height,
            keyframes=keyframes,
        ),
    )
    builder.Connect(slam.GetOutputPort("map"), view.GetInputPort("map"))
    builder.Connect(lidar.GetOutputPort("scan"), view.GetInputPort("scan"))
    builder.Connect(slam.GetOutputPort("scan_pose"), view.GetInputPort("pose"))
    trails = builder.AddNamedSystem(
        "trails", TrailVisualizer(meshcat=meshcat, period=1.0 / scenario.lidar.rate)
    )
    builder.Connect(slam.GetOutputPort("pose"), trails.GetInputPort("odometry_pose"))
    builder.Connect(truth.get_output_port(), trails.GetInputPort("true_pose"))
