"""A wheeled robot from its own description (``mobile_description``): the numbers the
simulation needs are read from the URDF (a small TurtleBot3-like robot written here, and the
real ``turtlebot3_description`` when ``../shared`` is there), mistakes in the names are one
line, and the robot so described drives to a goal."""

import json
from pathlib import Path

import numpy as np
import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.robots.turtlebot3_params import load_turtlebot3_params
from tests import navigation_helpers as nh

REAL = Path(__file__).resolve().parents[4] / "shared" / "real_ros" / "urdf"

WHEEL = """
  <joint name="{side}_wheel" type="continuous">
    <parent link="base_link"/><child link="{side}_tire"/>
    <origin xyz="0 {y} 0.023" rpy="{roll} 0 0"/><axis xyz="0 0 1"/>
  </joint>
  <link name="{side}_tire">
    <collision><geometry><cylinder radius="0.033" length="0.018"/></geometry></collision>
    <visual><geometry><mesh filename="package://nowhere/tire.stl"/></geometry></visual>
    <inertial><mass value="0.1"/><inertia ixx="3e-5" iyy="3e-5" izz="5e-5" ixy="0" ixz="0"
      iyz="0"/></inertial>
  </link>"""

ROBOT = """<robot name="little" xmlns:drake="http://drake.mit.edu">
  <link name="footprint"/>
  <joint name="base_joint" type="fixed">
    <parent link="footprint"/><child link="base_link"/><origin xyz="0 0 0.010"/>
  </joint>
  <link name="base_link">
    <collision><origin xyz="-0.064 0 0.05"/><geometry><box size="0.25 0.25 0.08"/></geometry>
    </collision>
    <collision name="caster"><origin xyz="-0.177 0 0.0"/><geometry><sphere radius="0.01"/>
      </geometry><drake:proximity_properties><drake:mu_dynamic value="0"/>
      <drake:mu_static value="0"/></drake:proximity_properties></collision>
    <inertial><origin xyz="-0.05 0 0.04"/><mass value="1.4"/>
      <inertia ixx="0.009" iyy="0.009" izz="0.015" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  {wheels}
  <joint name="scan_joint" type="fixed">
    <parent link="base_link"/><child link="scan"/>
    <origin xyz="-0.05 0.01 0.14" rpy="{lidar_roll} 0 0"/>
  </joint>
  <link name="scan"/>
</robot>
"""


def write_robot(folder: Path, *, right_roll="-1.5707963", lidar_roll="0", **description) -> Path:
    """A TurtleBot3-like URDF (wheels 0.28 m apart, lidar 0.15 m up) and its robot YAML."""
    wheels = WHEEL.format(side="left", y=0.14, roll="-1.5707963")
    wheels += WHEEL.format(side="right", y=-0.14, roll=right_roll)
    (folder / "little.urdf").write_text(ROBOT.format(wheels=wheels, lidar_roll=lidar_roll))
    keys = dict(
        urdf="little.urdf",
        base_frame="footprint",
        wheel_joints=["left_wheel", "right_wheel"],
        lidar_frame="scan",
    )
    keys.update(description)
    robot = folder / "little.yaml"
    robot.write_text(json.dumps({"description": keys, "limits": {"max_linear_velocity": 0.2}}))
    return robot


def test_the_numbers_come_from_the_description(tmp_path):
    params = load_turtlebot3_params(write_robot(tmp_path))
    assert params.wheel.radius == pytest.approx(0.033)
    assert params.wheel.separation == pytest.approx(0.28)
    assert params.wheel.mass == pytest.approx(0.1)
    assert params.lidar_mount == pytest.approx((-0.05, 0.01, 0.15))
    assert params.description.wheel_signs == [1.0, 1.0]
    assert params.limits.max_linear_velocity == 0.2  # the robot file's own value
    assert params.motor.max_torque == 1.0  # the rest: the shipped TurtleBot3's


def test_a_wheel_turning_the_other_way_gets_a_sign(tmp_path):
    params = load_turtlebot3_params(write_robot(tmp_path, right_roll="1.5707963"))
    assert params.description.wheel_signs == [1.0, -1.0]
    assert params.wheel.separation == pytest.approx(0.28)


@pytest.mark.parametrize(
    "change, needle",
    [
        (dict(wheel_joints=["left_wheel", "nope"]), "'nope' is not a joint"),
        (dict(wheel_joints=["right_wheel", "left_wheel"]), "must be [left, right]"),
        (dict(wheel_joints=["base_joint", "left_wheel"]), "not revolute"),
        (dict(lidar_frame="lidar"), "lidar_frame 'lidar' is not a link or frame"),
        (dict(base_frame="base"), "base_frame 'base' is not a link or frame"),
        (dict(right_roll="0"), "not about its y axis"),
        (dict(lidar_roll="0.5"), "not level"),
        (dict(urdf="missing.urdf"), "does not exist"),
    ],
)
def test_mistakes_are_one_clear_error(tmp_path, change, needle):
    with pytest.raises(ConfigError) as info:
        load_turtlebot3_params(write_robot(tmp_path, **change))
    assert needle in str(info.value) and "little.yaml" in str(info.value)


def test_the_described_robot_drives_to_a_goal(tmp_path):
    """The little robot (its own wheels, casters and lidar height) navigates in the room."""
    _, room_map = nh.saved_truth_map("room", tmp_path)
    robot = write_robot(tmp_path, right_roll="1.5707963")  # a wheel turning the other way too
    args = ["--robot", str(robot), "--map", str(room_map), "--goal", "0", "-1", "90"]
    nh.navigate_to_goals(args, tmp_path)


def real_waffle(tmp_path, variant: str) -> Path:
    """A robot YAML naming the real TurtleBot3 waffle of ``variant`` with a package map whose
    ``turtlebot3_description`` is laid out as the package is (``urdf/``, ``meshes/``)."""
    if not (REAL / variant).is_dir():
        pytest.skip(f"no real TurtleBot3 description at {REAL / variant}")
    package = tmp_path / "turtlebot3_description"
    package.mkdir()
    (package / "urdf").symlink_to(REAL / variant)
    (package / "meshes").symlink_to(REAL / "turtlebot3_description_meshes_noetic" / "meshes")
    urdf = next(p.name for p in (REAL / variant).glob("turtlebot3_waffle.urdf*"))
    robot = tmp_path / "waffle.yaml"
    robot.write_text(
        json.dumps(
            {
                "description": {
                    "urdf": f"turtlebot3_description/urdf/{urdf}",
                    "package_paths": {"turtlebot3_description": "turtlebot3_description"},
                }
            }
        )
    )
    return robot


@pytest.mark.parametrize("variant", ["turtlebot3_noetic", "turtlebot3_humble", "turtlebot3_main"])
def test_the_real_waffle_loads_with_a_package_map(tmp_path, variant):
    """The real waffle (ROS 1 xacro with ``$(find)``; ROS 2 URDF with ``xacro:arg``): the LDS
    at 0.132 m, wheels 0.288 m apart (the REP's 0.287 m plus rounding in the URDF)."""
    params = load_turtlebot3_params(real_waffle(tmp_path, variant))
    assert params.lidar_mount == pytest.approx((-0.064, 0.0, 0.132), abs=1e-6)
    assert params.wheel.radius == pytest.approx(0.033)
    assert params.wheel.separation == pytest.approx(0.288, abs=1e-3)
    assert np.all(np.array(params.description.wheel_signs) == 1.0)
