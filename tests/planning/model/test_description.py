"""The robot description: the YAML (paths relative to it, URIs kept, unused keys warned about,
a ConfigError naming the file and the key for bad input) and MoveIt config folders (with and
without a ``.setup_assistant``; the real Panda SRDF files in them)."""

import logging
from pathlib import Path

import pytest

import planning.model.description as mut
from drake_sim.base.errors import ConfigError
from tests.planning.model.real_files import moveit_srdf_dir

YAML = """
urdf: files/robot.urdf.xacro
srdf: files/robot.srdf
package_paths: {parts: parts, ur_description: "package://example-robot-data/robots/ur_description"}
group: manipulator
joint_limits: files/joint_limits.yaml
xacro_args: {name: ur5, gripper: true, scale: 2}
"""


@pytest.fixture
def folder(tmp_path) -> Path:
    for name in ("robot.urdf.xacro", "robot.srdf", "joint_limits.yaml"):
        (tmp_path / "files").mkdir(exist_ok=True)
        (tmp_path / "files" / name).write_text("")
    (tmp_path / "parts").mkdir()
    (tmp_path / "robot.yaml").write_text(YAML)
    return tmp_path


def test_reads_a_description_with_paths_relative_to_it(folder, caplog):
    with caplog.at_level(logging.WARNING):
        dut = mut.load_robot_description(folder / "robot.yaml")
    files = folder / "files"
    assert dut == mut.RobotDescription(
        urdf=str(files / "robot.urdf.xacro"),
        srdf=str(files / "robot.srdf"),
        package_paths={
            "parts": str(folder / "parts"),
            "ur_description": "package://example-robot-data/robots/ur_description",
        },
        group="manipulator",
        joint_limits=str(files / "joint_limits.yaml"),
        xacro_args={"name": "ur5", "gripper": "true", "scale": "2"},
        source=str(folder / "robot.yaml"),
    )
    assert caplog.records == []


def test_uris_stay_as_written_and_optional_keys_may_go(tmp_path):
    path = tmp_path / "ur5.yaml"
    path.write_text(
        "urdf: package://vamp_resources/ur5/ur5.urdf\n"
        "srdf: $(find vamp_resources)/ur5/ur5.srdf\n"
        "group: manipulator\n"
    )
    dut = mut.load_robot_description(path)
    assert (dut.urdf, dut.srdf) == ("package://vamp_resources/ur5/ur5.urdf", dut.srdf)
    assert dut.srdf == "$(find vamp_resources)/ur5/ur5.srdf"
    assert (dut.package_paths, dut.joint_limits, dut.xacro_args) == ({}, "", {})
    assert mut.is_uri("file:///robot.urdf") and not mut.is_uri("robot.urdf")


def test_arguments_replace_the_files_group_and_packages(folder, tmp_path):
    dut = mut.load_robot_description(
        folder / "robot.yaml", group="arm", package_paths={"parts": tmp_path / "files"}
    )
    assert dut.group == "arm"
    assert dut.package_paths["parts"] == str(tmp_path / "files")


def test_unused_keys_are_one_warning_line(folder, caplog):
    (folder / "robot.yaml").write_text(YAML + "planner: rrt\nend_effector: hand\n")
    with caplog.at_level(logging.WARNING):
        mut.load_robot_description(folder / "robot.yaml")
    assert [r.getMessage() for r in caplog.records] == [
        f"{folder / 'robot.yaml'}: keys not used (ignored): planner, end_effector"
    ]


@pytest.mark.parametrize(
    "old, new, message",
    [
        ("urdf: files/robot.urdf.xacro\n", "", r"urdf: missing"),
        ("group: manipulator", "group: ''", r"group must be a non-empty string"),
        ("group: manipulator", "group: [a, b]", r"group must be a non-empty string"),
        ("srdf: files/robot.srdf", "srdf: files/other.srdf", r"srdf: no such file .*other\.srdf"),
        ("joint_limits: files/", "joint_limits: ", r"joint_limits: no such file"),
        ("{parts: parts,", "{parts: wheels,", r"package_paths\.parts: no such folder .*wheels"),
        ("{parts: parts,", "{parts: 3,", r"package_paths\.parts must be a folder path"),
        ("package_paths: {", "package_paths: [", r"malformed YAML"),
        ("xacro_args: {name: ur5,", "xacro_args: {name: [ur5],", r"xacro_args\.name must be a"),
        ("xacro_args: {", "xacro_args: 3 #", r"xacro_args must be a mapping"),
    ],
)
def test_bad_input_is_a_config_error_naming_file_and_key(folder, old, new, message):
    assert old in YAML
    (folder / "robot.yaml").write_text(YAML.replace(old, new, 1))
    with pytest.raises(ConfigError, match=rf"^{folder / 'robot.yaml'}: {message}"):
        mut.load_robot_description(folder / "robot.yaml")


