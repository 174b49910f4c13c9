"""The pick-and-place app's recipe (drake_sim.runs.pickplace): its scenario with the scene and
station files and the seed, the report's keys, and a sweep's random scenes. (The run itself,
planning and simulating the task, is tests/drake_sim/test_pickplace.py's.)"""

import pytest

import drake_sim.runs.pickplace as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from planning.task.pick_place import TaskReport


def test_the_seed_is_the_planner_s():
    inputs = mut.RECIPE.load(seed=5)
    assert inputs.seed == 5 and inputs.scenario.planner.seed == 5
    assert inputs.robot is None  # the scenario holds the robot


def test_scene_and_station_files_replace_their_sections(tmp_path):
    scene = tmp_path / "scene.yaml"
    shipped = (config_dir() / "pickplace.yaml").read_text()
    scene.write_text(shipped.replace("[0.5, 0.25, 0.04]", "[0.45, 0.3, 0.04]"))
    station = tmp_path / "station.yaml"
    station.write_text("finger_kp: 5000.0\n")
    inputs = mut.RECIPE.load(scene=scene, station=station, overrides=["mode=kinematic"])
    scenario = inputs.scenario
    assert scenario.scene.place.position == [0.45, 0.3, 0.04]
    assert scenario.station.finger_kp == 5000.0 and scenario.mode == "kinematic"
    assert scenario.station_config().scene is scenario.scene  # still the scenario's


def test_a_station_file_may_not_set_what_the_scenario_sets(tmp_path):
    station = tmp_path / "station.yaml"
    station.write_text("model: {ee_frame: somewhere}\n")
    with pytest.raises(ConfigError, match="'station.model' is set by the scenario"):
        mut.RECIPE.load(station=station)


def test_report_keys_are_the_report_s():
    report = mut.PickPlaceReport(end="done", mode="physics", setup_time_s=1.0, task=TaskReport())
    data = report.to_dict()
    assert tuple(data) == mut.report_keys()
    assert data["end"] == "done" and data["setup_time_s"] == 1.0


def test_random_scene_k_is_the_same_in_every_sweep():
    scenario = mut.RECIPE.load().scenario
    first, again, other = (mut.generate_scene(scenario, k).scene for k in (3, 3, 4))
    assert first == again and first != other
    assert first.table == scenario.scene.table
