"""drake_sim.base.errors: ConfigError is the one typed error for bad configuration."""

import pytest

import drake_sim.base.errors as mut


def test_config_error_is_a_value_error():
    assert issubclass(mut.ConfigError, ValueError)
    with pytest.raises(ValueError, match="f.yaml: 'rate' must be > 0"):
        raise mut.ConfigError("f.yaml: 'rate' must be > 0")


def test_config_error_keeps_its_message_and_type():
    dut = mut.ConfigError("f.yaml: unknown key 'x'")
    assert str(dut) == "f.yaml: unknown key 'x'"
    assert isinstance(dut, mut.ConfigError) and not isinstance(dut, TypeError)
