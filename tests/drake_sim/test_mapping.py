"""``python -m drake_sim.mapping``: options, map files, JSON report and exit codes (DESIGN.md,
arena, route and goals files)."""

import json

import pytest
import yaml

import drake_sim.mapping as mut
from drake_sim.base import cli
from drake_sim.base.map_files import load_map
from drake_sim.base.resources import config_dir
from drake_sim.systems.estimation.occupancy_grid import occupancy_iou
from tests import navigation_helpers as nh
from tests.cli_helpers import assert_bad_input, run_module

REPORT_KEYS = {
    "map_iou",
    "known_fraction",
    "pose_rmse_m",
    "final_pose_error_m",
    "final_yaw_error_deg",
    "odometry_final_error_m",
    "scans",
    "sim_time_s",
    "wall_time_s",
    "real_time_factor",
}

SHORT_ROUTE = "waypoints: [[-0.6, -1.8], [-0.6, -1.5]]\n"  # In the room, from its start.


def _main(*args):
    return cli.run(mut.main, ["--headless", *args])


def test_a_short_route_maps_saves_and_reports(tmp_path, capsys):
    route = tmp_path / "route.yaml"
    route.write_text(SHORT_ROUTE)
    report_file = tmp_path / "report.json"
    out = tmp_path / "maps" / "room"
    code = _main(
        "--route", str(route), "--out", str(out), "--report", str(report_file), "--seed", "2"
    )
    assert code == 0, capsys.readouterr().err
    report = json.loads(report_file.read_text())
    assert report.keys() >= REPORT_KEYS
    assert report["end"] == "route_done" and report["seed"] == 2
    assert type(report["scans"]) is int and report["scans"] > 20
    assert report["pose_rmse_m"] < 0.05
    assert 0.2 < report["known_fraction"] < 0.95  # a short route sees part of the room
    assert report["map_files"] == [str(out) + ".pgm", str(out) + ".yaml"]
    saved = load_map(str(out) + ".yaml")
    assert saved.resolution == pytest.approx(0.05)
    assert saved.occupied().sum() > 50 and saved.free().sum() > 500
    assert "map IoU" in capsys.readouterr().out


def test_a_recorded_log_maps_back_to_the_same_map(tmp_path, capsys):
    """--record-log writes the run as a ROS 2 MCAP; --log on it draws the map the live SLAM
    drew (the issue's acceptance: IoU at least 0.98)."""
    route = tmp_path / "route.yaml"
    route.write_text(SHORT_ROUTE)
    log, live, again = tmp_path / "run.mcap", tmp_path / "live.json", tmp_path / "again.json"
    code = _main(
        "--route", str(route), "--out", str(tmp_path / "live"), "--record-log", str(log),
        "--report", str(live), "--seed", "2",
    )  # fmt: skip
    assert code == 0, capsys.readouterr().err
    assert f"ROS 2 log: {log}" in capsys.readouterr().out
    code = _main("--log", str(log), "--out", str(tmp_path / "again"), "--report", str(again))
    assert code == 0, capsys.readouterr().err
    live, again = json.loads(live.read_text()), json.loads(again.read_text())
    assert (again["scan_topic"], again["odom_topic"]) == ("/scan", "/odom")
    assert again["scans"] == live["scans"] and again["rejected_matches"] == 0
    lidar = nh.robot().lidar
    assert again["laser_pose"] == pytest.approx([lidar.x, lidar.y, 0.0], abs=1e-6)
    drawn = load_map(tmp_path / "again.yaml")
    assert occupancy_iou(drawn, load_map(tmp_path / "live.yaml"), tolerance_cells=1) >= 0.98


def test_a_log_is_recorded_as_mcap_and_not_while_mapping_a_log(tmp_path):
    assert_bad_input(_run("--record-log", str(tmp_path / "run.bag")), "FILE.mcap")
    log = tmp_path / "x.mcap"
    log.write_bytes(b"")
    result = _run("--log", str(log), "--record-log", str(tmp_path / "y.mcap"))
    assert_bad_input(result, "--record-log is for a simulated run")


def _run(*args, cwd=None):
    return run_module("drake_sim.mapping", "--headless", *args, cwd=cwd)


