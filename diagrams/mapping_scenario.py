"""Typed scenario for mapping an arena with the lidar robot: the arena and route, the lidar, the
wheel odometry's errors, the SLAM, the route follower, the plant and the viewer. Values live in
``config/mapping_scenario.yaml``; units in comments."""

import dataclasses as dc
from pathlib import Path

from pydrake.multibody.plant import MultibodyPlantConfig

from diagrams.lidar_robot import check_lidar_robot_scenario
from drake_sim.base.checks import fields_of, require_positive
from drake_sim.base.resources import config_dir
from drake_sim.systems.control.route_follower import (
    RouteFollowerConfig,
    check_route_follower_config,
)
from drake_sim.systems.estimation.encoder_odometry import EncoderOdometryConfig
from drake_sim.systems.estimation.slam_config import SlamConfig
from drake_sim.systems.sensors.lidar import LidarConfig


@dc.dataclass
class MappingScenario:
    """The lidar robot mapping an arena along a route (or driven by teleop)."""

    arena: str = "arenas/room.yaml"  # Arena file; a relative path is from config/.
    # A map_server map to drive in instead of the arena, its occupied cells walls
    # (drake_sim.worlds.map_world); "" for none. A relative path is from config/.
    world: str = ""
    # The robot's start in the map's world: [x, y, yaw] in m, m, degrees (an arena keeps its own).
    start: list[float] = dc.field(default_factory=list)
    route: str = ""  # Route file (relative: from config/); "" for the arena's default route.
    lidar: LidarConfig = dc.field(default_factory=LidarConfig)  # The TurtleBot3's LDS-01.
    odometry: EncoderOdometryConfig = dc.field(default_factory=EncoderOdometryConfig)
    slam: SlamConfig = dc.field(default_factory=SlamConfig)
    route_follower: RouteFollowerConfig = dc.field(default_factory=RouteFollowerConfig)
    drive_rate: float = 100.0  # Hz, the diff-drive controller's wheel loops (limits: the robot's).
    plant: MultibodyPlantConfig = dc.field(
        default_factory=lambda: MultibodyPlantConfig(
            time_step=2e-3, contact_model="point", discrete_contact_approximation="lagged"
        )
    )
    map_view_period: float = 1.0  # s between redraws of the map in Meshcat.
    # s between the map's (and the scan's) drawings kept in a --record replay: each is a whole
    # map, so a replay of a long run grows by megabytes per drawing.
    record_map_period: float = 5.0
    log_period: float = 0.05  # s between samples of the true pose (for the report).
    # s simulated at most: the route's length / speed x duration_factor + duration_margin.
    duration_factor: float = 2.0
    duration_margin: float = 30.0
    random_seed: int = 0  # Odometry errors and lidar noise.


def check_mapping_scenario(scenario: MappingScenario, where: str = "scenario") -> MappingScenario:
    """Returns ``scenario`` if valid; raises ``ConfigError`` naming ``where`` and the key."""
    check_lidar_robot_scenario(scenario, where)
    scenario.slam.check(f"{where}: slam")
    check_route_follower_config(scenario.route_follower, f"{where}: route_follower")
    keys = ("map_view_period", "record_map_period", "duration_factor", "duration_margin")
    require_positive(where, fields_of(scenario, keys))
    return scenario


def config_path(name: str) -> Path:
    """A file named in a scenario: as given if absolute, else under ``config/``."""
    path = Path(name)
    return path if path.is_absolute() else config_dir() / path


def default_scenario_file() -> Path:
    """Returns ``config/mapping_scenario.yaml``."""
    return config_dir() / "mapping_scenario.yaml"
