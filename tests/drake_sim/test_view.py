"""``python -m drake_sim.view``: runs, records, and rejects bad input with exit code 2."""

import pytest

import drake_sim.view as mut
from tests.cli_helpers import assert_bad_input, edited_robot_file, run_module
from tests.meshcat_html import scene_paths


def _run(*args):
    return run_module("drake_sim.view", *args)


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
    assert_bad_input(_run("--robot", str(tmp_path / "missing.yaml")), "robot file not found")


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


@pytest.mark.parametrize(
    "args, needle",
    [
        pytest.param(["--robot", "{latin1}"], "not UTF-8", id="robot-not-utf8"),
        pytest.param(["--view-only", "--robot", "{latin1}"], "not UTF-8", id="view-only"),
        pytest.param(["--config", "{latin1}"], "not UTF-8", id="config-not-utf8"),
        pytest.param(["--robot", "{tmp}"], "robot file is a directory", id="robot-directory"),
        pytest.param(["--config", "{empty}"], "scenario file is empty", id="config-empty"),
        pytest.param(["--view-only", "--record", "{tmp}"], "replay is a directory", id="record"),
        pytest.param(
            ["--record", "{latin1}/replay.html"], "latin1.yaml is not a directory", id="parent"
        ),
    ],
)
def test_bad_paths_are_one_line_and_exit_2_before_viewing(tmp_path, args, needle):
    """Non-UTF-8, empty or directory inputs, and outputs that cannot be written."""
    latin1, empty = tmp_path / "latin1.yaml", tmp_path / "empty.yaml"
    latin1.write_bytes("body: {length: 0.3}  # longueur, mètres\n".encode("latin-1"))
    empty.write_text("")
    files = {"latin1": latin1, "empty": empty, "tmp": tmp_path}
    result = _run(*(a.format(**files) for a in args), "--duration", "30")
    assert_bad_input(result, needle)
    assert result.stdout == ""  # nothing was shown
