"""planning.model.model_config: the model's and the table's defaults, the sections of
``PlanningConfig`` that ``planning.model.planning_model`` reads (loading and checking them is
``planning.config``'s, tested in tests/planning/test_config.py)."""

import pytest

import planning.model.model_config as mut


def test_model_defaults_name_the_panda_and_leave_the_rest_to_its_description():
    dut = mut.RobotModelConfig()
    assert dut.description == "panda" and dut.group == ""
    assert dut.collision_geometry == "convex_mesh" and dut.ee_frame == ""
    assert dut.finger_position is None
    assert dut.named_configurations == {} and dut.extra_disabled_collisions == []
    assert dut.edge_step_size > 0.0 and dut.held_object_touch_tolerance > 0.0


def test_each_config_gets_its_own_lists():
    dut = mut.RobotModelConfig()
    dut.named_configurations["mine"] = [0.0] * 7
    dut.extra_disabled_collisions.append(["a", "b"])
    table = mut.TableConfig()
    table.size[0] = 9.0
    assert mut.RobotModelConfig().named_configurations == {}
    assert mut.RobotModelConfig().extra_disabled_collisions == []
    assert mut.TableConfig().size[0] == 1.2


def test_table_top_is_at_the_panda_base():
    dut = mut.TableConfig()
    assert dut.size == [1.2, 1.4, 0.04]
    assert dut.position[2] + 0.5 * dut.size[2] == pytest.approx(0.0)
