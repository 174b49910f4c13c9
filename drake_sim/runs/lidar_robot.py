"""What the lidar robot's two apps (mapping and navigate) share in their recipes: the robot file
and the flags that choose the arena and the lidar."""

from drake_sim.base import cli
from drake_sim.robots.turtlebot3 import default_turtlebot3_file
from drake_sim.robots.turtlebot3_params import Turtlebot3Params, load_turtlebot3_params, validate
from drake_sim.runs.recipe import Flag, InputFile, file_flag

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
