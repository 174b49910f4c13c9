"""drake_sim.runs.lidar_robot: the robot file, the arena and lidar flags of mapping and navigate."""

from pathlib import Path

import pytest

import drake_sim.runs.lidar_robot as mut
from drake_sim.base.errors import ConfigError
from drake_sim.robots.turtlebot3_params import Turtlebot3Params


def test_the_robot_file_defaults_to_the_turtlebot3():
    robot = mut.ROBOT_FILE.read(None)
    assert isinstance(robot, Turtlebot3Params)
    assert mut.ROBOT_FILE.read(None, ["lidar.z=0.2"]).lidar.z == 0.2


def test_the_flags_set_scenario_keys():
    assert mut.LIDAR_FLAG.override("sick_tim571") == ("--lidar sick_tim571", 'lidar="sick_tim571"')
    key, _, value = mut.ARENA_FLAG.override(Path("arenas/room.yaml"))[1].partition("=")
    assert key == "arena" and Path(value.strip('"')).is_absolute()
    assert mut.LIDAR_FLAG.kwargs["type"]("lds_01") == "lds_01"


def test_an_unknown_preset_is_named_by_the_flag():
    from drake_sim.runs import command, mapping

    args = command.parser(mapping.RECIPE, "doc").parse_args(["--lidar", "nonsense"])
    with pytest.raises(ConfigError, match=r"^--lidar nonsense: 'lidar': unknown lidars preset"):
        command.load_from_args(mapping.RECIPE, args)
