"""``python -m drake_sim.view``: runs, records, and rejects bad input with exit code 2."""

import subprocess
import sys

import pytest

import drake_sim.view as mut
from tests.cli_helpers import assert_bad_input, edited_robot_file
from tests.meshcat_html import scene_paths


def _run(*args, timeout=300):
    return subprocess.run(
        [sys.executable, "-m", "drake_sim.view", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def test_world_view_records_html(tmp_path):
    out = tmp_path / "view.html"
    assert mut.main(["--duration", "0.2", "--record", str(out)]) == 0
    paths = scene_paths(out.read_text())
    assert any(p.startswith("/odometry/") for p in paths)  # the odometry display
    for model in (
        "ddrive/base_link",
        "ddrive/left_wheel",
        "barrier_north_1",
        "cardboard_box_1",
        "traffic_cone_1",
        "trash_can_1",
        "asphalt_ground",
    ):
        assert any(model in p for p in paths), model


def test_view_only_runs_with_sliders(tmp_path):
    out = tmp_path / "model.html"
    assert mut.main(["--view-only", "--duration", "0.1", "--record", str(out)]) == 0
    paths = scene_paths(out.read_text())
    assert any("ddrive/left_wheel" in p for p in paths)
    assert not any("barrier" in p for p in paths)  # the robot alone


@pytest.mark.parametrize(
    "edit, needle",
    [
        (lambda d: d["body"].pop("height"), "body.height"),
        (lambda d: d["wheel"].update(radius=0), "wheel.radius"),
        (lambda d: d["body"].update(mass=-2), "body.mass"),
        (lambda d: d["motor"].update(max_torque="x"), "max_torque"),
        (lambda d: d["wheel"].update(width=float("nan")), "wheel.width"),
    ],
    ids=["missing-key", "zero", "negative", "non-number", "nan"],
)
def test_bad_robot_file_is_one_line_and_exit_2(tmp_path, edit, needle):
    assert_bad_input(
        _run("--robot", str(edited_robot_file(tmp_path, edit)), "--duration", "0.01"), needle
    )


def test_malformed_or_missing_robot_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("body: {length: [")
    assert_bad_input(_run("--robot", str(bad)), "malformed")
    assert_bad_input(_run("--robot", str(tmp_path / "missing.yaml")), "no such robot file")


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--duration", "-1"], "duration"),
        (["--duration", "nan"], "duration"),
        (["--no-such-flag"], "unrecognized"),
    ],
)
def test_bad_options(args, needle):
    assert_bad_input(_run(*args), needle)


def test_bad_scenario_file(tmp_path):
    scenario = tmp_path / "scenario.yaml"
    scenario.write_text("scene: {world: package://drake_sim_models/worlds/nowhere.sdf}\n")
    assert_bad_input(_run("--config", str(scenario)), "nowhere.sdf")
    scenario.write_text("scene: {robot_pose: {x: .nan}}\n")
    assert_bad_input(_run("--config", str(scenario)), "robot_pose.x")
    scenario.write_text("scene: {robot_pos: {x: 1}}\n")
    assert_bad_input(_run("--config", str(scenario)), "robot_pos")
