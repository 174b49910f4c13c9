import pytest

import diagrams.explore_scenario as mut
from diagrams.navigation_scenario import NavigationScenario
from drake_sim.base.errors import ConfigError
from drake_sim.navigation.frontiers import FrontierConfig


def test_the_shipped_scenario_is_a_navigation_scenario_with_exploration():
    scenario = mut.load_explore_scenario(mut.default_scenario_file())
    assert isinstance(scenario, NavigationScenario)
    assert isinstance(scenario.exploration, FrontierConfig)
    assert scenario.time_limit == 600.0
    assert scenario.no_map_localization == "slam"
    # A turning Waffle sweeps 0.255 m round its axle: the costmap keeps that clear.
    assert scenario.navigator.costmap.robot_radius >= 0.255


def test_overrides_reach_the_exploration_section(tmp_path):
    scenario = mut.load_explore_scenario(
        mut.default_scenario_file(), ["exploration.gain_scale=2.0", "time_limit=30"]
    )
    assert scenario.exploration.gain_scale == 2.0 and scenario.time_limit == 30.0


@pytest.mark.parametrize(
    "text, needle",
    [
        ("time_limit: 0\n", "time_limit"),
        ("exploration: {replan_period: 0}\n", "replan_period"),
        ("exploration: {clearance: -1}\n", "clearance"),
        ("exploration: {colour: red}\n", "colour"),
        ("navigator: {costmap: {robot_radius: -0.2}}\n", "robot_radius"),
    ],
)
def test_bad_values_name_the_key(tmp_path, text, needle):
    path = tmp_path / "scenario.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=needle):
        mut.load_explore_scenario(path)
