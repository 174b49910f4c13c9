"""planning.model.panda_config: the Panda model's and the table's defaults, the sections of
``PandaPlanningConfig`` that ``planning.model.panda`` reads (loading and checking them is
``planning.config``'s, tested in tests/planning/test_config.py)."""

import math

import pytest

import planning.model.panda_config as mut
from planning.model.layout import FINGER_OPEN, NUM_ARM_JOINTS, READY_Q


def test_model_defaults_load_the_convex_panda_with_its_named_configurations():
    dut = mut.PandaModelConfig()
    assert dut.collision_geometry == "convex_mesh" and dut.ee_frame == "panda_hand_tcp"
    assert dut.finger_position == FINGER_OPEN
    assert dut.named_configurations["ready"] == pytest.approx(READY_Q)
    assert sorted(dut.named_configurations) == ["extended", "ready", "transport"]
    assert all(len(q) == NUM_ARM_JOINTS for q in dut.named_configurations.values())
    assert dut.named_configurations["extended"][-1] == pytest.approx(math.pi / 4)
    assert ["panda_attachment", "panda_rightfinger"] in dut.extra_disabled_collisions
    assert dut.edge_step_size > 0.0 and dut.held_object_touch_tolerance > 0.0


def test_each_config_gets_its_own_lists():
    dut = mut.PandaModelConfig()
    dut.named_configurations["ready"][0] = 1.0
    dut.extra_disabled_collisions.clear()
    table = mut.TableConfig()
    table.size[0] = 9.0
    assert mut.PandaModelConfig().named_configurations["ready"][0] == READY_Q[0]
    assert len(mut.PandaModelConfig().extra_disabled_collisions) == 2
    assert mut.TableConfig().size[0] == 1.2


def test_table_top_is_at_the_panda_base():
    dut = mut.TableConfig()
    assert dut.size == [1.2, 1.4, 0.04]
    assert dut.position[2] + 0.5 * dut.size[2] == pytest.approx(0.0)
