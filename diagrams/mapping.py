"""The lidar robot mapping an arena: the arena, the TurtleBot3 at its start with its diff-drive
controller and wheel odometry, the lidar, the SLAM, and a route follower (or teleop) on
``cmd_vel``; with a Meshcat, the robot, the map, the scan and the trails.

``make_mapping_diagram`` builds it; a pure builder (nothing is simulated here).
"""

import dataclasses as dc

import numpy as np
from pydrake.geometry import Meshcat, MeshcatVisualizer, MeshcatVisualizerParams, Role
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput

from diagrams.lidar_robot import add_lidar_robot, add_ros_log
from diagrams.mapping_scenario import MappingScenario
from drake_sim.base.mcap_files import McapLogWriter
from drake_sim.robots.turtlebot3_params import Turtlebot3Params
from drake_sim.systems.control.route_follower import RouteFollower
from drake_sim.systems.estimation.slam import SCAN_DELAY, SlamSystem
from drake_sim.systems.estimation.slam_config import map_square
from drake_sim.systems.viewer.map_view import MapView
from drake_sim.systems.viewer.teleop import MeshcatTeleop, TeleopConfig
from drake_sim.systems.viewer.trails import TrailVisualizer
from drake_sim.worlds.arena import Arena, arena_bounds


def make_mapping_diagram(
    scenario: MappingScenario,
    robot: Turtlebot3Params,
    arena: Arena,
    waypoints,
    *,
    meshcat: Meshcat | None = None,
    teleop: bool = False,
    keyframes: bool = False,
    log_writer: McapLogWriter | None = None,
) -> Diagram:
    """Builds the mapping diagram for ``scenario`` in ``arena``.

    The ``RouteFollower`` (named ``route_follower``) drives ``waypoints`` ([[x, y], ...] m)
    from the arena's start using the true pose; with ``teleop`` the ``MeshcatTeleop``'s keys
    drive instead (needs ``meshcat``). With ``keyframes`` a Meshcat recording keeps the map
    and the scan as they grow (see ``MapView``). With a ``log_writer`` the run is written
    to it as a ROS 2 log (``add_ros_log``: scans, odometry, tf, the SLAM's map). The SLAM
    (``slam``, a ``SlamSystem``) starts at the arena's start pose, so its map frame is the
    arena's; its map holds the whole arena (``slam_config.map_square``).

    Exported outputs: ``true_pose``, ``odometry_pose``, ``slam_pose`` (``[x, y, yaw]``),
    ``scan`` (``LaserScan``), ``map`` (``OccupancyMap``), ``command`` (``cmd_vel``) and, with a
    route, ``route_done``. ``log_true_pose`` logs the true pose every ``scenario.log_period``.
    """
    builder = DiagramBuilder()
    start = np.array(arena.start_pose())
    robot_parts = add_lidar_robot(builder, scenario, robot=robot, world=arena, start=start)
    X_base_sensor = robot_parts.X_base_sensor
    # The SLAM's map holds the arena and its walls (centred on the start when it can).
    center, size = map_square(*arena_bounds(arena, walls=True), start[:2], scenario.slam.map_size)
    slam = builder.AddNamedSystem(
        "slam",
        SlamSystem(
            config=dc.replace(scenario.slam, map_size=size),
            period=1.0 / scenario.lidar.rate,
            initial_pose=start,
            X_base_sensor=X_base_sensor,
            map_center=center,
        ),
    )
    builder.Connect(robot_parts.scan, slam.GetInputPort("scan"))
    builder.Connect(robot_parts.odometry_pose, slam.GetInputPort("odometry"))

    if teleop:
        driver = builder.AddNamedSystem(
            "teleop", MeshcatTeleop(meshcat=meshcat, config=TeleopConfig(linear_step=0.05))
        )
    else:
        driver = builder.AddNamedSystem(
            "route_follower", RouteFollower(waypoints=waypoints, config=scenario.route_follower)
        )
        builder.Connect(robot_parts.true_pose, driver.GetInputPort("pose"))
        builder.ExportOutput(driver.GetOutputPort("done"), "route_done")
    builder.Connect(driver.GetOutputPort("command"), robot_parts.cmd_vel)

    for name, port in (
        ("true_pose", robot_parts.true_pose),
        ("odometry_pose", robot_parts.odometry_pose),
        ("slam_pose", slam.GetOutputPort("pose")),
        ("scan", robot_parts.scan),
        ("map", slam.GetOutputPort("map")),
        ("command", driver.GetOutputPort("command")),
    ):
        builder.ExportOutput(port, name)
    if log_writer is not None:
        add_ros_log(
            builder, log_writer, scenario, robot, robot_parts,
            estimate=slam.GetOutputPort("pose"), map_port=slam.GetOutputPort("map"),
        )  # fmt: skip
    logger = LogVectorOutput(robot_parts.true_pose, builder, scenario.log_period)
    logger.set_name("log_true_pose")
    if meshcat is not None:
        _add_views(builder, meshcat, scenario, robot, robot_parts, slam, keyframes)
    diagram = builder.Build()
    diagram.set_name("mapping")
    return diagram


def _add_views(builder, meshcat, scenario, robot, robot_parts, slam, keyframes) -> None:
    """The robot and arena, the map, the scan and the SLAM pose against the truth."""
    MeshcatVisualizer.AddToBuilder(
        builder, robot_parts.scene_graph, meshcat, MeshcatVisualizerParams(role=Role.kIllustration)
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
    builder.Connect(robot_parts.scan, view.GetInputPort("scan"))
    builder.Connect(slam.GetOutputPort("scan_pose"), view.GetInputPort("pose"))
    trails = builder.AddNamedSystem(
        "trails", TrailVisualizer(meshcat=meshcat, period=1.0 / scenario.lidar.rate)
    )
    builder.Connect(slam.GetOutputPort("pose"), trails.GetInputPort("odometry_pose"))
    builder.Connect(robot_parts.true_pose, trails.GetInputPort("true_pose"))
