"""``python -m drake_sim.pickplace``: report, replay, exit codes and one-line errors."""

import json
import subprocess
import sys

import pytest
import yaml

from drake_sim.base.resources import config_dir
from planning.task.pick_place import STEPS
from tests.cli_helpers import assert_bad_input

REPORT_KEYS = {
    "success",
    "place_error_m",
    "object_final_position",
    "planning_time_s",
    "sim_time_s",
    "wall_time_s",
    "steps",
}


def run_cli(*args):
    return subprocess.run(
        [sys.executable, "-m", "drake_sim.pickplace", *args],
        capture_output=True,
        text=True,
        timeout=600,
    )


def scene_file(tmp_path, edit):
    data = yaml.safe_load((config_dir() / "pickplace.yaml").read_text())
    edit(data)
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_kinematic_run_writes_report_and_replay(tmp_path):
    report, replay = tmp_path / "report.json", tmp_path / "replay.html"
    result = run_cli(
        "--mode", "kinematic", "--headless", "--report", str(report), "--record", str(replay)
    )
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    data = json.loads(report.read_text())
    assert set(data) >= REPORT_KEYS and data["success"] and data["mode"] == "kinematic"
    assert data["place_error_m"] < 0.02
    assert [s["name"] for s in data["steps"]] == list(STEPS)
    for step in data["steps"]:
        assert set(step) >= {"name", "success", "planning_time_s"}
    assert "meshcat" in replay.read_text().lower()
    assert "success" in result.stdout


def test_impossible_scene_exits_1_with_one_line(tmp_path):
    def far(data):
        data["object"]["position"] = [1.4, -0.25, 0.04]

    result = run_cli("--headless", "--mode", "kinematic", "--scene", str(scene_file(tmp_path, far)))
    assert result.returncode == 1, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "impossible" in lines[0] and "reach" in lines[0]
    assert "Traceback" not in result.stderr


def _set(key, index, value):
    def edit(data):
        data[key][index] = value

    return edit


@pytest.mark.parametrize(
    "edit,needle",
    [
        (lambda d: d.update(objekt=d.pop("object")), "objekt"),
        (_set("object", "size", [0.05, -0.05, 0.08]), "positive"),
        (_set("object", "position", [0.5, float("nan"), 0.04]), "object"),
        (_set("object", "mass", 0.0), "mass"),
        (_set("obstacle", "size", [0.3, 0.04]), "obstacle"),
        (lambda d: d.pop("place"), "the scene has no 'place' key"),
        (lambda d: d.pop("object"), "the scene has no 'object' key"),
    ],
    ids=[
        "unknown_key",
        "negative_size",
        "nan_position",
        "zero_mass",
        "short_size",
        "no_place",
        "no_object",
    ],
)
def test_bad_scene_exits_2(tmp_path, edit, needle):
    result = run_cli("--headless", "--scene", str(scene_file(tmp_path, edit)))
    assert_bad_input(result, needle)


@pytest.mark.parametrize(
    "args,needle",
    [
        (["--mode", "hardware"], "--mode"),
        (["--seed", "-1"], "--seed"),
        (["--scene", "/no/such/scene.yaml"], "scene file not found"),
        (["--bogus"], "--bogus"),
    ],
)
def test_bad_arguments_exit_2(args, needle):
    assert_bad_input(run_cli("--headless", *args), needle)


def test_malformed_yaml_exits_2(tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text("object: {size: [0.05, 0.05\n")
    assert_bad_input(run_cli("--headless", "--scene", str(path)), "scene.yaml")


@pytest.mark.parametrize(
    "args, needle",
    [
        pytest.param(["--scene", "{latin1}"], "not UTF-8", id="scene-not-utf8"),
        pytest.param(["--scenario", "{latin1}"], "not UTF-8", id="scenario-not-utf8"),
        pytest.param(["--station", "{latin1}"], "not UTF-8", id="station-not-utf8"),
        pytest.param(["--scene", "{tmp}"], "scene file is a directory", id="scene-directory"),
        pytest.param(["--scene", "{empty}"], "scene file is empty", id="scene-empty"),
        pytest.param(["--scenario", "{empty}"], "scenario file is empty", id="scenario-empty"),
        pytest.param(["--report", "{tmp}"], "report is a directory", id="report-directory"),
        pytest.param(
            ["--report", "{latin1}/report.json"], "latin1.yaml is not a directory", id="parent"
        ),
        pytest.param(["--record", "{tmp}/"], "replay is a directory", id="record-directory"),
    ],
)
def test_bad_paths_exit_2_before_the_task(tmp_path, args, needle):
    latin1, empty = tmp_path / "latin1.yaml", tmp_path / "empty.yaml"
    latin1.write_bytes("place: {position: [0.5, 0.25, 0.04]}  # défaut\n".encode("latin-1"))
    empty.write_text("")
    names = {"latin1": latin1, "empty": empty, "tmp": tmp_path}
    result = run_cli("--headless", "--mode", "kinematic", *(a.format(**names) for a in args))
    assert_bad_input(result, needle)
    assert result.stdout == ""  # no step ran
