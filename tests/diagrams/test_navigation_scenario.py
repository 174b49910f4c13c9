import pytest

import diagrams.navigation_scenario as mut
from drake_sim.base.config import load_checked
from drake_sim.base.errors import ConfigError
from drake_sim.systems.estimation.amcl import default_amcl_config_file, load_amcl_config
from drake_sim.worlds.arena import BoxSpec, load_arena
from tests import navigation_helpers as nh


def test_the_shipped_scenario_loads_with_the_tuned_amcl():
    scenario = load(
        mut.NavigationScenario, mut.check_navigation_scenario, mut.default_scenario_file()
    )
    assert mut.config_path(scenario.arena).is_file()
    assert scenario.amcl == load_amcl_config(default_amcl_config_file())
    assert scenario.extra_obstacles == []


@pytest.mark.parametrize(
    "text, needle",
    [
        ("colour: red\n", "colour"),
        ("amcl: {min_particles: -1}\n", "amcl.min_particles"),
        ("navigator: {costmap: {robot_radius: -0.2}}\n", "robot_radius"),
        ("lidar: {samples: 0}\n", "samples"),
        ("goal_time_factor: 0\n", "goal_time_factor"),
        ("plant: {time_step: 0}\n", "time_step"),
        ("random_seed: -1\n", "random_seed"),
    ],
)
def test_bad_values_name_the_file_and_key(tmp_path, text, needle):
    path = tmp_path / "scenario.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=needle):
        load(mut.NavigationScenario, mut.check_navigation_scenario, path)


def test_extra_obstacles_join_the_world_and_are_checked():
    arena = load_arena(nh.arena_file("room"))
    scenario = mut.NavigationScenario()
    assert mut.world_arena(scenario, arena) is arena
    scenario.extra_obstacles = [
        mut.ExtraObstacle(box=BoxSpec(size=[0.3, 0.3, 0.3], position=[0.5, 0.0]))
    ]
    world = mut.world_arena(scenario, arena)
    assert len(world.obstacles) == len(arena.obstacles) + 1
    assert world.obstacles[-1].name == "extra_0"
    scenario.extra_obstacles[0].box.position = [9.0, 0.0]
    with pytest.raises(ConfigError, match="extra_obstacles"):
        mut.world_arena(scenario, arena)


def load(schema, check, filename):
    """The scenario file, as the app's recipe loads it (``load_checked``)."""
    return load_checked(schema, filename, check, what="scenario file")
