"""MoveIt's joint_limits.yaml: both layouts (MoveIt 1 at the top, MoveIt 2 under
robot_description_planning), flags and values, one warning line for unused keys, and a
ConfigError naming the file and the key for each kind of bad value."""

import logging

import pytest

import planning.model.joint_limits as mut
from drake_sim.base.errors import ConfigError

# The layout of moveit_resources' panda_moveit_config (two joints of it).
MOVEIT1 = """
default_velocity_scaling_factor: 0.1
joint_limits:
  panda_joint1:
    has_velocity_limits: true
    max_velocity: 2.1750
    has_acceleration_limits: true
    max_acceleration: 3.75
    has_jerk_limits: true
    max_jerk: 500.0
  panda_finger_joint1:
    has_velocity_limits: true
    max_velocity: 0.1
    has_acceleration_limits: false
    max_acceleration: 0
    max_effort: 20
"""
MOVEIT2 = """
robot_description_planning:
  joint_limits:
    panda_joint2:
      has_velocity_limits: true
      max_velocity: 2
      has_position_limits: true
      min_position: -1.7628
      max_position: 1.7628
"""


def write(tmp_path, text: str, name="joint_limits.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_reads_moveit1_limits_and_warns_about_unused_keys(tmp_path, caplog):
    path = write(tmp_path, MOVEIT1)
    with caplog.at_level(logging.WARNING):
        dut = mut.load_joint_limits(path)
    assert list(dut) == ["panda_joint1", "panda_finger_joint1"]
    assert dut["panda_joint1"] == mut.JointLimit(True, 2.175, True, 3.75, True, 500.0)
    finger = dut["panda_finger_joint1"]
    assert (finger.has_velocity_limits, finger.max_velocity) == (True, 0.1)
    assert (finger.has_acceleration_limits, finger.max_acceleration) == (False, 0.0)
    assert (finger.has_jerk_limits, finger.max_jerk) == (False, None)  # absent: off
    assert [r.getMessage() for r in caplog.records] == [
        f"{path}: keys not used (ignored): default_velocity_scaling_factor, "
        "joint_limits.panda_finger_joint1.max_effort"
    ]


def test_reads_moveit2_limits_under_robot_description_planning(tmp_path, caplog):
    with caplog.at_level(logging.WARNING):
        dut = mut.load_joint_limits(write(tmp_path, MOVEIT2))
    limit = dut["panda_joint2"]
    assert (limit.max_velocity, limit.min_position, limit.max_position) == (2.0, -1.7628, 1.7628)
    assert isinstance(limit.max_velocity, float)
    assert limit.has_position_limits
    assert caplog.records == []


@pytest.mark.parametrize(
    "old, new, message",
    [
        ("max_velocity: 2.1750", "max_velocity: -2.1750", r"\.max_velocity is -2\.175, a limit "),
        ("max_velocity: 2.1750", "max_velocity: .nan", r"\.max_velocity must be a finite number"),
        ("max_velocity: 2.1750", "max_velocity: fast", r"\.max_velocity must be a finite number"),
        ("max_velocity: 2.1750", "max_velocity: true", r"\.max_velocity must be a finite number"),
        ("has_jerk_limits: true", "has_jerk_limits: 1", r"\.has_jerk_limits must be true or false"),
        ("    max_jerk: 500.0\n", "", r"has_jerk_limits is true but max_jerk is missing"),
        ("max_acceleration: 3.75", "max_acceleration: 0", r"max_acceleration is 0 with has_acc"),
        ("  panda_joint1:\n", "  panda_joint0: 3\n  panda_joint1:\n", r"panda_joint0 must be a"),
        ("joint_limits:", "limits:", r"no joint_limits mapping"),
        ("max_velocity: 0.1", "max_velocity: [0.1]", r"max_velocity must be a finite number"),
        ("joint_limits:", "joint_limits: {", r"malformed YAML"),
    ],
)
def test_a_bad_value_is_a_config_error_naming_file_and_key(tmp_path, old, new, message):
    assert old in MOVEIT1
    path = write(tmp_path, MOVEIT1.replace(old, new, 1))
    with pytest.raises(ConfigError, match=rf"^{path}: .*{message}"):
        mut.load_joint_limits(path)


def test_bad_position_limits_and_layouts_are_config_errors(tmp_path):
    path = write(tmp_path, MOVEIT2.replace("min_position: -1.7628", "min_position: 2"))
    with pytest.raises(ConfigError, match=r"panda_joint2: min_position 2.0 > max_position"):
        mut.load_joint_limits(path)
    path = write(tmp_path, "robot_description_planning: 3\n")
    with pytest.raises(ConfigError, match=r"no robot_description_planning\.joint_limits mapping"):
        mut.load_joint_limits(path)
    with pytest.raises(ConfigError, match=r"no such joint limits file"):
        mut.load_joint_limits(tmp_path / "missing.yaml")
    path = write(tmp_path, "")
    with pytest.raises(ConfigError, match=r"no joint_limits mapping"):
        mut.load_joint_limits(path)
