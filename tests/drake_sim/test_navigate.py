"""``python -m drake_sim.navigate``: options, JSON report and exit codes (DESIGN.md)."""

import json
from pathlib import Path

import pytest

import drake_sim.navigate as mut
import drake_sim.runs.navigate as navigate_app
from drake_sim.base import cli
from drake_sim.base.mcap_files import McapLogReader
from tests import navigation_helpers as nh
from tests.cli_helpers import assert_bad_input, run_module

REPORT_KEYS = {
    "goals",
    "reached_all",
    "collisions",
    "min_clearance_m",
    "localization_error_mean_m",
    "localization_error_max_m",
    "converged_after_s",
    "sim_time_s",
    "wall_time_s",
    "real_time_factor",
}
GOAL_KEYS = {"reached", "position_error_m", "yaw_error_deg", "time_s", "path_length_m"}


@pytest.fixture(scope="module")
def room_map(tmp_path_factory):
    return nh.saved_truth_map("room", tmp_path_factory.mktemp("maps"))[1]


def test_one_goal_is_reached_and_reported(room_map, tmp_path, capsys):
    report_file = tmp_path / "report.json"
    code = cli.run(
        mut.main,
        [
            "--headless",
            "--map",
            str(room_map),
            "--goal",
            "0",
            "-1",
            "90",
            "--report",
            str(report_file),
            "--seed",
            "3",
        ],
    )
    assert code == 0, capsys.readouterr().err
    report = json.loads(report_file.read_text())
    assert report.keys() >= REPORT_KEYS and report["reached_all"] is True
    assert report["goals"][0].keys() >= GOAL_KEYS
    assert report["goals"][0]["position_error_m"] < 0.05
    assert report["collisions"] == 0 and report["seed"] == 3
    assert "1 of 1 goals reached" in capsys.readouterr().out


def test_a_run_is_recorded_as_a_ros2_log_with_the_map_and_the_estimate(room_map, tmp_path):
    log = tmp_path / "nav.mcap"
    args = ["--headless", "--map", str(room_map), "--goal", "0", "-1", "90"]
    assert cli.run(mut.main, [*args, "--record-log", str(log), "--seed", "3"]) == 0
    reader = McapLogReader(log)
    reader.open()
    try:
        counts = {c.topic: c.msgcount for c in reader.connections}
        assert counts["/map"] == 1 and counts["/tf_static"] == 1  # the saved map, latched
        scans = counts["/scan"]  # four odometry messages a scan, the last scan's included
        assert scans > 10 and counts["/odom"] == counts["/tf"]
        assert 4 * (scans - 1) < counts["/odom"] <= 4 * scans
        tf = next(c for c in reader.connections if c.topic == "/tf")
        _, _, raw = next(iter(reader.messages([tf])))
        frames = [t.child_frame_id for t in reader.deserialize(raw, tf.msgtype).transforms]
        assert frames == ["base_footprint", "odom"]  # odom -> base, map -> odom (AMCL's)
    finally:
        reader.close()


def _run(*args):
    return run_module("drake_sim.navigate", "--headless", *args)


def test_an_unreachable_goal_exits_1_and_says_which_and_why(room_map):
    result = _run("--map", str(room_map), "--goal", "0.3", "1.4", "0")
    assert result.returncode == 1, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "goal 0 (0.3, 1.4) not reached" in lines[0]


def test_bad_map_files_are_one_line_and_exit_2(room_map, tmp_path):
    assert_bad_input(_run("--map", str(tmp_path / "nope.yaml")), "nope.yaml")
    malformed = tmp_path / "malformed.yaml"
    malformed.write_text("image: [unclosed\n")
    assert_bad_input(_run("--map", str(malformed)), "malformed.yaml")
    pgm = room_map.with_suffix(".pgm")
    (tmp_path / "room.pgm").write_bytes(pgm.read_bytes()[:100])
    (tmp_path / "room.yaml").write_text(room_map.read_text())
    assert_bad_input(_run("--map", str(tmp_path / "room.yaml")), "room.pgm")


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--goal", "40", "0", "0"], "outside the map"),
        (["--goal", "nan", "0", "0"], "--goal"),
        (["--initial-pose", "0", "inf", "0"], "--initial-pose"),
        (["--set", "amcl.max_particles=-5"], "max_particles"),
        (["--set", "navigator.costmap.inflation_radius=nan"], "inflation_radius"),
        (["--goals", "missing.yaml"], "missing.yaml"),
        (["--goal", "1", "2"], "--goal"),
    ],
)
def test_bad_options_are_one_line_and_exit_2(room_map, args, needle):
    assert_bad_input(_run("--map", str(room_map), *args), needle)


def test_a_goals_file_with_nan_is_bad_input(room_map, tmp_path):
    goals = tmp_path / "goals.yaml"
    goals.write_text("goals: [{x: .nan, y: 0.0, yaw: 0}]\n")
    assert_bad_input(_run("--map", str(room_map), "--goals", str(goals)), "goals")


class _FakePanel:
    """Presses "2D Nav Goal" once, at (-1.0, -1.8) heading east, then nothing."""

    def __init__(self, **kwargs):
        self.presses = [[("goal", nh.pose_deg(-1.0, -1.8, 0.0))]]

    def poll(self):
        return self.presses.pop() if self.presses else []

    def remove(self):
        pass


