"""Loading and validating the TurtleBot3's YAML (drake_sim.robots.turtlebot3_params)."""

import math

import pytest
import yaml

import drake_sim.robots.turtlebot3_params as mut
from drake_sim.base.errors import ConfigError
from drake_sim.robots.turtlebot3 import default_turtlebot3_file

DELETE = object()


def _load_edited(tmp_path, edits: dict, text: str | None = None):
    """Loads config/turtlebot3.yaml with ``edits`` ({"section.key": value, or DELETE})
    applied, or ``text`` instead; returns the params."""
    data = yaml.safe_load(default_turtlebot3_file().read_text())
    for dotted, value in edits.items():
        section, _, key = dotted.partition(".")
        block = data if not key else data[section]
        if value is DELETE:
            del block[key or section]
        else:
            block[key or section] = value
    path = tmp_path / "turtlebot3.yaml"
    path.write_text(text if text is not None else yaml.safe_dump(data))
    return mut.load_turtlebot3_params(path)


def test_default_file_is_the_published_waffle():
    dut = mut.load_turtlebot3_params(default_turtlebot3_file())
    assert 2 * dut.wheel.radius == pytest.approx(0.066)
    assert dut.wheel_separation == pytest.approx(0.287)
    assert (dut.body.length, dut.body.width) == pytest.approx((0.281, 0.306))
    assert dut.total_mass == pytest.approx(1.8, abs=0.1)
    assert dut.limits.max_linear_velocity == pytest.approx(0.26)
    assert dut.limits.max_angular_velocity == pytest.approx(1.82)
    assert 0.15 < dut.scan_height < 0.2
    assert dut.lidar_mount == (dut.lidar.x, dut.lidar.y, dut.lidar.z)
    assert dut.scan_height > dut.top_z  # The lidar sees over the deck.
    # The plate fits between the wheels, the deck clears them.
    assert dut.plate_width + dut.wheel.width + 2 * dut.wheel.gap == pytest.approx(0.287)
    assert dut.deck_bottom > 2 * dut.wheel.radius
    assert dut.caster.x < 0  # The casters trail the axle.


def test_optional_keys_take_defaults(tmp_path):
    edits = {"limits": DELETE, "wheel.gap": DELETE, "camera.y": DELETE}
    dut = _load_edited(tmp_path, edits)
    assert dut.limits == mut.VelocityLimits()
    assert dut.wheel.gap == mut.DriveWheelParams().gap
    assert dut.camera.y == 0.0


BAD = {
    "missing-key": ({"body.mass": DELETE}, "missing key 'body.mass'"),
    "missing-section": ({"motor": DELETE}, "missing key 'motor.max_torque'"),
    "missing-lidar": ({"lidar": DELETE}, "missing key 'lidar.x'"),
    "zero": ({"wheel.radius": 0.0}, "wheel.radius"),
    "negative": ({"body.length": -0.1}, "body.length"),
    "negative-limit": ({"limits.max_linear_velocity": -0.2}, "limits.max_linear_velocity"),
    "nan": ({"wheel.separation": float("nan")}, "wheel.separation"),
    "inf": ({"motor.max_torque": float("inf")}, "motor.max_torque"),
    "not-a-number": ({"wheel.mass": "heavy"}, "wheel.mass"),
    "boolean": ({"caster.mass": True}, "caster.mass"),
    "unknown-key": ({"body.colour": "red"}, "colour"),
    "unknown-section": ({"bumper": {"x": 1}}, "bumper"),
    "wheels-too-close": ({"wheel.separation": 0.02}, "wheel.separation"),
    "deck-narrower-than-the-wheels": ({"body.width": 0.25}, "body.width"),
    "deck-on-the-wheels": ({"body.height": 0.04}, "body.height"),
    "axle-off-the-chassis": ({"body.offset_x": -0.2}, "body.offset_x"),
    "caster-ahead-of-the-axle": ({"caster.x": 0.05}, "caster.x"),
    "caster-behind-the-chassis": ({"caster.x": -0.3}, "caster.x"),
    "caster-beside-the-plate": ({"caster.y": 0.13}, "caster.y"),
    "caster-too-big": ({"caster.radius": 0.02}, "caster.radius"),
    "imu-off-the-chassis": ({"imu.x": 0.2}, "imu.x"),
    "camera-above-the-chassis": ({"camera.z": 0.3}, "camera.z"),
    "lidar-off-the-side": ({"lidar.y": 0.2}, "lidar.y"),
    "lidar-inside-the-chassis": ({"lidar.z": 0.1}, "lidar.z"),
}


@pytest.mark.parametrize("edits, message", BAD.values(), ids=BAD.keys())
def test_bad_values_name_the_file_and_key(tmp_path, edits, message):
    with pytest.raises(ConfigError, match=message) as info:
        _load_edited(tmp_path, edits)
    assert str(tmp_path / "turtlebot3.yaml") in str(info.value)
    assert "\n" not in str(info.value)


def test_positions_may_be_negative_or_zero(tmp_path):
    dut = _load_edited(tmp_path, {"imu.x": -0.1, "lidar.x": 0.0, "camera.y": -0.05})
    assert (dut.imu.x, dut.lidar.x, dut.camera.y) == (-0.1, 0.0, -0.05)


@pytest.mark.parametrize("text", ["body: [1, 2", "just a string", "", "wheel: {radius: 0.03}"])
def test_malformed_or_incomplete_files(tmp_path, text):
    with pytest.raises(ConfigError) as info:
        _load_edited(tmp_path, {}, text)
    assert "\n" not in str(info.value)


def test_missing_file(tmp_path):
    with pytest.raises(ConfigError, match="no such robot file"):
        mut.load_turtlebot3_params(tmp_path / "nope.yaml")


def test_validate_checks_objects_built_in_code():
    dut = mut.load_turtlebot3_params(default_turtlebot3_file())
    dut.wheel.radius = math.nan
    with pytest.raises(ConfigError, match="wheel.radius"):
        mut.validate(dut)


def test_scaled_and_round_trip(tmp_path):
    base = mut.load_turtlebot3_params(default_turtlebot3_file())
    dut = base.scaled(length=1.5, mass=2.0)
    assert math.isclose(dut.wheel_separation, 1.5 * base.wheel_separation)
    assert math.isclose(dut.scan_height, 1.5 * base.scan_height)
    assert math.isclose(dut.body.offset_x, 1.5 * base.body.offset_x)
    assert math.isclose(dut.total_mass, 2.0 * base.total_mass)
    assert dut.motor == base.motor and dut.limits == base.limits
    assert base.wheel.radius == 0.033  # The original is untouched.
    mut.validate(dut)
    path = tmp_path / "scaled.yaml"
    mut.write_turtlebot3_params(dut, path)
    assert mut.load_turtlebot3_params(path) == dut
