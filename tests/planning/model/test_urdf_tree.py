"""The URDF kinematic tree: joints with limits, mimic and soft limits, the parent and chain
queries, MoveIt's depth-first joint order, the real VAMP and example-robot-data URDFs, and a
ConfigError naming the file and the element for each kind of malformed URDF."""

import logging

import pytest

import planning.model.urdf_tree as mut
from drake_sim.base.errors import ConfigError
from tests.planning.model.real_files import VAMP_ROBOTS, example_robot_data_dir, vamp_robot_dir

# base -> shoulder -> {b_arm -> b_hand, a_arm}: the file lists b before a; the fingers mimic.
URDF = """<?xml version="1.0"?>
<robot name="toy">
  <link name="base"/> <link name="shoulder"/> <link name="b_arm"/> <link name="b_hand"/>
  <link name="a_arm"/> <link name="finger"/>
  <joint name="pan" type="revolute">
    <parent link="base"/> <child link="shoulder"/>
    <limit lower="-1.5" upper="1.5" velocity="2.0" effort="10"/>
    <safety_controller soft_lower_limit="-1.4" soft_upper_limit="1.4" k_velocity="1"/>
  </joint>
  <joint name="z_b" type="continuous">
    <parent link="shoulder"/> <child link="b_arm"/> <limit velocity="3" effort="1"/>
  </joint>
  <joint name="b_wrist" type="fixed"><parent link="b_arm"/><child link="b_hand"/></joint>
  <joint name="y_a" type="prismatic">
    <parent link="shoulder"/> <child link="a_arm"/> <limit upper="0.3" velocity="0.1" effort="5"/>
  </joint>
  <joint name="grip" type="prismatic">
    <parent link="b_hand"/> <child link="finger"/> <limit upper="0.04" velocity="0.1" effort="5"/>
    <mimic joint="y_a" multiplier="-2" offset="0.01"/>
  </joint>
  <transmission name="t"><joint name="pan"/><joint name="ghost"/></transmission>
</robot>
"""


@pytest.fixture
def dut() -> mut.UrdfTree:
    return mut.read_urdf_tree(URDF, "toy.urdf")


def test_reads_links_joints_and_limits(dut):
    assert dut.robot_name == "toy"
    assert dut.where == "toy.urdf"
    assert dut.links == ["base", "shoulder", "b_arm", "b_hand", "a_arm", "finger"]
    assert list(dut.joints) == ["pan", "z_b", "b_wrist", "y_a", "grip"]  # not the transmission's
    pan = dut.joints["pan"]
    assert (pan.type, pan.parent, pan.child) == ("revolute", "base", "shoulder")
    assert (pan.lower, pan.upper, pan.velocity, pan.effort) == (-1.5, 1.5, 2.0, 10.0)
    assert (pan.soft_lower, pan.soft_upper) == (-1.4, 1.4)
    continuous = dut.joints["z_b"]
    assert (continuous.lower, continuous.upper, continuous.velocity) == (None, None, 3.0)
    assert dut.joints["y_a"].lower == 0.0  # urdfdom's default
    assert dut.joints["b_wrist"].velocity is None
    grip = dut.joints["grip"]
    assert (grip.mimic, grip.mimic_multiplier, grip.mimic_offset) == ("y_a", -2.0, 0.01)
    actuated = [name for name, joint in dut.joints.items() if joint.is_actuated]
    assert actuated == ["pan", "z_b", "y_a"]


def test_parent_joint_and_root(dut):
    assert dut.root_link == "base"
    assert dut.parent_joint("base") is None
    assert dut.parent_joint("finger").name == "grip"
    with pytest.raises(ConfigError, match=r"toy\.urdf: no link 'elbow' in robot 'toy'"):
        dut.parent_joint("elbow")


def test_chain_goes_down_from_base_to_tip(dut):
    assert dut.chain("base", "finger") == ["pan", "z_b", "b_wrist", "grip"]
    assert dut.chain("shoulder", "a_arm") == ["y_a"]
    assert dut.chain("b_arm", "b_arm") == []
    with pytest.raises(ConfigError, match="no chain from 'a_arm' to 'finger'"):
        dut.chain("a_arm", "finger")
    with pytest.raises(ConfigError, match="no link 'nowhere'"):
        dut.chain("base", "nowhere")


def test_path_goes_through_the_common_ancestor(dut):
    assert dut.path("a_arm", "finger") == ["y_a", "z_b", "b_wrist", "grip"]
    assert dut.path("base", "b_hand") == dut.chain("base", "b_hand")
    assert dut.path("finger", "base") == ["grip", "b_wrist", "z_b", "pan"]
    with pytest.raises(ConfigError, match="no link 'nowhere'"):
        dut.path("base", "nowhere")