def _arena_file(tmp_path, edit):
    data = yaml.safe_load((config_dir() / "arenas" / "room.yaml").read_text())
    edit(data)
    path = tmp_path / "arena.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _obstacle_outside(data):
    data["obstacles"].append({"box": {"size": [0.4, 0.4, 0.3], "position": [9.0, 0.0]}})


def _negative_size(data):
    data["size"] = [-6.0, 5.0]


def _unknown_key(data):
    data["colour"] = "red"


def _nan(data):
    data["wall"]["height"] = float("nan")


def _start_in_obstacle(data):
    box = next(o["box"] for o in data["obstacles"] if "box" in o)
    data["start"] = {"x": box["position"][0], "y": box["position"][1], "yaw": 0}


@pytest.mark.parametrize(
    "edit, needle",
    [
        (_obstacle_outside, "obstacles"),
        (_negative_size, "size"),
        (_unknown_key, "colour"),
        (_nan, "wall.height"),
        (_start_in_obstacle, "start"),
    ],
)
def test_bad_arenas_are_one_line_and_exit_2(tmp_path, edit, needle):
    assert_bad_input(_run("--arena", str(_arena_file(tmp_path, edit))), needle)


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--arena", "missing.yaml"], "missing.yaml"),
        (["--route", "missing.yaml"], "missing.yaml"),
        (["--teleop"], "--teleop"),
        (["--set", "lidar.range_max=0.05"], "range"),
        (["--set", "slam.resolution=-1"], "resolution"),
        (["--seed", "-1"], "--seed"),
    ],
)
def test_bad_options_are_one_line_and_exit_2(args, needle):
    assert_bad_input(_run(*args), needle)


def test_a_route_through_a_wall_is_bad_input(tmp_path):
    route = tmp_path / "route.yaml"
    route.write_text("waypoints: [[-1.2, -1.5], [9.0, 0.0]]\n")
    assert_bad_input(_run("--route", str(route)), "waypoints[1]")


def test_a_map_path_under_a_file_is_bad_input(tmp_path):
    blocker = tmp_path / "file.txt"
    blocker.write_text("not a folder")
    assert_bad_input(_run("--out", str(blocker / "sub" / "map")), "map")


def test_a_route_not_completed_exits_with_1(tmp_path):
    route = tmp_path / "route.yaml"
    route.write_text(SHORT_ROUTE)
    report = tmp_path / "report.json"
    result = _run(
        "--route",
        str(route),
        "--duration",
        "2",
        "--out",
        str(tmp_path / "m"),
        "--report",
        str(report),
    )
    assert result.returncode == 1, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "not completed" in lines[0]
    assert json.loads(report.read_text())["end"] == "duration"
    # The map so far is saved beside where a complete one would go, never in its place.
    assert (tmp_path / "m.partial.pgm").is_file() and (tmp_path / "m.partial.yaml").is_file()
    assert not (tmp_path / "m.yaml").exists()
    assert "partial map" in result.stdout


def test_a_short_route_in_a_world_from_a_map(tmp_path, capsys):
    """The room's saved map simulated as walls (``--world``, ``--start``): the map is scored on
    the world map's known cells, so it compares with the arena's own run."""
    _, room_map = nh.saved_truth_map("room", tmp_path)
    route = tmp_path / "route.yaml"
    route.write_text("waypoints: [[-2.2, -1.8], [-0.6, -1.8], [-0.6, -1.5]]\n")
    report_file = tmp_path / "report.json"
    args = ["--world", str(room_map), "--start", "-2.2", "-1.8", "0", "--route", str(route)]
    code = _main(*args, "--out", str(tmp_path / "out"), "--report", str(report_file))
    assert code == 0, capsys.readouterr().err
    report = json.loads(report_file.read_text())
    assert report["end"] == "route_done" and report["pose_rmse_m"] < 0.05
    assert 0.2 < report["known_fraction"] < 0.95


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--world", "MAP"], "give the robot's start with --start"),
        (["--start", "0", "0", "0"], "--start places the robot in a world from a map"),
        (["--world", "MAP", "--start", "0", "0", "0"], "give --route"),  # no default route
    ],
)
def test_bad_world_options_are_one_line_and_exit_2(tmp_path, args, needle):
    _, room_map = nh.saved_truth_map("room", tmp_path)
    args = [str(room_map) if a == "MAP" else a for a in args]
    assert_bad_input(_run(*args), needle)
