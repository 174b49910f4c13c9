"""``params_common``: the robots' shared schema helpers, on a small schema of two sections."""

import dataclasses as dc
import math

import pytest
import yaml

import drake_sim.robots.params_common as mut
from drake_sim.base.errors import ConfigError


@dc.dataclass
class _Body:
    length: float = 0.5  # m
    mass: float = 2.0  # kg
    x: float = -0.1  # m, a position


@dc.dataclass
class _Motor:
    max_torque: float = 1.5  # N m


@dc.dataclass
class _Params(mut.RobotParamsBase):
    UNSCALED = ("motor",)

    body: _Body = dc.field(default_factory=_Body)
    motor: _Motor = dc.field(default_factory=_Motor)


def test_scaled_scales_lengths_and_masses_but_not_the_unscaled():
    params = _Params()
    dut = params.scaled(length=2.0, mass=3.0)
    assert dut.body == _Body(length=1.0, mass=6.0, x=-0.2)
    assert dut.motor == _Motor() and dut.motor is not params.motor  # copied as it is
    assert params == _Params()  # the original is left alone


def test_unscaled_names_fields_too():
    dut = dc.replace(_Params())
    dut.UNSCALED = ("mass",)
    assert dut.scaled(length=2.0, mass=3.0).body == _Body(length=1.0, mass=2.0, x=-0.2)


def test_to_dict_is_the_yaml_layout():
    assert _Params().to_dict() == {
        "body": {"length": 0.5, "mass": 2.0, "x": -0.1},
        "motor": {"max_torque": 1.5},
    }


def test_number_fields_yields_every_key_in_order():
    assert list(mut.number_fields(_Params(), "robot.yaml")) == [
        ("body.length", 0.5),
        ("body.mass", 2.0),
        ("body.x", -0.1),
        ("motor.max_torque", 1.5),
    ]


@pytest.mark.parametrize("value", [True, "1", None])
def test_number_fields_rejects_what_is_not_a_number(value):
    params = _Params(motor=_Motor(max_torque=value))
    with pytest.raises(ConfigError, match=r"robot.yaml: 'motor.max_torque' must be a number"):
        list(mut.number_fields(params, "robot.yaml"))


@pytest.mark.parametrize(
    "body, message",
    [
        (_Body(length=math.nan), "missing key 'body.length'"),
        (_Body(mass=math.inf), "'body.mass' must be finite"),
        (_Body(mass=0.0), "'body.mass' must be > 0"),
        (_Body(x=-math.inf), "'body.x' must be finite"),
    ],
)
def test_check_values_names_the_first_bad_key(body, message):
    with pytest.raises(ConfigError, match=f"robot.yaml: {message}"):
        mut.check_values(_Params(body=body), "robot.yaml", frozenset({"body.x"}))


def test_check_values_lets_positions_be_zero_or_negative():
    mut.check_values(_Params(), "robot.yaml", frozenset({"body.x"}))
    with pytest.raises(ConfigError, match="'body.x' must be > 0"):
        mut.check_values(_Params(), "robot.yaml")


def test_write_params_writes_the_yaml_layout(tmp_path):
    path = tmp_path / "robot.yaml"
    mut.write_params(_Params(), path)
    assert yaml.safe_load(path.read_text()) == _Params().to_dict()
    assert path.read_text().startswith("body:")  # in the schema's order
