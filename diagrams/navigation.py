"""The lidar robot navigating on a saved map: the arena it really drives in, the TurtleBot3 with
its diff-drive controller, wheel odometry and lidar, AMCL localising it on the map, and the
navigator (costmaps, global and local planners) driving ``cmd_vel``; with a Meshcat, the robot,
the map, the costmap, the particles, the paths and the true trail.

``make_navigation_diagram`` builds it; a pure builder (nothing is simulated here).
"""

from pydrake.geometry import Meshcat, MeshcatVisualizer, MeshcatVisualizerParams, Role
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput

from diagrams.lidar_robot import add_lidar_robot
from diagrams.navigation_scenario import NavigationScenario
from drake_sim.base.map_files import OccupancyMap
from drake_sim.navigation.navigator import Navigator
from drake_sim.robots.turtlebot3_params import Turtlebot3Params
from drake_sim.systems.estimation.amcl import Amcl
from drake_sim.systems.viewer.navigation_view import NavigationView
from drake_sim.systems.viewer.trails import TrailVisualizer
from drake_sim.worlds.arena import Arena


def make_navigation_diagram(
    scenario: NavigationScenario,
    robot: Turtlebot3Params,
    world: Arena,
    occupancy_map: OccupancyMap,
    *,
    start,
    initial_estimate=None,
    initial_covariance=None,
    global_localization: bool = False,
    goals=(),
    meshcat: Meshcat | None = None,
) -> Diagram:
    """Builds the navigation diagram.

    Args:
        world: the arena the robot drives in (with any obstacles added after mapping).
        occupancy_map: the saved map AMCL and the navigator use (its frame is the world's).
        start: the robot's true start ``[x, y, yaw]`` (m, m, rad).
        initial_estimate, initial_covariance: AMCL's first guess ``[x, y, yaw]`` and its 3 x 3
            covariance (None: the AMCL config's ``initial_pose_*`` and ``initial_cov_*``).
        global_localization: start AMCL with particles over the map's free space instead.
        goals: ``[x, y, yaw]`` goals (m, m, rad) the navigator visits in order.

    Exported outputs: ``true_pose``, ``odometry_pose``, ``estimated_pose`` (AMCL's),
    ``covariance``, ``particles``, ``scan``, ``cmd_vel`` and ``navigation_status``. The loggers
    ``log_true_pose`` and ``log_estimated_pose`` sample every ``scenario.log_period``; the
    systems are named ``amcl``, ``navigator``, ``lidar`` and ``plant``.
    """
    builder = DiagramBuilder()
    robot_parts = add_lidar_robot(builder, scenario, robot=robot, world=world, start=start)
    X_base_sensor = robot_parts.X_base_sensor
    amcl = builder.AddNamedSystem(
        "amcl",
        Amcl(
            map=occupancy_map,
            config=scenario.amcl,
            period=1.0 / scenario.lidar.rate,
            X_base_sensor=X_base_sensor,
            seed=scenario.random_seed,
            initial_pose=initial_estimate,
            initial_covariance=initial_covariance,
            global_localization=global_localization,
        ),
    )
    builder.Connect(robot_parts.scan, amcl.GetInputPort("scan"))
    builder.Connect(robot_parts.odometry_pose, amcl.GetInputPort("odometry"))
    navigator = builder.AddNamedSystem(
        "navigator",
        Navigator(
            map=occupancy_map,
            config=scenario.navigator,
            X_base_sensor=X_base_sensor,
            goals=list(goals),
        ),
    )
    builder.Connect(amcl.GetOutputPort("pose"), navigator.GetInputPort("pose"))
    builder.Connect(robot_parts.odometry_twist, navigator.GetInputPort("twist"))
    builder.Connect(robot_parts.scan, navigator.GetInputPort("scan"))
    builder.Connect(navigator.GetOutputPort("cmd_vel"), robot_parts.cmd_vel)

    for name, port in (
        ("true_pose", robot_parts.true_pose),
        ("odometry_pose", robot_parts.odometry_pose),
        ("estimated_pose", amcl.GetOutputPort("pose")),
        ("covariance", amcl.GetOutputPort("covariance")),
        ("particles", amcl.GetOutputPort("particles")),
        ("scan", robot_parts.scan),
        ("cmd_vel", navigator.GetOutputPort("cmd_vel")),
        ("navigation_status", navigator.GetOutputPort("status")),
    ):
        builder.ExportOutput(port, name)
    for name, port in (
        ("log_true_pose", robot_parts.true_pose),
        ("log_estimated_pose", amcl.GetOutputPort("pose")),
    ):
        LogVectorOutput(port, builder, scenario.log_period).set_name(name)
    if meshcat is not None:
        _add_views(builder, meshcat, scenario, occupancy_map, robot_parts, amcl, navigator)
    diagram = builder.Build()
    diagram.set_name("navigation")
    return diagram


def _add_views(builder, meshcat, scenario, occupancy_map, robot_parts, amcl, navigator):
    """The robot and arena, the map and costmap, the particles and the paths, the trails."""
    MeshcatVisualizer.AddToBuilder(
        builder, robot_parts.scene_graph, meshcat, MeshcatVisualizerParams(role=Role.kIllustration)
    )
    view = builder.AddNamedSystem(
        "navigation_view",
        NavigationView(meshcat=meshcat, occupancy_map=occupancy_map, period=scenario.view_period),
    )
    builder.Connect(amcl.GetOutputPort("particles"), view.GetInputPort("particles"))
    builder.Connect(navigator.GetOutputPort("status"), view.GetInputPort("navigation_status"))
    trails = builder.AddNamedSystem(
        "trails", TrailVisualizer(meshcat=meshcat, period=scenario.view_period)
    )
    builder.Connect(amcl.GetOutputPort("pose"), trails.GetInputPort("odometry_pose"))
    builder.Connect(robot_parts.true_pose, trails.GetInputPort("true_pose"))
