"""Loading and validating the robot YAML (drake_sim.robots.ddrive_params)."""

import math

import pytest
import yaml

import drake_sim.robots.ddrive_params as mut
from drake_sim.base.errors import ConfigError
from drake_sim.robots.ddrive import default_robot_file


def _write(tmp_path, data, name="robot.yaml"):
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else yaml.safe_dump(data))
    return path


def _default_dict():
    return yaml.safe_load(default_robot_file().read_text())


def test_default_file_loads():
    dut = mut.load_robot_params(default_robot_file())
    assert dut.body.length == 0.40
    assert dut.wheel.radius == 0.15
    assert dut.motor.max_torque > 0
    # Realistic: a few kilograms, standing level on wheels and caster.
    assert 1.0 < dut.total_mass < 10.0
    assert dut.caster_z - dut.caster.radius >= dut.body.height / 2


def test_contract_keys_alone_are_enough(tmp_path):
    """A file with only DESIGN.md's keys works: optional keys take their defaults."""
    data = _default_dict()
    del data["wheel"]["gap"]
    del data["caster"]["mass"]
    dut = mut.load_robot_params(_write(tmp_path, data))
    assert dut.wheel.gap == mut.WheelParams().gap
    assert dut.caster.mass == mut.CasterParams().mass


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda d: d["body"].pop("mass"), "body.mass"),
        (lambda d: d.pop("motor"), "motor"),
        (lambda d: d["wheel"].update(radius=0.0), "wheel.radius"),
        (lambda d: d["body"].update(length=-0.4), "body.length"),
        (lambda d: d["body"].update(width=float("nan")), "body.width"),
        (lambda d: d["motor"].update(max_torque=float("inf")), "motor.max_torque"),
        (lambda d: d["wheel"].update(mass="heavy"), "mass"),
        (lambda d: d["body"].update(colour="red"), "colour"),
        (lambda d: d["wheel"].update(radius=0.05), "wheel.radius"),
        (lambda d: d["caster"].update(radius=0.06), "caster.radius"),
    ],
    ids=[
        "missing-key",
        "missing-section",
        "zero",
        "negative",
        "nan",
        "inf",
        "not-a-number",
        "unknown-key",
        "wheel-too-small",
        "caster-too-big",
    ],
)
def test_bad_values_name_the_key(tmp_path, edit, message):
    data = _default_dict()
    edit(data)
    path = _write(tmp_path, data)
    with pytest.raises(ConfigError, match=message) as info:
        mut.load_robot_params(path)
    assert str(path) in str(info.value)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    "text", ["body: [1, 2", "just a string", "", "body: {length: 0.4}\n  bad indent: 1"]
)
def test_malformed_files(tmp_path, text):
    with pytest.raises(ConfigError):
        mut.load_robot_params(_write(tmp_path, text))


def test_missing_file(tmp_path):
    with pytest.raises(ConfigError, match="no such robot file"):
        mut.load_robot_params(tmp_path / "nope.yaml")


def test_scaled_and_round_trip(tmp_path):
    base = mut.load_robot_params(default_robot_file())
    dut = base.scaled(length=1.25, mass=0.7)
    assert math.isclose(dut.body.length, 0.5)
    assert math.isclose(dut.wheel.mass, 0.175)
    assert dut.motor.max_torque == base.motor.max_torque
    path = tmp_path / "scaled.yaml"
    mut.write_robot_params(dut, path)
    assert mut.load_robot_params(path) == dut
