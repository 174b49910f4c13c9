"""PickPlaceOptions load from YAML (the scenario's task section) and fit the Franka hand."""

import pytest

import planning.task.options as mut
from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from planning.model.layout import FINGER_OPEN


def test_defaults_fit_the_hand():
    dut = mut.PickPlaceOptions()
    assert dut.min_object_width < dut.max_object_width < 2 * FINGER_OPEN
    assert dut.place_tolerance > 0 and dut.pregrasp_height > dut.grasp_depth


def test_loads_from_yaml_and_rejects_bad_values():
    dut = load_typed(mut.PickPlaceOptions, data="lift_height: 0.08")
    assert dut.lift_height == 0.08 and dut.grasp_depth == mut.PickPlaceOptions().grasp_depth
    with pytest.raises(ConfigError, match="'lift_height' must be finite"):
        load_typed(mut.PickPlaceOptions, data="lift_height: .nan")