def test_a_file_that_is_not_a_description_is_a_config_error(tmp_path):
    (tmp_path / "list.yaml").write_text("- urdf\n")
    with pytest.raises(ConfigError, match=r"list\.yaml: a robot description is a mapping"):
        mut.load_robot_description(tmp_path / "list.yaml")
    with pytest.raises(ConfigError, match=r"none\.yaml: no such robot description"):
        mut.load_robot_description(tmp_path / "none.yaml")


# MoveIt config folders, holding the real Panda SRDF files.

PACKAGE_XML = """<?xml version="1.0"?>
<package format="3"><name>moveit_resources_panda_moveit_config</name><version>2.0.0</version>
</package>"""
SETUP_ASSISTANT_1 = """moveit_setup_assistant_config:
  URDF:
    package: moveit_resources_panda_description
    relative_path: urdf/panda.urdf
    xacro_args: ""
  SRDF:
    relative_path: config/panda.srdf
  CONFIG:
    author_name: MoveIt maintainer team
"""
SETUP_ASSISTANT_2 = """moveit_setup_assistant_config:
  urdf:
    package: panda_description
    relative_path: urdf/panda.urdf.xacro
    xacro_args: "hand:=true arm_id:='panda arm'"
  srdf:
    relative_path: config/panda.srdf
"""


def moveit_config(tmp_path, files, setup_assistant=None) -> Path:
    """A ``panda_moveit_config`` folder whose config/ links to the real ``files``."""
    folder = tmp_path / "panda_moveit_config"
    (folder / "config").mkdir(parents=True)
    (folder / "package.xml").write_text(PACKAGE_XML)
    for name in files:
        (folder / "config" / name).symlink_to(moveit_srdf_dir() / name)
    if setup_assistant:
        (folder / ".setup_assistant").write_text(setup_assistant)
    return folder


def test_reads_a_moveit1_config_folder(tmp_path):
    folder = moveit_config(tmp_path, ["panda.srdf", "vamp_panda.srdf"], SETUP_ASSISTANT_1)
    (folder / "config" / "joint_limits.yaml").write_text("joint_limits: {}\n")
    dut = mut.load_robot_description(folder)
    assert dut == mut.RobotDescription(
        urdf="package://moveit_resources_panda_description/urdf/panda.urdf",
        srdf=str(folder / "config" / "panda.srdf"),
        package_paths={"moveit_resources_panda_moveit_config": str(folder)},
        group="panda_arm",  # the parent group of the end effector "hand"
        joint_limits=str(folder / "config" / "joint_limits.yaml"),
        source=str(folder),
    )


def test_reads_a_moveit2_setup_assistant_with_xacro_arguments(tmp_path):
    folder = moveit_config(tmp_path, ["panda.srdf"], SETUP_ASSISTANT_2)
    dut = mut.load_robot_description(folder, group="hand")
    assert dut.urdf == "package://panda_description/urdf/panda.urdf.xacro"
    assert dut.xacro_args == {"hand": "true", "arm_id": "panda arm"}
    assert (dut.group, dut.joint_limits) == ("hand", "")


def test_without_a_setup_assistant_takes_the_one_urdf_and_srdf_in_config(tmp_path):
    names = ["panda_arm_hand.srdf.xacro", "panda_arm.xacro", "hand.xacro"]
    folder = moveit_config(tmp_path, names)
    (folder / "config" / "panda.urdf.xacro").write_text("<robot name='panda'/>")
    dut = mut.load_robot_description(folder)  # $(find) of the folder's own package resolves
    assert dut.urdf == str(folder / "config" / "panda.urdf.xacro")
    assert dut.srdf == str(folder / "config" / "panda_arm_hand.srdf.xacro")
    assert dut.group == "panda_arm"


def test_an_ambiguous_or_incomplete_config_folder_is_a_config_error(tmp_path):
    folder = moveit_config(tmp_path, ["panda.srdf", "vamp_panda.srdf"])
    with pytest.raises(ConfigError, match=r"panda_moveit_config: no URDF found"):
        mut.load_robot_description(folder)
    (folder / "config" / "panda.urdf").write_text("<robot name='panda'/>")
    with pytest.raises(ConfigError, match=r"several \*\.srdf files in config/ \(panda\.srdf, "):
        mut.load_robot_description(folder)
    (folder / ".setup_assistant").write_text("moveit_setup_assistant_config: 3\n")
    with pytest.raises(ConfigError, match=r"\.setup_assistant: no moveit_setup_assistant_config"):
        mut.load_robot_description(folder)
