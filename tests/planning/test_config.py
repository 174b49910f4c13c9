"""The Panda planning configuration: defaults, loading YAML from a file or a string (missing keys
keep their defaults), and ConfigError naming the source and the key for anything unusable."""

import dataclasses as dc
import math

import pytest

import planning.config as mut
from drake_sim.base.errors import ConfigError
from planning.model.layout import FINGER_OPEN, READY_Q
from planning.model.model_config import RobotModelConfig
from planning.model.planning_model import finger_defaults, named_configurations


def test_defaults_describe_the_panda_on_its_table():
    dut = mut.PlanningConfig()
    model = dut.model
    assert model.description == "panda" and model.collision_geometry == "convex_mesh"
    named = named_configurations(model)
    assert named["ready"] == pytest.approx(READY_Q)
    assert sorted(named) == ["extended", "ready", "transport"]
    assert all(len(q) == 7 for q in named.values())
    assert finger_defaults(model) == [FINGER_OPEN, FINGER_OPEN]
    assert dut.table.size == [1.2, 1.4, 0.04]
    top = dut.table.position[2] + 0.5 * dut.table.size[2]
    assert top == pytest.approx(0.0)  # the Panda stands on the table top
    assert dut.ik == mut.IkOptions() and dut.ik.seed == 0
    mut.check_planning_config(dut)  # the defaults are valid
    # Each config gets its own lists: changing one leaves the defaults alone.
    dut.model.named_configurations["ready"] = [1.0] * 7
    assert mut.PlanningConfig().model.named_configurations == {}


def test_yaml_string_changes_only_its_keys():
    dut = mut.load_planning_config(
        data="model: {finger_position: 0.02, named_configurations: {up: [0, 0, 0, -1, 0, 1, 0]}}\n"
        "ik: {max_restarts: 3, minimum_distance: null}\n"
    )
    default = mut.PlanningConfig()
    assert dut.model.finger_position == 0.02
    assert dut.model.named_configurations["up"] == [0, 0, 0, -1, 0, 1, 0]
    assert dut.ik.max_restarts == 3 and dut.ik.minimum_distance is None
    assert dut.ik.time_budget == default.ik.time_budget
    assert dut.table == default.table and dut.model.ee_frame == default.model.ee_frame


def test_yaml_file_and_a_null_table(tmp_path):
    path = tmp_path / "panda.yaml"
    path.write_text("table: null\nmodel: {collision_geometry: primitives}\n")
    dut = mut.load_planning_config(path)
    assert dut.table is None and dut.model.collision_geometry == "primitives"
    assert mut.load_planning_config(str(path)) == dut
    empty = tmp_path / "empty.yaml"
    empty.write_text("")
    assert mut.load_planning_config(empty) == mut.PlanningConfig()


@pytest.mark.parametrize(
    "text, needles",
    [
        ("modle: {}", ["modle"]),
        ("model: {ee_frme: x}", ["model.ee_frme"]),
        ("ik: {max_restarts: many}", ["ik.max_restarts"]),
        ("ik: {time_budget: .inf}", ["ik.time_budget"]),
        ("model: {named_configurations: {up: [0, 0, 0]}}", ["named_configurations.up", "7 joints"]),
        ("model: {extra_disabled_collisions: [[panda_link1]]}", ["extra_disabled_collisions"]),
        ("model: {finger_position: 0.05}", ["model.finger_position"]),
        ("model: {edge_step_size: 0.0}", ["model.edge_step_size"]),
        ("table: {size: [1.0, 1.0]}", ["table"]),
        ("table: {size: [1.0, 1.0, 0.0]}", ["table"]),
        ("ik: {time_budget: 0.0}", ["ik.time_budget"]),
        ("ik: {max_restarts: -1}", ["ik.max_restarts"]),
        ("ik: {position_tolerance: 0.0}", ["ik", "tolerance"]),
        ("ik: {orientation_tolerance: -0.1}", ["ik", "tolerance"]),
        ("model: [1, 2]", ["model"]),
        ("model: {ee_frame: x", []),
    ],
)
def test_bad_yaml_raises_config_error_naming_file_and_key(tmp_path, text, needles):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        mut.load_planning_config(path)
    message = str(info.value)
    for needle in [str(path), *needles]:
        assert needle in message
    assert "\n" not in message.strip()  # one line, for a command line's error


def test_missing_file_raises_config_error(tmp_path):
    with pytest.raises(ConfigError, match="nowhere.yaml"):
        mut.load_planning_config(tmp_path / "nowhere.yaml")


def test_check_names_where_the_values_came_from():
    bad = mut.PlanningConfig(ik=mut.IkOptions(max_restarts=-1))
    with pytest.raises(ConfigError, match="^robot: ik"):
        mut.check_planning_config(bad)
    with pytest.raises(ConfigError, match="^scenario.yaml: ik"):
        mut.check_planning_config(bad, "scenario.yaml")
    named = dc.replace(RobotModelConfig(), named_configurations={"pi": [math.pi] * 6})
    with pytest.raises(ConfigError, match="named_configurations.pi has 6 values, group 'arm'"):
        mut.check_planning_config(mut.PlanningConfig(model=named))
