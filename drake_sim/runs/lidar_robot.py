"""What the lidar robot's two apps (mapping and navigate) share in their recipes: the robot file,
the flags that choose the world (an arena, or a map's world and a start) and the lidar."""

import math
from pathlib import Path

from diagrams.mapping_scenario import config_path
from drake_sim.base import cli
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap, load_map
from drake_sim.robots.turtlebot3 import default_turtlebot3_file
from drake_sim.robots.turtlebot3_params import Turtlebot3Params, load_turtlebot3_params, validate
from drake_sim.runs.recipe import Flag, InputFile, file_flag
from drake_sim.worlds.arena import Arena, load_arena
from drake_sim.worlds.map_world import map_arena

ROBOT_FILE = InputFile(
    Turtlebot3Params,
    default_turtlebot3_file,
    validate,
    what="robot file",
    load=load_turtlebot3_params,
)
"""``config/turtlebot3.yaml`` by default."""

ARENA_FLAG = file_flag("--arena", "arena file", "arena YAML", key="arena")
"""``--arena FILE``: the scenario's ``arena``."""

LIDAR_FLAG = Flag(
    "--lidar",
    "lidar",
    {
        "type": cli.preset_or_file("lidar"),
        "help": "lidar preset (config/lidars/NAME.yaml, e.g. sick_tim571) or YAML file "
        "(default: the scenario's, the LDS-01)",
    },
)
"""``--lidar NAME|FILE``: the scenario's ``lidar``, a preset by name or a file."""

WORLD_FLAG = file_flag(
    "--world", "world map file", "map_server .yaml simulated as walls", key="world"
)
"""``--world MAP``: the scenario's ``world``, a map to drive in (``drake_sim.worlds.map_world``)."""

START_FLAG = Flag(
    "--start",
    key="start",
    kwargs={
        "nargs": 3,
        "type": float,
        "metavar": ("X", "Y", "YAW"),
        "help": "the robot's start in a world from a map (--world MAP; navigate: or --map "
        "with no arena named): x, y (m), yaw (degrees)",
    },
)
"""``--start X Y YAW``: the scenario's ``start``, where the robot starts in a ``world``."""


def load_world(scenario) -> tuple[Path, Arena, OccupancyMap | None]:
    """The world a mapping or navigation scenario's robot drives in, its file and the map it
    was made from: the map its ``world`` names (occupied cells walls) with the robot at its
    ``start`` ([x, y, yaw_deg], required there), else its ``arena`` (which keeps its own start;
    no map).

    Raises:
        ConfigError: a start without a world or a world without a start, a bad map, or a start
            off the map's free cells.
    """
    start = scenario.start or None
    if not scenario.world:
        if start is not None:
            raise ConfigError(
                "--start places the robot in a world from a map (--world MAP); an arena keeps "
                "its own start"
            )
        arena_file = config_path(scenario.arena)
        return arena_file, load_arena(arena_file), None
    world_file = config_path(scenario.world)
    if start is None:
        raise ConfigError(f"--world {world_file}: give the robot's start with --start X Y YAW")
    if len(start) != 3:
        raise ConfigError(f"start must be [x, y, yaw], got {len(start)} values")
    x, y, yaw = (float(v) for v in start)
    where = f"--world {world_file}"
    world_map = load_map(world_file)
    arena = map_arena(world_map, (x, y, math.radians(yaw)), where=where)
    return Path(world_file), arena, world_map
