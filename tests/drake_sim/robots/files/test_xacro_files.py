"""xacro without ROS: arguments, ``$(find pkg)`` from a package map or a callable, the files
read, xacro's globals restored, and a ConfigError naming the file for what goes wrong."""

import pytest
import xacro
from xacro import substitution_args

import drake_sim.robots.files.xacro_files as mut
from drake_sim.base.errors import ConfigError
from tests.planning.model.real_files import moveit_srdf_dir

MAIN = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="robot">
  <xacro:arg name="name" default="bot"/>
  <link name="$(arg name)_base"/>
  <xacro:include filename="$(find parts)/arm.xacro"/>
  <xacro:arm prefix="left_" gripper="$(arg gripper)"/>
</robot>
"""
ARM = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="arm" params="prefix gripper">
    <link name="${prefix}upper"/>
    <xacro:if value="${gripper}"><link name="${prefix}gripper"/></xacro:if>
  </xacro:macro>
</robot>
"""


@pytest.fixture
def files(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "arm.xacro").write_text(ARM)
    main = tmp_path / "robot.urdf.xacro"
    main.write_text(MAIN)
    return main, tmp_path / "parts"


def test_renders_with_arguments_and_a_package_map(files):
    main, parts = files
    dut = mut.render_xacro_file(
        main, xacro_args={"name": "duo", "gripper": True}, package_paths={"parts": parts}
    )
    assert '<link name="duo_base"/>' in dut.text
    assert '<link name="left_upper"/>' in dut.text
    assert '<link name="left_gripper"/>' in dut.text  # True became "true"
    assert dut.files == [main, parts / "arm.xacro"]


def test_find_package_resolves_what_the_map_lacks(files):
    main, parts = files
    asked = []

    def find(name):
        asked.append(name)
        return parts

    dut = mut.render_xacro_file(main, xacro_args={"gripper": "false"}, find_package=find)
    assert asked == ["parts"]
    assert '<link name="bot_base"/>' in dut.text
    assert "left_gripper" not in dut.text


def test_an_unknown_package_is_a_config_error_and_xacro_is_left_as_it_was(files):
    main, _ = files
    find, includes = substitution_args._eval_find, list(xacro.all_includes)
    with pytest.raises(ConfigError, match=rf"^{main}: \$\(find parts\): no folder for package"):
        mut.render_xacro_file(main, xacro_args={"gripper": "1"}, package_paths={"other": "/"})
    assert substitution_args._eval_find is find
    assert xacro.all_includes == includes


def test_xacro_errors_are_config_errors_naming_the_file(files, tmp_path):
    main, parts = files
    with pytest.raises(ConfigError, match=rf"^{main}: xacro failed: .*gripper"):
        mut.render_xacro_file(main, package_paths={"parts": parts})  # $(arg gripper) unset
    with pytest.raises(ConfigError, match=r"^.*empty\.xacro: xacro failed"):
        (tmp_path / "empty.xacro").write_text("<robot")
        mut.render_xacro_file(tmp_path / "empty.xacro")
    with pytest.raises(ConfigError, match=r"missing\.xacro: no such xacro file"):
        mut.render_xacro_file(tmp_path / "missing.xacro")


def test_xacro_value_writes_booleans_as_xacro_reads_them():
    assert [mut.xacro_value(v) for v in (True, False, 1, 0.5, "x")] == [
        "true",
        "false",
        "1",
        "0.5",
        "x",
    ]


def test_renders_moveits_panda_srdf_xacro(tmp_path):
    folder = moveit_srdf_dir()
    (tmp_path / "config").symlink_to(folder)
    dut = mut.render_xacro_file(
        folder / "panda_arm_hand.srdf.xacro",
        package_paths={"moveit_resources_panda_moveit_config": tmp_path},
    )
    assert [path.name for path in dut.files] == [
        "panda_arm_hand.srdf.xacro",
        "panda_arm.xacro",
        "hand.xacro",
    ]
    assert dut.text.count("<disable_collisions") == 34
