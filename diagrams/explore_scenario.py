"""Typed scenario for exploring an unknown place with the lidar robot: a navigation scenario
(the world, the robot's sensors and odometry, the navigator, the live SLAM) plus how frontiers
are chosen and how long the run may take. Values live in ``config/explore_scenario.yaml``."""

import dataclasses as dc
from pathlib import Path

from diagrams.navigation_scenario import (
    NavigationScenario,
    check_navigation_scenario,
    load_navigation_scenario,
)
from drake_sim.base.checks import require_positive
from drake_sim.base.resources import config_dir
from drake_sim.navigation.frontiers import FrontierConfig, check_frontier_config


@dc.dataclass
class ExploreScenario(NavigationScenario):
    """The lidar robot mapping a place by itself, from frontier to frontier."""

    exploration: FrontierConfig = dc.field(default_factory=FrontierConfig)
    time_limit: float = 600.0  # s of simulated time at most


def check_explore_scenario(scenario: ExploreScenario, where: str = "scenario") -> ExploreScenario:
    """Returns ``scenario`` if valid; raises ``ConfigError`` naming ``where`` and the key."""
    check_navigation_scenario(scenario, where)
    check_frontier_config(scenario.exploration, f"{where}: exploration")
    require_positive(where, [("time_limit", scenario.time_limit)])
    return scenario


def default_scenario_file() -> Path:
    """Returns ``config/explore_scenario.yaml``."""
    return config_dir() / "explore_scenario.yaml"


def load_explore_scenario(path, overrides=()) -> ExploreScenario:
    """``load_navigation_scenario`` for this schema (parameter files included)."""
    return load_navigation_scenario(
        path, overrides, schema=ExploreScenario, check=check_explore_scenario
    )
