"""``python -m drake_sim.walle``: options, JSON report and exit codes (DESIGN.md, Wall-E)."""

import json
import subprocess
import sys

import pytest
import yaml

import drake_sim.walle as mut
from drake_sim.base import cli
from drake_sim.robots.walle import default_robot_file
from tests.cli_helpers import assert_bad_input
from tests.meshcat_html import scene_paths
from tests.walle_course_helpers import REPORT_KEYS

TYPES = {
    "fell": bool,
    "time_upright_s": float,
    "max_abs_pitch_deg": float,
    "course_fraction": float,
    "laps": int,
    "mean_line_offset_m": float,
    "max_line_offset_m": float,
    "sim_time_s": float,
    "wall_time_s": float,
    "real_time_factor": float,
}


def _main(*args):
    return cli.run(mut.main, ["--headless", *args])


def test_headless_follow_report(tmp_path):
    report_file = tmp_path / "out" / "report.json"
    code = _main("--mode", "follow", "--duration", "2", "--seed", "3", "--report", str(report_file))
    assert code == 0
    report = json.loads(report_file.read_text())
    assert report.keys() >= REPORT_KEYS
    for key, kind in TYPES.items():
        assert type(report[key]) is kind, key
    assert report["lap_time_s"] is None  # Not there yet.
    assert report["sim_time_s"] == pytest.approx(2.0)
    assert report["seed"] == 3 and report["mode"] == "follow"
    assert 0.05 < report["course_fraction"] < 0.2  # About 0.5 m of the 6.1 m oval.
    assert report["max_line_offset_m"] < 0.01


def test_a_fall_exits_with_1(tmp_path, capsys):
    push = "walle.pushes=[{time: 0.2, force: [40.0, 0.0, 0.0], duration: 0.3}]"
    report_file = tmp_path / "report.json"
    code = _main("--mode", "balance", "--set", push, "--report", str(report_file))
    assert code == 1
    assert "fell" in capsys.readouterr().err
    assert json.loads(report_file.read_text())["fell"] is True


def _bad_course(tmp_path, text):
    path = tmp_path / "course.yaml"
    path.write_text(text)
    return ["--course", str(path)]


def _bad_robot(tmp_path):
    data = yaml.safe_load(default_robot_file().read_text())
    data["wheel"]["radius"] = -0.05
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(data))
    return ["--robot", str(path)]


BAD_INPUTS = {
    "open loop marked closed": (
        lambda p: _bad_course(p, "closed: true\nsegments: [{straight: 1.0}]\n"),
        "'closed' is true",
    ),
    "zero radius": (
        lambda p: _bad_course(p, "segments: [{arc: {radius: 0.0, angle: 90}}]\n"),
        "radius",
    ),
    "unknown course key": (
        lambda p: _bad_course(p, "segments: [{straight: 1.0}]\nlanes: 2\n"),
        "unknown key 'lanes'",
    ),
    "NaN": (lambda p: _bad_course(p, "segments: [{straight: .nan}]\n"), "finite"),
    "bad robot": (_bad_robot, "wheel.radius"),
    "unknown --set key": (lambda p: ["--set", "speed=0.2"], "unknown key 'speed'"),
    "bad mode": (lambda p: ["--mode", "fly"], "--mode"),
    "bad duration": (lambda p: ["--duration", "-1"], "--duration"),
    "missing course": (lambda p: ["--course", str(p / "none.yaml")], "course file not found"),
    "teleop headless": (lambda p: ["--teleop"], "--teleop"),
}


@pytest.mark.parametrize("case", BAD_INPUTS, ids=list(BAD_INPUTS))
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, case):
    make_args, needle = BAD_INPUTS[case]
    assert _main(*make_args(tmp_path)) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0], captured.err
    assert lines[0].startswith("error: ")


def test_entry_point_runs_as_a_module(tmp_path):
    """The real command line: a bad course is one stderr line and exit code 2."""
    course = tmp_path / "course.yaml"
    course.write_text("closed: true\nsegments: [{straight: 1.0}]\n")
    result = subprocess.run(
        [sys.executable, "-m", "drake_sim.walle", "--headless", "--course", str(course)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert_bad_input(result, "'closed' is true")


def test_record_writes_a_replay_of_the_course(tmp_path):
    html = tmp_path / "replay.html"
    assert _main("--mode", "follow", "--duration", "0.5", "--record", str(html)) == 0
    paths = scene_paths(html.read_text())
    assert any("walle/base_link" in p for p in paths)
    assert any("course_floor" in p for p in paths)
