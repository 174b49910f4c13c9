"""drake_sim.runs.lidar_robot: the robot file, the world (arena or map) and lidar flags of mapping
and navigate."""

import math
from pathlib import Path

import pytest

import drake_sim.runs.lidar_robot as mut
from diagrams.navigation_scenario import NavigationScenario
from drake_sim.base.errors import ConfigError
from drake_sim.robots.turtlebot3_params import Turtlebot3Params
from tests import navigation_helpers as nh


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


def test_a_scenario_names_a_world_and_a_start(tmp_path):
    """``world`` and ``start`` keys: what ``--world`` and ``--start`` set."""
    _, room_map = nh.saved_truth_map("room", tmp_path)
    scenario = NavigationScenario(world=str(room_map), start=[-2.2, -1.8, 90.0])
    path, arena, world_map = mut.load_world(scenario)
    assert world_map.resolution == pytest.approx(0.05)
    assert path == room_map and arena.start_pose()[2] == pytest.approx(math.pi / 2)
    assert len(arena.obstacles) > 4
    with pytest.raises(ConfigError, match="give the robot's start"):
        mut.load_world(NavigationScenario(world=str(room_map)))
    path, arena, world_map = mut.load_world(NavigationScenario())  # the arena, its own start
    assert world_map is None
    assert path.name == "room.yaml" and arena.start.x == -2.2
