"""The lidar robot's mapping run (drake_sim.runs.mapping): the route driven to its end, the
report that scores the map and the poses, the map files, the recipe's route, and (slow) the
acceptance runs on every arena."""

import math

import numpy as np
import pytest
from pydrake.geometry import Meshcat

import drake_sim.runs.mapping as mut
from diagrams.mapping_scenario import MappingScenario
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from drake_sim.robots.turtlebot3 import default_turtlebot3_file
from drake_sim.robots.turtlebot3_params import load_turtlebot3_params
from drake_sim.worlds.arena import load_arena, shipped_arenas
from drake_sim.worlds.route import Route, check_route, default_route_file, load_route


@pytest.fixture(scope="module")
def finished():
    """The room, a 2.8 m route with a turn, driven to its end."""
    robot = load_turtlebot3_params(default_turtlebot3_file())
    arena = load_arena(config_dir() / "arenas" / "room.yaml")
    waypoints = [[0.0, -1.8], [0.0, -1.2]]
    dut = mut.MappingRun(MappingScenario(random_seed=4), robot, arena, waypoints)
    assert dut.run(dut.default_duration()) == "route_done"
    return dut


def test_route_length():
    assert mut.route_length([0, 0, 1.0], [[3, 4], [3, 0]]) == pytest.approx(9.0)
    assert mut.route_length([1, 1], []) == 0.0


def test_a_run_ends_at_the_route_end_with_poses_per_scan(finished):
    paths = finished.trajectories()
    n = len(paths["time"])
    assert n == finished.report().scans and n > 30
    assert np.allclose(np.diff(paths["time"]), 1.0 / finished.scenario.lidar.rate)
    assert paths["truth"][-1, :2] == pytest.approx([0.0, -1.2], abs=0.06)
    # The SLAM follows the truth closely; the odometry drifts away from it.
    slam_error = np.hypot(*(paths["slam"][:, :2] - paths["truth"][:, :2]).T)
    assert slam_error.max() < 0.05
    assert finished.route_fraction() == 1.0


def test_the_report_scores_the_map_and_the_poses(finished, tmp_path):
    pgm, yaml_file = finished.save_map(tmp_path / "maps" / "room")
    report = finished.report()
    assert report.end == "route_done" and report.seed == 4
    assert report.map_files == [str(pgm), str(yaml_file)]
    assert 0.5 < report.map_iou < 0.95  # what it saw is right, but it saw part of the room
    assert 0.2 < report.known_fraction < 0.95  # part of the room
    assert report.pose_rmse_m < 0.03 and report.final_pose_error_m < 0.05
    assert report.final_yaw_error_deg < 2.0
    assert report.odometry_final_error_m > 0  # odometry drift is real
    assert report.sim_time_s == pytest.approx(finished.context.get_time())
    assert report.real_time_factor > 0 and math.isfinite(report.wall_time_s)
    data = report.to_dict()
    assert data["scans"] == report.scans and "route_fraction" in data


def test_the_default_duration_covers_the_route_at_cruise_speed(finished):
    length = mut.route_length(finished.arena.start_pose(), finished.waypoints)
    scenario = finished.scenario
    expected = length / scenario.route_follower.speed * scenario.duration_factor
    assert finished.default_duration() == pytest.approx(expected + scenario.duration_margin)


def test_a_completed_run_saves_its_map_at_out(finished, tmp_path):
    finished.out = tmp_path / "room"
    report = finished.finish()
    assert finished.files == (tmp_path / "room.pgm", tmp_path / "room.yaml")
    assert all(f.is_file() for f in finished.files)
    assert report.map_files == [str(f) for f in finished.files]
    assert finished.error(report) is None
    assert "ended by route_done" in finished.summary(report)


def test_an_early_end_keeps_the_map_there_and_saves_a_partial_one(tmp_path, capsys):
    (tmp_path / "room.yaml").write_text("kept\n")
    run = mut.RECIPE.start(seed=2, out=tmp_path / "room")
    assert run.seed == 2 and run.scenario.random_seed == 2
    assert run.run(1.0) == "duration"
    report = run.finish()
    assert (tmp_path / "room.yaml").read_text() == "kept\n"
    assert run.files[1] == tmp_path / "room.partial.yaml" and run.files[1].is_file()
    assert "room.yaml is kept as it was" in capsys.readouterr().out
    assert "route was not completed" in run.error(report)


def test_the_route_is_the_scenario_s_or_the_arena_s_default(tmp_path):
    arena_file = config_dir() / "arenas" / "room.yaml"
    assert mut.route_file(MappingScenario(), arena_file) == default_route_file(arena_file)
    route = tmp_path / "route.yaml"
    assert mut.route_file(MappingScenario(route=str(route)), arena_file) == route
    with pytest.raises(ConfigError, match="no default route"):
        mut.route_file(MappingScenario(), tmp_path / "nowhere.yaml")


def test_teleop_drives_no_route():
    run = mut.RECIPE.start(teleop=True, meshcat=Meshcat())  # the keys are the page's
    assert run.teleop and len(run.waypoints) == 0 and run.route_fraction() == 1.0
    assert run.check() is None
    assert run.default_duration(viewer=True) == math.inf
    assert run.default_duration() == run.scenario.duration_margin


# Not shipped: a long hall split by an inner wall, driven round the wall's free end.
UNSEEN_ARENA = """
size: [8.0, 4.0]
wall: {height: 0.35, thickness: 0.1}
obstacles:
  - {box: {size: [0.5, 0.5, 0.3], position: [1.8, 0.4], yaw: 20}}
  - {cylinder: {radius: 0.2, height: 0.3, position: [-2.0, -0.6]}}
  - {wall: {from: [0.0, -2.0], to: [0.0, 0.2], thickness: 0.08}}
start: {x: -3.2, y: -1.3, yaw: 90}
"""
UNSEEN_ROUTE = [[-3.2, 1.3], [0.0, 1.3], [3.2, 1.3], [3.2, -1.3], [0.6, -1.3], [0.6, -0.4]]


def _accepted(report) -> None:
    """The issue's acceptance for a whole arena mapped along its route."""
    assert report.end == "route_done"
    assert report.map_iou >= 0.9
    assert report.known_fraction >= 0.95
    assert report.pose_rmse_m <= 0.05
    assert 3 * report.pose_rmse_m <= report.odometry_final_error_m


@pytest.mark.slow
@pytest.mark.parametrize("arena_file", shipped_arenas(), ids=lambda p: p.stem)
def test_every_shipped_arena_is_mapped_along_its_default_route(arena_file):
    robot = load_turtlebot3_params(default_turtlebot3_file())
    arena = load_arena(arena_file)
    waypoints = load_route(default_route_file(arena_file), arena).waypoints
    run = mut.MappingRun(MappingScenario(random_seed=1), robot, arena, waypoints)
    run.run(run.default_duration())
    _accepted(run.report())


@pytest.mark.slow
def test_an_unseen_arena_is_mapped_too(tmp_path):
    path = tmp_path / "hall.yaml"
    path.write_text(UNSEEN_ARENA)
    arena = load_arena(path)
    robot = load_turtlebot3_params(default_turtlebot3_file())
    waypoints = check_route(Route(waypoints=UNSEEN_ROUTE), arena, "hall route").waypoints
    run = mut.MappingRun(MappingScenario(random_seed=5), robot, arena, waypoints)
    run.run(run.default_duration())
    _accepted(run.report())
