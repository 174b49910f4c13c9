"""Loading and validating Wall-E's YAML (drake_sim.robots.walle_params)."""

import math

import pytest
import yaml

import drake_sim.robots.walle_params as mut
from drake_sim.base.errors import ConfigError
from drake_sim.robots.walle import default_robot_file

DELETE = object()


def _load_edited(tmp_path, edits: dict, text: str | None = None):
    """Loads config/walle.yaml with ``edits`` ({"section.key": value, or DELETE}) applied,
    or ``text`` instead; returns the params and the file's path."""
    data = yaml.safe_load(default_robot_file().read_text())
    for dotted, value in edits.items():
        section, _, key = dotted.partition(".")
        block = data if not key else data[section]
        if value is DELETE:
            del block[key or section]
        else:
            block[key or section] = value
    path = tmp_path / "walle.yaml"
    path.write_text(text if text is not None else yaml.safe_dump(data))
    return mut.load_walle_params(path), path


def test_default_file_loads_a_tall_robot():
    dut = mut.load_walle_params(default_robot_file())
    assert dut.body.height == 0.36
    assert dut.motor.max_torque > 0
    assert 0.5 < dut.total_mass < 5.0
    # Tall: the body's centre of mass is well above the axle, and the axle inside the body.
    assert dut.com_height > 2 * dut.wheel.radius
    assert -dut.body.height / 2 < dut.axle_z < 0
    # The IMU sits on the axle, the camera high on the front face.
    assert dut.imu.z == pytest.approx(dut.axle_z)
    assert dut.camera.x == pytest.approx(dut.body.length / 2)
    assert dut.camera.z > dut.body.height / 4
    # Standing upright, the floor is at z = axle_z - radius in B.
    assert dut.axle_z - dut.wheel.radius == pytest.approx(
        -dut.body.height / 2 - dut.body.ground_clearance
    )


def test_optional_keys_take_defaults(tmp_path):
    edits = {"caster": DELETE, "body.ground_clearance": DELETE, "camera.y": DELETE}
    dut, _ = _load_edited(tmp_path, edits)
    assert dut.caster == mut.CasterParams()
    assert dut.body.ground_clearance == mut.BodyParams().ground_clearance
    assert dut.camera.y == 0.0


BAD = {
    "missing-key": ({"body.mass": DELETE}, "missing key 'body.mass'"),
    "missing-section": ({"motor": DELETE}, "missing key 'motor.max_torque'"),
    "missing-camera-pitch": ({"camera.pitch": DELETE}, "missing key 'camera.pitch'"),
    "zero": ({"wheel.radius": 0.0}, "wheel.radius"),
    "negative": ({"body.length": -0.1}, "body.length"),
    "nan": ({"body.width": float("nan")}, "body.width"),
    "inf": ({"motor.max_torque": float("inf")}, "motor.max_torque"),
    "not-a-number": ({"wheel.mass": "heavy"}, "wheel.mass"),
    "unknown-key": ({"body.colour": "red"}, "colour"),
    "axle-below-the-body": ({"wheel.radius": 0.02}, "wheel.radius"),
    "axle-above-the-centre": ({"wheel.radius": 0.25}, "wheel.radius"),
    "imu-off-the-body": ({"imu.z": -0.5}, "imu.z"),
    "camera-off-the-body": ({"camera.x": 0.2}, "camera.x"),
    "camera-looks-up": ({"camera.pitch": -10.0}, "camera.pitch"),
    "camera-looks-back": ({"camera.pitch": 95.0}, "camera.pitch"),
    "caster-does-not-fit": ({"caster.radius": 0.02}, "caster.radius"),
    "motors-too-weak": ({"motor.max_torque": 0.1}, "motor.max_torque"),
}


@pytest.mark.parametrize("edits, message", BAD.values(), ids=BAD.keys())
def test_bad_values_name_the_key(tmp_path, edits, message):
    with pytest.raises(ConfigError, match=message) as info:
        _load_edited(tmp_path, edits)
    assert str(tmp_path / "walle.yaml") in str(info.value)
    assert "\n" not in str(info.value)


def test_positions_may_be_negative_or_zero(tmp_path):
    edits = {"camera.x": -0.06, "imu.x": 0.0, "imu.z": 0.0}  # The camera on the back face.
    dut, _ = _load_edited(tmp_path, edits)
    assert dut.camera.x == -0.06 and dut.imu.z == 0.0


@pytest.mark.parametrize("text", ["body: [1, 2", "just a string", "", "body: {length: 0.1}"])
def test_malformed_or_incomplete_files(tmp_path, text):
    with pytest.raises(ConfigError):
        _load_edited(tmp_path, {}, text)


def test_missing_file(tmp_path):
    with pytest.raises(ConfigError, match="no such robot file"):
        mut.load_walle_params(tmp_path / "nope.yaml")


def test_validate_checks_objects_built_in_code():
    dut = mut.load_walle_params(default_robot_file())
    dut.body.mass = -1.0
    with pytest.raises(ConfigError, match="body.mass"):
        mut.validate(dut)


def test_scaled_and_round_trip(tmp_path):
    base = mut.load_walle_params(default_robot_file())
    dut = base.scaled(length=1.25, mass=0.7)
    assert math.isclose(dut.body.height, 1.25 * base.body.height)
    assert math.isclose(dut.camera.z, 1.25 * base.camera.z)
    assert math.isclose(dut.imu.z, 1.25 * base.imu.z)
    assert math.isclose(dut.wheel.mass, 0.7 * base.wheel.mass)
    assert math.isclose(dut.com_height, 1.25 * base.com_height)
    assert dut.camera.pitch == base.camera.pitch
    assert dut.motor.max_torque == base.motor.max_torque
    assert base.body.height == 0.36  # The original is untouched.
    path = tmp_path / "scaled.yaml"
    mut.write_walle_params(dut, path)
    assert mut.load_walle_params(path) == dut


@pytest.mark.parametrize("length, mass", [(0.8, 0.7), (0.8, 1.5), (1.25, 0.7), (1.25, 1.5)])
def test_scaled_robots_are_valid(length, mass):
    base = mut.load_walle_params(default_robot_file())
    mut.validate(base.scaled(length=length, mass=mass))
