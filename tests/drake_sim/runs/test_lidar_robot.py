"""drake_sim.runs.lidar_robot: the robot file, the arena and lidar flags of mapping and navigate."""

from pathlib import Path

import drake_sim.runs.lidar_robot as mut
from drake_sim.robots.turtlebot3_params import Turtlebot3Params


def test_the_robot_file_defaults_to_the_turtlebot3():
    robot = mut.ROBOT_FILE.read(None)
    assert isinstance(robot, Turtlebot3Params)
    assert mut.ROBOT_FILE.read(None, ["lidar.z=0.2"]).lidar.z == 0.2


def test_the_flags_set_scenario_keys():
    assert mut.LIDAR_FLAG.override("sick_tim571") == 'lidar="sick_tim571"'
    key, _, value = mut.ARENA_FLAG.override(Path("arenas/room.yaml")).partition("=")
    assert key == "arena" and Path(value.strip('"')).is_absolute()
    assert mut.LIDAR_FLAG.kwargs["type"]("lds_01") == "lds_01"
