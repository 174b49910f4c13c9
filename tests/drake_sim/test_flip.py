"""``python -m drake_sim.flip``: options, JSON report and exit codes (DESIGN.md)."""

import json
import subprocess
import sys

import pytest

import drake_sim.flip as mut
from tests.cli_helpers import assert_bad_input, edited_robot_file, run_module
from tests.meshcat_html import scene_paths

REPORT_KEYS = {
    "flips",
    "max_lateral_deviation_m",
    "travel_extent_m",
    "sim_time_s",
    "wall_time_s",
    "real_time_factor",
    "odometry_error_m",
}


def _run_process(*args):
    return subprocess.run(
        [sys.executable, "-m", "drake_sim.flip", *args], capture_output=True, text=True, timeout=600
    )


def _run(*args):
    return run_module("drake_sim.flip", *args)


def test_headless_report_and_record(tmp_path):
    report_file, html = tmp_path / "out" / "report.json", tmp_path / "replay.html"
    bare = tmp_path / "bare.yaml"
    bare.write_text("scene: {world: ''}\n")
    code = mut.main(
        [
            "--headless",
            "--duration",
            "3",
            "--config",
            str(bare),
            "--seed",
            "3",
            "--report",
            str(report_file),
            "--record",
            str(html),
        ]
    )
    assert code == 0
    report = json.loads(report_file.read_text())
    assert report.keys() >= REPORT_KEYS
    assert report["sim_time_s"] == pytest.approx(3.0)
    assert report["seed"] == 3
    assert report["flips"] >= 1
    paths = scene_paths(html.read_text())
    assert any("ddrive/base_link" in p for p in paths)
    assert any(p.startswith("/odometry/") for p in paths)


def test_seed_changes_only_the_noise(tmp_path):
    bare = tmp_path / "bare.yaml"
    bare.write_text("scene: {world: ''}\n")
    reports = []
    for seed in ("1", "1", "2"):
        out = tmp_path / f"r{len(reports)}.json"
        assert (
            mut.main(
                [
                    "--headless",
                    "--duration",
                    "1",
                    "--config",
                    str(bare),
                    "--seed",
                    seed,
                    "--report",
                    str(out),
                ]
            )
            == 0
        )
        reports.append(json.loads(out.read_text()))
    assert reports[0]["odometry_error_m"] == reports[1]["odometry_error_m"]
    assert reports[0]["odometry_error_m"] != reports[2]["odometry_error_m"]


def test_set_overrides_a_value(tmp_path):
    out = tmp_path / "r.json"
    code = mut.main(
        [
            "--headless",
            "--duration",
            "1.5",
            "--set",
            "scene.world=''",
            "--set",
            "flip.drive_time=3.0",
            "--report",
            str(out),
        ]
    )
    assert code == 0
    assert json.loads(out.read_text())["flips"] == 0  # Still driving after 1.5 s.


@pytest.mark.parametrize(
    "make_args, needle",
    [
        (
            lambda p: ["--robot", str(edited_robot_file(p, lambda d: d["wheel"].pop("radius")))],
            "wheel.radius",
        ),
        (
            lambda p: ["--robot", str(edited_robot_file(p, lambda d: d["body"].update(length=0)))],
            "body.length",
        ),
        (
            lambda p: ["--robot", str(edited_robot_file(p, lambda d: d["body"].update(mass=-1)))],
            "body.mass",
        ),
        (
            lambda p: [
                "--robot",
                str(edited_robot_file(p, lambda d: d["motor"].update(max_torque=".nan"))),
            ],
            "max_torque",
        ),
        (
            lambda p: [
                "--robot",
                str(edited_robot_file(p, lambda d: d["wheel"].update(width=float("nan")))),
            ],
            "wheel.width",
        ),
        (lambda p: ["--duration", "-2"], "duration"),
        (lambda p: ["--seed", "-1"], "seed"),
        (lambda p: ["--teleop"], "teleop"),
        (lambda p: ["--set", "flip.drive_speed=fast"], "drive_speed"),
        (lambda p: ["--set", "flip.drive_speed=-1"], "drive_speed"),
        (lambda p: ["--set", "flip.no_such_key=1"], "no_such_key"),
    ],
    ids=[
        "missing-key",
        "zero",
        "negative",
        "nan-string",
        "nan",
        "negative-duration",
        "negative-seed",
        "teleop-headless",
        "not-a-number",
        "negative-speed",
        "unknown-key",
    ],
)
def test_bad_input_exits_2_with_one_line(tmp_path, make_args, needle):
    assert_bad_input(_run("--headless", *make_args(tmp_path)), needle)


@pytest.mark.parametrize(
    "text", ["scene: [1, 2", "flip: {drive_speed: .nan}", "imu: {rate: 0}", "nothing: 1"]
)
def test_bad_scenario_file_exits_2(tmp_path, text):
    path = tmp_path / "flip.yaml"
    path.write_text(text)
    assert_bad_input(_run("--headless", "--config", str(path)), str(path))


def test_runs_as_a_module_and_exits_0(tmp_path):
    out = tmp_path / "r.json"
    result = _run_process(
        "--headless", "--duration", "0.5", "--set", "scene.world=''", "--report", str(out)
    )
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert "flips 0" in result.stdout
    assert json.loads(out.read_text())["finite"] is True


def _latin1_file(tmp_path, text="# réglage par défaut\nflip: {drive_speed: 0.5}\n"):
    path = tmp_path / "latin1.yaml"
    path.write_bytes(text.encode("latin-1"))  # "é" is one byte, not UTF-8
    return path


def _file(tmp_path, text=""):
    path = tmp_path / "file.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "make_args, needle",
    [
        (lambda p: ["--robot", str(_latin1_file(p))], "not UTF-8"),
        (lambda p: ["--config", str(_latin1_file(p))], "not UTF-8"),
        (lambda p: ["--config", str(_file(p))], "scenario file is empty"),
        (lambda p: ["--config", str(_file(p, "\n  \n"))], "scenario file is empty"),
        (lambda p: ["--config", str(p)], "scenario file is a directory"),
        (lambda p: ["--robot", str(p)], "robot file is a directory"),
        (lambda p: ["--robot", str(p / "none.yaml")], "robot file not found"),
        (lambda p: ["--report", str(p)], "report is a directory"),
        (lambda p: ["--report", f"{_file(p)}/report.json"], "file.yaml is not a directory"),
        (lambda p: ["--record", f"{_file(p)}/out/replay.html"], "file.yaml is not a directory"),
    ],
    ids=[
        "robot-not-utf8",
        "config-not-utf8",
        "config-empty",
        "config-blank",
        "config-directory",
        "robot-directory",
        "robot-missing",
        "report-directory",
        "report-parent-is-a-file",
        "record-parent-is-a-file",
    ],
)
def test_bad_file_is_one_line_and_exit_2_before_the_run(tmp_path, make_args, needle):
    result = _run("--headless", "--duration", "30", *make_args(tmp_path))
    assert_bad_input(result, needle)
    assert result.stdout == ""  # no summary: nothing was simulated
