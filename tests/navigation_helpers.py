"""Shared by the navigation tests: maps saved from the arenas' ground truth (what a perfect
mapping run would save) or by a mapping run, the robot and the scenario."""

import json

import numpy as np

from drake_sim.base.map_files import OccupancyMap, load_map, save_map
from drake_sim.base.resources import config_dir
from drake_sim.robots.turtlebot3 import default_turtlebot3_file
from drake_sim.robots.turtlebot3_params import load_turtlebot3_params
from drake_sim.runs.mapping import RECIPE as MAPPING
from drake_sim.runs.navigate import RECIPE as NAVIGATE
from drake_sim.worlds.arena import arena_grid, load_arena


def robot():
    return load_turtlebot3_params(default_turtlebot3_file())


def scenario():
    return NAVIGATE.scenario.read(None)


def arena_file(name: str):
    return config_dir() / "arenas" / f"{name}.yaml"


def saved_truth_map(name: str, folder) -> tuple[OccupancyMap, object]:
    """The arena ``name``'s ground truth at the lidar's height, saved as map_server files in
    ``folder`` and loaded back; returns the map and its ``.yaml`` path."""
    truth = arena_grid(load_arena(arena_file(name)), 0.05, height=robot().scan_height)
    _, yaml_file = save_map(truth, folder / name)
    return load_map(yaml_file), yaml_file


def saved_slam_map(name: str, folder, seed: int = 0) -> tuple[OccupancyMap, object]:
    """The map that mapping the arena ``name`` along its default route saves (as
    ``python -m drake_sim.mapping`` does), loaded back; returns the map and its ``.yaml`` path."""
    run = MAPPING.start(overrides=[f"arena=arenas/{name}.yaml"], seed=seed)
    assert run.run(run.default_duration()) == "route_done"
    _, yaml_file = run.save_map(folder / name)
    return load_map(yaml_file), yaml_file


def pose_deg(x: float, y: float, yaw_deg: float) -> np.ndarray:
    return np.array([x, y, np.radians(yaw_deg)])


def navigate_to_goals(args, folder, *, position_m=0.05, yaw_deg=5.0) -> dict:
    """Runs ``python -m drake_sim.navigate --headless ARGS`` in this process, asserts every
    goal was reached with no collision, within ``position_m`` and ``yaw_deg`` of the truth
    (None: not asserted), and returns the report."""
    import drake_sim.navigate as navigate  # noqa: PLC0415 (the app, only for these tests)
    from drake_sim.base import cli  # noqa: PLC0415

    report_file = folder / "report.json"
    code = cli.run(navigate.main, ["--headless", *args, "--report", str(report_file)])
    assert code == 0
    report = json.loads(report_file.read_text())
    assert report["reached_all"] and report["collisions"] == 0
    for goal in report["goals"]:
        assert position_m is None or goal["position_error_m"] < position_m, goal
        assert yaw_deg is None or goal["yaw_error_deg"] < yaw_deg, goal
    return report