def test_goals_from_the_page_with_a_viewer(room_map, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(navigate_app, "GoalPanel", _FakePanel)
    # The page's goals are under test, not the pacing: simulate flat out.
    flat_out = navigate_app.NavigateRun
    monkeypatch.setattr(
        navigate_app, "NavigateRun", lambda *a, **k: flat_out(*a, **{**k, "realtime": False})
    )
    report_file = tmp_path / "report.json"
    args = ["--map", str(room_map), "--duration", "15", "--report", str(report_file)]
    assert cli.run(mut.main, args) == 0
    report = json.loads(report_file.read_text())
    (goal,) = report["goals"]
    assert goal["reached"] and goal["position_error_m"] < 0.05
    assert "1 goals given in the page, 1 reached" in capsys.readouterr().out


def test_a_world_from_a_map_alone(room_map, tmp_path):
    """The room's saved map simulated as walls (``--world``), the robot placed by ``--start``:
    no arena file is read."""
    args = ["--map", str(room_map), "--world", str(room_map), "--start", "-2.0", "-1.5", "0"]
    nh.navigate_to_goals([*args, "--goal", "0", "-1", "90"], tmp_path, yaw_deg=None)


def test_a_map_of_another_place_is_one_line_and_exit_2(tmp_path):
    _, maze_map = nh.saved_truth_map("maze", tmp_path)
    result = _run("--map", str(maze_map), "--goal", "0", "-1", "90")
    assert_bad_input(result, "the map and the arena do not agree")
    assert "give the robot's start with --start" in result.stderr  # no arena named: the way on
    named = _run(
        "--map", str(maze_map), "--arena", str(nh.arena_file("room")), "--goal", "0", "-1", "90"
    )
    assert_bad_input(named, "the map and the arena do not agree")
    assert "no arena named" not in named.stderr


def test_with_no_arena_named_the_map_is_the_world(tmp_path):
    """``--map`` and ``--start`` with no arena: the robot drives in the map's own world (the
    maze's map, which the default room arena does not match)."""
    _, maze_map = nh.saved_truth_map("maze", tmp_path)
    args = ["--map", str(maze_map), "--start", "-2.65", "-2.4", "90"]
    args += ["--goal", "-2.65", "-1.4", "90"]
    nh.navigate_to_goals(args, tmp_path, position_m=None, yaw_deg=None)


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--arena", "ROOM", "--start", "0", "0", "0"], "--start places the robot"),
        (["--world", "MAP"], "give the robot's start with --start"),
        (["--world", "MAP", "--start", "40", "0", "0"], "outside the map"),
        (["--world", "MAP", "--start", "nan", "0", "0"], "must be finite"),
    ],
)
def test_bad_world_options_are_one_line_and_exit_2(room_map, args, needle):
    names = {"MAP": str(room_map), "ROOM": str(nh.arena_file("room"))}
    args = [names.get(a, a) for a in args]
    assert_bad_input(_run("--map", str(room_map), "--goal", "0", "-1", "0", *args), needle)


def test_with_no_map_the_robot_maps_as_it_goes(tmp_path):
    """No ``--map`` (as BARN's move_base runs): the live SLAM localises, the costmap fills from
    the lidar, the goal is reached with the true error in tolerance."""
    report = nh.navigate_to_goals(["--goal", "0", "-1", "90"], tmp_path)
    assert report["localization_error_max_m"] < 0.05


@pytest.mark.parametrize("flag", [["--initial-pose", "0", "0", "0"], ["--global-localization"]])
def test_amcl_flags_without_a_map_are_one_line_and_exit_2(flag):
    assert_bad_input(_run("--goal", "0", "-1", "90", *flag), "give the map it localises on")


def test_teb_as_the_local_planner_reaches_the_goal(room_map, tmp_path):
    args = ["--map", str(room_map), "--goal", "2.0", "-0.1", "0"]
    nh.navigate_to_goals([*args, "--set", "navigator.local_planner=teb"], tmp_path)


REAL_ROS = Path(__file__).resolve().parents[3] / "shared" / "real_ros"


@pytest.mark.parametrize("params", ["nav2_humble/nav2_params.yaml", "nav2_main/nav2_params.yaml"])
def test_real_nav2_params_drive_in_the_turtlebot3_world(params, tmp_path):
    """nav2's own files as they are (DWB at 20 Hz, a 0.22 m robot radius: the gaps between the
    world's pillars are narrow for it) on the TurtleBot3 world's saved map: the goal past the
    pillars is reached within nav2's tolerances (0.25 m, 0.25 rad) there."""
    world, params = REAL_ROS / "maps" / "turtlebot3_main" / "map.yaml", REAL_ROS / "params" / params
    if not (world.is_file() and params.is_file()):
        pytest.skip(f"no {world} or {params} (third-party files beside the checkout)")
    args = ["--map", str(world), "--start", "-2.0", "-0.5", "0", "--goal", "0.5", "-1.8", "0"]
    nh.navigate_to_goals([*args, "--params", str(params)], tmp_path, position_m=0.25,
                         yaw_deg=14.3)  # fmt: skip
