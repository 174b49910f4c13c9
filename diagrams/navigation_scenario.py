"""Typed scenario for navigating the lidar robot on a saved map: the arena it really drives in
(with obstacles the map does not have), the lidar, the odometry's errors, AMCL, the navigator
(costmaps, global and local planners, recoveries), the plant and the run's limits. Values live
in ``config/navigation_scenario.yaml``; units in comments."""

import dataclasses as dc
from pathlib import Path

from pydrake.multibody.plant import MultibodyPlantConfig

from diagrams.lidar_robot import check_lidar_robot_scenario
from diagrams.mapping_scenario import config_path
from diagrams.ros_params import ros_overrides
from drake_sim.base.checks import fields_of, require_positive
from drake_sim.base.config import apply_overrides, load_checked
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from drake_sim.navigation.navigator import NavigatorConfig, check_navigator_config
from drake_sim.systems.estimation.amcl import (
    AmclConfig,
    check_amcl_config,
    default_amcl_config_file,
    load_amcl_config,
)
from drake_sim.systems.estimation.encoder_odometry import EncoderOdometryConfig
from drake_sim.systems.estimation.slam_config import SlamConfig
from drake_sim.systems.sensors.lidar import LidarConfig
from drake_sim.worlds.arena import Arena, BoxSpec, CylinderSpec, ObstacleSpec, check_arena

__all__ = ["NavigationScenario", "check_navigation_scenario", "config_path"]


@dc.dataclass
class ExtraObstacle:
    """An obstacle put in the world after mapping: exactly one of ``box`` and ``cylinder``, in
    the arena file's format."""

    box: BoxSpec | None = None
    cylinder: CylinderSpec | None = None
    name: str = ""  # Optional; default "extra_<index>".


@dc.dataclass
class NavigationScenario:
    """The lidar robot localising on a saved map and driving to goals."""

    arena: str = "arenas/room.yaml"  # The world it drives in; a relative path is from config/.
    # A map_server map to drive in instead of the arena, its occupied cells walls
    # (drake_sim.worlds.map_world); "" for none. A relative path is from config/.
    world: str = ""
    # The robot's start in the map's world: [x, y, yaw] in m, m, degrees (an arena keeps its own).
    start: list[float] = dc.field(default_factory=list)
    # ROS parameter files (nav2_params.yaml; ROS 1 parameter YAML or launch files), read in
    # order: their keys with a meaning here replace the scenario's (diagrams.ros_params).
    # Relative paths are from config/.
    params: list[str] = dc.field(default_factory=list)
    # Obstacles added to the world after mapping (arena obstacle entries): the robot's
    # obstacle layer sees them, its map does not.
    extra_obstacles: list[ExtraObstacle] = dc.field(default_factory=list)
    lidar: LidarConfig = dc.field(default_factory=LidarConfig)  # The TurtleBot3's LDS-01.
    odometry: EncoderOdometryConfig = dc.field(default_factory=EncoderOdometryConfig)
    # AMCL: config/amcl.yaml's values (tuned here; ROS's defaults leave 5 to 20 cm of error).
    amcl: AmclConfig = dc.field(
        default_factory=lambda: load_amcl_config(default_amcl_config_file())
    )
    navigator: NavigatorConfig = dc.field(default_factory=NavigatorConfig)
    # With no saved map (navigate without --map): "slam", the live SLAM's pose (its map starts
    # empty at the start pose), or "odometry", the wheel odometry's alone.
    no_map_localization: str = "slam"
    slam: SlamConfig = dc.field(default_factory=SlamConfig)  # as mapping's (no map only)
    drive_rate: float = 100.0  # Hz, the wheel velocity loops (limits: the robot's).
    plant: MultibodyPlantConfig = dc.field(
        default_factory=lambda: MultibodyPlantConfig(
            time_step=2e-3, contact_model="point", discrete_contact_approximation="lagged"
        )
    )
    # s allowed per goal: its path length over the robot's top speed times goal_time_factor,
    # plus goal_time_margin (turning, localising, recoveries).
    goal_time_factor: float = 2.5
    goal_time_margin: float = 20.0
    log_period: float = 0.05  # s between samples of the true and estimated poses.
    view_period: float = 0.5  # s between redraws of the costmap, particles and paths.
    random_seed: int = 0  # Odometry errors, lidar noise, AMCL.


NO_MAP_LOCALIZATION = ("slam", "odometry")
"""How the robot localises when navigating with no saved map."""


def check_navigation_scenario(
    scenario: NavigationScenario, where: str = "scenario"
) -> NavigationScenario:
    """Returns ``scenario`` if valid; raises ``ConfigError`` naming ``where`` and the key."""
    check_lidar_robot_scenario(scenario, where)
    check_amcl_config(scenario.amcl, where, prefix="amcl.")
    check_navigator_config(scenario.navigator, f"{where}: navigator")
    if scenario.no_map_localization not in NO_MAP_LOCALIZATION:
        raise ConfigError(
            f"{where}: 'no_map_localization' must be one of {', '.join(NO_MAP_LOCALIZATION)}, "
            f"got {scenario.no_map_localization!r}"
        )
    scenario.slam.check(f"{where}: slam")
    keys = ("goal_time_factor", "goal_time_margin", "view_period")
    require_positive(where, fields_of(scenario, keys))
    return scenario


def world_arena(scenario: NavigationScenario, arena: Arena, where: str = "scenario") -> Arena:
    """``arena`` with the scenario's ``extra_obstacles`` added (checked like an arena's own:
    inside the walls, clear of the start); the arena the robot really drives in."""
    extra = [
        ObstacleSpec(box=o.box, cylinder=o.cylinder, name=o.name or f"extra_{i}")
        for i, o in enumerate(scenario.extra_obstacles)
    ]
    if not extra:
        return arena
    world = dc.replace(arena, obstacles=[*arena.obstacles, *extra])
    return check_arena(world, f"{where}: extra_obstacles")


def default_scenario_file() -> Path:
    """Returns ``config/navigation_scenario.yaml``."""
    return config_dir() / "navigation_scenario.yaml"


def load_navigation_scenario(
    path, overrides=(), *, schema=NavigationScenario, check=check_navigation_scenario
):
    """The scenario at ``path`` with ``overrides`` (``KEY=VALUE`` or ``(label, KEY=VALUE)``)
    applied, its ``params`` files' keys under them (the files' values first, in order, the
    overrides' on top: a ``--set amcl.x=...`` still wins), checked. ``schema`` and ``check``:
    a scenario that extends this one (the explore app's) and its check.

    Raises:
        ConfigError: naming the file (the scenario's, the parameter file's or ``--set``) and
            the key at fault.
    """
    overrides = list(overrides)
    what = "scenario file"
    scenario = load_checked(schema, path, check, what=what)
    base = scenario
    if overrides:
        scenario = apply_overrides(schema, scenario, overrides)
    if not scenario.params:
        return check(scenario, "--set")
    for name in scenario.params:
        params = config_path(name)
        where = str(params)
        labelled = [(f"{where}: {o.partition('=')[0]}", o) for o in ros_overrides(params)]
        base = apply_overrides(schema, base, labelled)
        base = check(base, where)
    if overrides:
        base = apply_overrides(schema, base, overrides)
    return check(base, "--set")
