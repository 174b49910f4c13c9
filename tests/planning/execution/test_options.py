"""InterfaceOptions load from YAML with units that make sense (the scenario's interface section)."""

import pytest

import planning.execution.options as mut
from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError


def test_defaults_are_positive_and_consistent():
    dut = mut.InterfaceOptions()
    assert dut.poll_period > 0 and dut.finger_speed > 0
    assert dut.goal_tolerance < dut.start_tolerance  # a finished move starts the next one


def test_loads_from_yaml_and_rejects_unknown_keys():
    dut = load_typed(mut.InterfaceOptions, data="poll_period: 0.02\nfinger_speed: 0.1\n")
    assert dut.poll_period == 0.02 and dut.finger_speed == 0.1
    with pytest.raises(ConfigError, match="unknown key 'poll_periood'"):
        load_typed(mut.InterfaceOptions, data="poll_periood: 0.02")
