"""The lidar robot navigating on a saved map: the arena it really drives in, the TurtleBot3 with
its diff-drive controller, wheel odometry and lidar, AMCL localising it on the map, and the
navigator (costmaps, global and local planners) driving ``cmd_vel``; with a Meshcat, the robot,
the map, the costmap, the particles, the paths and the true trail.

With no saved map (as move_base and nav2 run in an unknown place) there is no AMCL: the robot
localises with the live SLAM (``scenario.no_map_localization``, or on its wheel odometry
alone; either starts at the true start), and the navigator plans on a
map of unknown cells (``unknown_map``) that its obstacle layer fills from the lidar as the robot
drives: the global planner goes through unknown space (``planner.allow_unknown``) and replans
as it is revealed.

``make_navigation_diagram`` builds it; a pure builder (nothing is simulated here).
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import Meshcat, MeshcatVisualizer, MeshcatVisualizerParams, Role
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import (
    ConstantValueSource,
    ConstantVectorSource,
    LogVectorOutput,
)

from diagrams.lidar_robot import add_lidar_robot, add_ros_log
from diagrams.navigation_scenario import NavigationScenario
from drake_sim.base.map_files import UNKNOWN, OccupancyMap
from drake_sim.base.mcap_files import McapLogWriter
from drake_sim.navigation.navigator import Navigator
from drake_sim.robots.turtlebot3_params import Turtlebot3Params
from drake_sim.systems.estimation.amcl import Amcl
from drake_sim.systems.estimation.slam import SCAN_DELAY, SlamSystem
from drake_sim.systems.estimation.slam_config import map_square
from drake_sim.systems.viewer.map_view import MapView
from drake_sim.systems.viewer.navigation_view import NavigationView
from drake_sim.systems.viewer.trails import TrailVisualizer
from drake_sim.worlds.arena import Arena

UNKNOWN_MAP_MARGIN = 20.0
"""m: how far a map of unknown cells (no saved map) reaches beyond the start and the goals."""


def unknown_map(points, resolution: float, margin: float = UNKNOWN_MAP_MARGIN) -> OccupancyMap:
    """A map of unknown cells covering ``points`` ((N, >=2) x, y: the start and the goals)
    and ``margin`` beyond them, in the world frame: the navigator's map when there is none
    (move_base's rolling global costmap in ``odom``, 40 m square, is alike)."""
    xy = np.asarray(points, dtype=float).reshape(-1, np.shape(points)[-1])[:, :2]
    low, high = xy.min(axis=0) - margin, xy.max(axis=0) + margin
    cols, rows = (int(math.ceil(v / resolution)) for v in high - low)
    return OccupancyMap(np.full((rows, cols), UNKNOWN, np.int8), resolution, (*low, 0.0))


def make_navigation_diagram(
    scenario: NavigationScenario,
    robot: Turtlebot3Params,
    world: Arena,
    occupancy_map: OccupancyMap | None,
    *,
    start,
    initial_estimate=None,
    initial_covariance=None,
    global_localization: bool = False,
    goals=(),
    meshcat: Meshcat | None = None,
    log_writer: McapLogWriter | None = None,
    map_extent=(),
    map_margin: float = UNKNOWN_MAP_MARGIN,
) -> Diagram:
    """Builds the navigation diagram.

    Args:
        world: the arena the robot drives in (with any obstacles added after mapping).
        occupancy_map: the saved map AMCL and the navigator use (its frame is the world's);
            None: no map, the robot on its odometry and the navigator on ``unknown_map`` of
            the start and the goals (module docstring).
        start: the robot's true start ``[x, y, yaw]`` (m, m, rad).
        initial_estimate, initial_covariance: AMCL's first guess ``[x, y, yaw]`` and its 3 x 3
            covariance (None: the AMCL config's ``initial_pose_*`` and ``initial_cov_*``).
        global_localization: start AMCL with particles over the map's free space instead.
        goals: ``[x, y, yaw]`` goals (m, m, rad) the navigator visits in order.
        log_writer: where to write the run as a ROS 2 log (``add_ros_log``: scans, odometry,
            tf with the estimate, the saved map, or the live SLAM's without one), or None.
        map_extent: more [x, y] points the map of unknown cells covers (no saved map): an
            explorer's place, whose goals are not known beforehand.
        map_margin: how far (m) that map reaches beyond the start, the goals and
            ``map_extent`` (``unknown_map``).

    Exported outputs: ``true_pose``, ``odometry_pose``, ``estimated_pose`` (AMCL's, or the
    odometry's with no map),
    ``covariance``, ``particles``, ``scan``, ``cmd_vel`` and ``navigation_status``. The loggers
    ``log_true_pose`` and ``log_estimated_pose`` sample every ``scenario.log_period``; the
    systems are named ``amcl`` (with a map), ``navigator``, ``lidar`` and ``plant``.
    """
    builder = DiagramBuilder()
    robot_parts = add_lidar_robot(builder, scenario, robot=robot, world=world, start=start)
    X_base_sensor = robot_parts.X_base_sensor
    if occupancy_map is None:
        points = [np.asarray(start)[:2], *(np.asarray(g)[:2] for g in goals)]
        points += [np.asarray(p, dtype=float)[:2] for p in map_extent]
        nav_map = unknown_map(points, GROUND_RESOLUTION, map_margin)
        estimate, covariance, particles = _no_map_estimate(
            builder, scenario, robot_parts, start, nav_map
        )
        localized = None
    else:
        nav_map = occupancy_map
        estimate, covariance, particles, localized = _add_amcl(
            builder, scenario, occupancy_map, robot_parts,
            initial_estimate, initial_covariance, global_localization,
        )  # fmt: skip
    navigator = builder.AddNamedSystem(
        "navigator",
        Navigator(
            map=nav_map,
            config=scenario.navigator,
            X_base_sensor=X_base_sensor,
            goals=list(goals),
            localize_first=localized is not None and global_localization,
        ),
    )
    if localized is not None and global_localization:
        builder.Connect(localized, navigator.GetInputPort("localized"))
    builder.Connect(estimate, navigator.GetInputPort("pose"))
    builder.Connect(robot_parts.odometry_twist, navigator.GetInputPort("twist"))
    builder.Connect(robot_parts.scan, navigator.GetInputPort("scan"))
    builder.Connect(navigator.GetOutputPort("cmd_vel"), robot_parts.cmd_vel)

    for name, port in (
        ("true_pose", robot_parts.true_pose),
        ("odometry_pose", robot_parts.odometry_pose),
        ("estimated_pose", estimate),
        ("covariance", covariance),
        ("particles", particles),
        ("scan", robot_parts.scan),
        ("cmd_vel", navigator.GetOutputPort("cmd_vel")),
        ("navigation_status", navigator.GetOutputPort("status")),
    ):
        builder.ExportOutput(port, name)
    if log_writer is not None:
        slam = builder.GetSubsystemByName("slam") if builder.HasSubsystemNamed("slam") else None
        add_ros_log(
            builder, log_writer, scenario, robot, robot_parts, estimate=estimate,
            map_port=slam.GetOutputPort("map") if slam is not None else None,
            static_map=occupancy_map,
        )  # fmt: skip
    for name, port in (
        ("log_true_pose", robot_parts.true_pose),
        ("log_estimated_pose", estimate),
    ):
        LogVectorOutput(port, builder, scenario.log_period).set_name(name)
    if meshcat is not None:
        _add_views(builder, meshcat, scenario, nav_map, robot_parts, estimate, particles, navigator)
        if builder.HasSubsystemNamed("slam"):
            _add_slam_view(builder, meshcat, scenario, robot, robot_parts)
    diagram = builder.Build()
    diagram.set_name("navigation")
    return diagram


GROUND_RESOLUTION = 0.05
"""m: the cells of the map of unknown cells (no saved map)."""


def _no_map_estimate(builder, scenario, robot_parts, start, nav_map):
    """The pose estimate with no map: the live SLAM's (named ``slam``, its map holding
    ``nav_map``, started at the true ``start``) or the wheel odometry's
    (``scenario.no_map_localization``); a zero covariance and no particles beside it."""
    estimate = robot_parts.odometry_pose
    if scenario.no_map_localization == "slam":
        low = np.array(nav_map.origin[:2], dtype=float)
        high = low + [nav_map.width_m, nav_map.height_m]
        # No margin: nav_map has its own (the square's corner snaps down to the coarsest
        # cells, so its far edge may fall up to one such cell short of nav_map's).
        center, size = map_square(low, high, np.asarray(start)[:2], scenario.slam.map_size, 0.0)
        slam = builder.AddNamedSystem(
            "slam",
            SlamSystem(
                config=dc.replace(scenario.slam, map_size=size),
                period=1.0 / scenario.lidar.rate,
                initial_pose=np.asarray(start, dtype=float),
                X_base_sensor=robot_parts.X_base_sensor,
                map_center=center,
            ),
        )
        builder.Connect(robot_parts.scan, slam.GetInputPort("scan"))
        builder.Connect(robot_parts.odometry_pose, slam.GetInputPort("odometry"))
        estimate = slam.GetOutputPort("pose")
    covariance = builder.AddNamedSystem("no_covariance", ConstantVectorSource(np.zeros(9)))
    particles = builder.AddNamedSystem(
        "no_particles", ConstantValueSource(AbstractValue.Make(np.zeros((0, 3))))
    )
    return estimate, covariance.get_output_port(), particles.get_output_port()


def _add_amcl(
    builder, scenario, occupancy_map, robot_parts, initial_estimate, initial_covariance,
    global_localization,
):  # fmt: skip
    """AMCL on the saved map; its pose, covariance, particles and localized outputs."""
    amcl = builder.AddNamedSystem(
        "amcl",
        Amcl(
            map=occupancy_map,
            config=scenario.amcl,
            period=1.0 / scenario.lidar.rate,
            X_base_sensor=robot_parts.X_base_sensor,
            seed=scenario.random_seed,
            initial_pose=initial_estimate,
            initial_covariance=initial_covariance,
            global_localization=global_localization,
        ),
    )
    builder.Connect(robot_parts.scan, amcl.GetInputPort("scan"))
    builder.Connect(robot_parts.odometry_pose, amcl.GetInputPort("odometry"))
    return (
        amcl.GetOutputPort("pose"),
        amcl.GetOutputPort("covariance"),
        amcl.GetOutputPort("particles"),
        amcl.GetOutputPort("localized"),
    )


def _add_views(builder, meshcat, scenario, occupancy_map, robot_parts, estimate, particles,
               navigator):  # fmt: skip
    """The robot and arena, the map and costmap, the particles and the paths, the trails."""
    MeshcatVisualizer.AddToBuilder(
        builder, robot_parts.scene_graph, meshcat, MeshcatVisualizerParams(role=Role.kIllustration)
    )
    view = builder.AddNamedSystem(
        "navigation_view",
        NavigationView(meshcat=meshcat, occupancy_map=occupancy_map, period=scenario.view_period),
    )
    builder.Connect(particles, view.GetInputPort("particles"))
    builder.Connect(navigator.GetOutputPort("status"), view.GetInputPort("navigation_status"))
    trails = builder.AddNamedSystem(
        "trails", TrailVisualizer(meshcat=meshcat, period=scenario.view_period)
    )
    builder.Connect(estimate, trails.GetInputPort("odometry_pose"))
    builder.Connect(robot_parts.true_pose, trails.GetInputPort("true_pose"))


def _add_slam_view(builder, meshcat, scenario, robot, robot_parts) -> None:
    """With no saved map: the live SLAM's map as it grows, and the last scan (as mapping
    shows them)."""
    slam = builder.GetSubsystemByName("slam")
    view = builder.AddNamedSystem(
        "map_view",
        MapView(
            meshcat=meshcat,
            map_period=scenario.view_period,
            scan_period=1.0 / scenario.lidar.rate,
            scan_offset=2 * SCAN_DELAY,
            X_base_sensor=(robot.lidar.x, robot.lidar.y, 0.0),
            scan_height=robot.scan_height,
        ),
    )
    builder.Connect(slam.GetOutputPort("map"), view.GetInputPort("map"))
    builder.Connect(robot_parts.scan, view.GetInputPort("scan"))
    builder.Connect(slam.GetOutputPort("scan_pose"), view.GetInputPort("pose"))