def test_depth_first_order_visits_children_by_name(dut):
    assert [j.name for j in dut.child_joints("shoulder")] == ["y_a", "z_b"]
    assert dut.depth_first_joints() == ["pan", "y_a", "z_b", "b_wrist", "grip"]


def test_a_mimic_of_an_unknown_joint_is_kept_as_an_ordinary_joint(caplog):
    text = URDF.replace('mimic joint="y_a"', 'mimic joint="nothing"')
    with caplog.at_level(logging.WARNING):
        dut = mut.read_urdf_tree(text, "toy.urdf")
    assert dut.joints["grip"].mimic is None
    assert dut.joints["grip"].is_actuated
    assert "grip (mimics nothing)" in caplog.text


@pytest.mark.parametrize(
    "old, new, message",
    [
        ("<robot", "<robots", r"not XML"),
        ('<robot name="toy">', "<robot>", r"<robot> has no 'name' attribute"),
        ('<link name="finger"/>', '<link name="base"/>', r"link 'base' is defined twice"),
        ('name="z_b"', 'name="pan"', r"joint 'pan' is defined twice"),
        ('type="continuous"', 'type="ball"', r"joint 'z_b': unknown type 'ball'"),
        ('<parent link="base"/>', "", r"joint 'pan': no <parent> element"),
        ('<child link="a_arm"/>', '<child link="b_arm"/>', r"'b_arm' is the child of two"),
        ('<child link="a_arm"/>', '<child link="c_arm"/>', r"child link 'c_arm' is not a link"),
        ('<limit lower="-1.5"', '<limit lower="nan"', r"lower='nan' is not a finite number"),
        ('upper="1.5"', 'upper="one"', r"joint 'pan': <limit> upper='one' is not a finite"),
        ('upper="1.5"', 'upper="-2"', r"joint 'pan': <limit> lower -1.5 > upper -2.0"),
        ('velocity="2.0"', 'velocity="-2"', r"joint 'pan': <limit> velocity -2.0 is negative"),
        ('<limit upper="0.3" velocity="0.1" effort="5"/>', "", r"'y_a': a prismatic joint needs"),
        ('offset="0.01"', 'offset="inf"', r"joint 'grip': <mimic> offset='inf' is not a finite"),
        ('<child link="shoulder"/>', '<child link="base"/>', r"a cycle through link 'base'"),
        ('<link name="a_arm"/>', '<link name="a_arm"/><link name="lost"/>', r"'base', 'lost'"),
    ],
)
def test_a_malformed_urdf_is_a_config_error_naming_file_and_element(old, new, message):
    assert old in URDF
    with pytest.raises(ConfigError, match=r"^toy\.urdf: .*" + message):
        mut.read_urdf_tree(URDF.replace(old, new, 1), "toy.urdf")


def test_a_cycle_is_a_config_error():
    text = """<robot name="loop"><link name="root"/><link name="a"/><link name="b"/>
      <joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>
      <joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint></robot>"""
    with pytest.raises(ConfigError, match=r"loop\.urdf: the joints form a cycle"):
        mut.read_urdf_tree(text, "loop.urdf")


def test_another_root_element_is_a_config_error():
    with pytest.raises(ConfigError, match=r"x\.urdf: the root element is <sdf>"):
        mut.read_urdf_tree("<sdf/>", "x.urdf")


@pytest.mark.parametrize(
    "robot, links, joints, actuated, root",
    [
        ("panda", 13, 12, 7, "panda_link0"),
        ("ur5", 22, 21, 6, "offset_link"),
        ("fetch", 17, 16, 8, "base_link"),
        ("baxter", 49, 48, 14, "base"),
    ],
)
def test_reads_the_vamp_urdfs(robot, links, joints, actuated, root):
    assert robot in VAMP_ROBOTS
    path = vamp_robot_dir(robot) / f"{robot}.urdf"
    dut = mut.read_urdf_tree(path.read_text(), str(path))
    assert (len(dut.links), len(dut.joints), dut.root_link) == (links, joints, root)
    assert sum(joint.is_actuated for joint in dut.joints.values()) == actuated
    assert sorted(dut.depth_first_joints()) == sorted(dut.joints)


def test_reads_the_example_robot_data_panda():
    path = example_robot_data_dir() / "panda_description" / "urdf" / "panda.urdf"
    dut = mut.read_urdf_tree(path.read_text(), str(path))
    assert (dut.robot_name, len(dut.links), len(dut.joints)) == ("panda", 13, 12)
    assert dut.chain("panda_link0", "panda_link8") == [f"panda_joint{i}" for i in range(1, 9)]
    joint1 = dut.joints["panda_joint1"]
    assert (joint1.lower, joint1.upper, joint1.velocity) == (-2.8973, 2.8973, 2.175)
    assert (joint1.soft_lower, joint1.soft_upper) == (-2.8973, 2.8973)
    assert dut.joints["panda_finger_joint2"].mimic == "panda_finger_joint1"
