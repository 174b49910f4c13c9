"""The pick-and-place scenario: one file, one place per value, overrides and the scene file."""

import numpy as np
import pytest

import diagrams.pickplace_scenario as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from planning.model.layout import FINGER_OPEN, NUM_POSITIONS, READY_Q
from planning.model.planning_model import named_configurations
from tests.robot_helpers import XARM7_YAML

SCENE = config_dir() / "pickplace.yaml"


def write(tmp_path, text: str):
    path = tmp_path / "scenario.yaml"
    path.write_text(f"scene_file: {SCENE}\n{text}")
    return path


def test_shipped_scenario_loads_with_its_scene():
    dut = mut.load_pickplace_scenario()
    assert dut.mode == "physics"
    assert dut.scene.object.size == [0.045, 0.045, 0.08]
    assert dut.robot.table is None  # the table is the scene's
    station = dut.station_config()
    assert station.initial_q == pytest.approx([*READY_Q, FINGER_OPEN, FINGER_OPEN])
    assert len(station.initial_q) == NUM_POSITIONS
    assert station.model is dut.robot.model and station.scene is dut.scene


def test_one_model_for_planner_and_station(tmp_path):
    dut = mut.load_pickplace_scenario(
        write(tmp_path, "robot: {model: {collision_geometry: primitives}}\n")
    )
    assert dut.station_config().model.collision_geometry == "primitives"


@pytest.mark.parametrize(
    "text, match",
    [
        ("robot: {table: {size: [1, 1, 0.1]}}", "'robot.table' is set by scene.table"),
        ("station: {model: {ee_frame: x}}", "'station.model' is set by robot.model"),
        ("station: {initial_q: [0, 0]}", "'station.initial_q' is set by initial_configuration"),
        ("stations: {}", "unknown key 'stations'"),
        ("task: {lift_height: -1}", "'task.lift_height' must be >= 0"),
        ("mode: hardware", "'mode' must be one of physics, kinematic"),
        ("initial_configuration: nowhere", "'nowhere' is not a named configuration"),
        ("station: {arm_kp: [1, 2]}", "station.arm_kp needs 7 values"),
    ],
)
def test_bad_scenarios_name_the_key(tmp_path, text, match):
    with pytest.raises(ConfigError, match=match):
        mut.load_pickplace_scenario(write(tmp_path, text))


def test_an_arm_without_fingers_grasps_in_the_kinematic_mode_only(tmp_path):
    arm = tmp_path / "xarm7.yaml"
    arm.write_text(XARM7_YAML)
    sets = [f"robot.model.description={arm}", "initial_configuration=home"]
    with pytest.raises(ConfigError, match="UF_ROBOT has no finger joints.*kinematic mode only"):
        mut.load_pickplace_scenario(overrides=sets)
    dut = mut.load_pickplace_scenario(overrides=[*sets, "mode=kinematic"])
    config = dut.station_config()
    assert len(config.initial_q) == 7  # the xArm's 7 joints, no fingers
    home = named_configurations(dut.robot.model)["home"]
    np.testing.assert_array_equal(config.initial_q, home)


def test_physics_gains_take_the_size_of_the_group(tmp_path):
    with pytest.raises(ConfigError, match="station.arm_kd needs 7 values, one per joint"):
        mut.load_pickplace_scenario(overrides=["station.arm_kd=[1, 2, 3]"])


def test_scene_file_is_relative_to_the_scenario(tmp_path):
    (tmp_path / "scene.yaml").write_text(SCENE.read_text().replace("0.1]", "0.12]"))
    path = tmp_path / "s.yaml"
    path.write_text("scene_file: scene.yaml\n")
    assert mut.load_pickplace_scenario(path).scene.obstacle.position[2] == 0.12
    path.write_text("scene_file: missing.yaml\n")
    with pytest.raises(ConfigError, match="missing.yaml: no such file"):
        mut.load_pickplace_scenario(path)


def test_scene_argument_and_overrides_come_last(tmp_path):
    other = tmp_path / "other.yaml"
    other.write_text(SCENE.read_text().replace("[0.5, 0.25, 0.04]", "[0.45, 0.3, 0.04]"))
    dut = mut.load_pickplace_scenario(
        scene_file=other, overrides=["scene.object.mass=0.2", "planner.seed=4", "mode=kinematic"]
    )
    assert dut.scene.place.position == [0.45, 0.3, 0.04]
    assert dut.scene.object.mass == 0.2 and dut.planner.seed == 4 and dut.mode == "kinematic"
    with pytest.raises(ConfigError, match="station.model.ee_frame is set by robot.model"):
        mut.load_pickplace_scenario(overrides=["station.model.ee_frame=x"])


def test_dump_reads_back_the_same(tmp_path):
    dut = mut.load_pickplace_scenario(overrides=["task.lift_height=0.07"])
    path = tmp_path / "dumped.yaml"
    path.write_text(mut.dump_pickplace_scenario(dut))
    again = mut.load_pickplace_scenario(path)
    assert mut.dump_pickplace_scenario(again) == path.read_text()
    assert again.task.lift_height == 0.07 and again.scene == dut.scene
