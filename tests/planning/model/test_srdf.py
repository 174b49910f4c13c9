"""The SRDF: what is read (groups, states, end effectors, pairs, virtual and passive joints), the
group joints in MoveIt's order, the check against a URDF, the real MoveIt, VAMP and
example-robot-data SRDFs (xacro ones rendered with a package map), and a ConfigError naming
the file and the element for each kind of malformed SRDF."""

import logging

import pytest

import planning.model.srdf as mut
from drake_sim.base.errors import ConfigError
from planning.model.srdf_check import check_srdf
from planning.model.urdf_tree import read_urdf_tree
from tests.planning.model.real_files import (
    example_robot_data_dir,
    moveit_srdf_dir,
    vamp_robot_dir,
)

# A torso with two arms, r before l in the file; each arm: shoulder, elbow, a fixed tool and a
# gripper whose second finger mimics the first.
URDF = """<robot name="duo">
  <link name="torso"/>
  {arms}
</robot>"""
ARM = """
  <link name="{s}_upper"/> <link name="{s}_lower"/> <link name="{s}_tool"/> <link name="{s}_f1"/>
  <link name="{s}_f2"/>
  <joint name="{s}_shoulder" type="revolute"><parent link="torso"/><child link="{s}_upper"/>
    <limit lower="-2" upper="2" velocity="1" effort="1"/></joint>
  <joint name="{s}_elbow" type="revolute"><parent link="{s}_upper"/><child link="{s}_lower"/>
    <limit lower="-2" upper="2" velocity="1" effort="1"/></joint>
  <joint name="{s}_tool_joint" type="fixed"><parent link="{s}_lower"/><child link="{s}_tool"/>
  </joint>
  <joint name="{s}_finger1" type="prismatic"><parent link="{s}_tool"/><child link="{s}_f1"/>
    <limit upper="0.04" velocity="0.1" effort="1"/></joint>
  <joint name="{s}_finger2" type="prismatic"><parent link="{s}_tool"/><child link="{s}_f2"/>
    <limit upper="0.04" velocity="0.1" effort="1"/><mimic joint="{s}_finger1"/></joint>"""
SRDF = """<?xml version="1.0"?>
<robot name="duo">
  <group name="r_arm"><chain base_link="torso" tip_link="r_tool"/></group>
  <group name="l_arm"><joint name="l_elbow"/><joint name="l_shoulder"/></group>
  <group name="l_hand"><link name="l_f1"/><link name="l_f2"/></group>
  <group name="both"><group name="r_arm"/><group name="l_arm"/></group>
  <group name="tips"><chain base_link="l_f1" tip_link="r_f1"/></group>
  <group_state name="home" group="both">
    <joint name="r_shoulder" value="0.5"/> <joint name="l_shoulder" value="-0.5"/>
    <joint name="r_elbow" value="1e-1"/> <joint name="l_elbow" value="0"/>
  </group_state>
  <group_state name="open" group="l_hand">
    <joint name="l_finger1" value="0.04"/> <joint name="l_finger2" value="0.04"/>
  </group_state>
  <end_effector name="l_gripper" group="l_hand" parent_link="l_tool" parent_group="l_arm"/>
  <virtual_joint name="world_joint" type="Fixed" parent_frame="world" child_link="torso"/>
  <disable_collisions link1="torso" link2="r_upper" reason="Adjacent"/>
  <disable_collisions link1="r_f1" link2="r_f2"/>
  <passive_joint name="r_finger1"/>
  <link_sphere_approximation link="torso"/>
</robot>
"""
OPEN_AGAIN = '<group_state name="open" group="l_hand"/><end_effector'


@pytest.fixture
def tree():
    return read_urdf_tree(URDF.format(arms=ARM.format(s="r") + ARM.format(s="l")), "duo.urdf")


@pytest.fixture
def dut() -> mut.Srdf:
    return mut.parse_srdf(SRDF, "duo.srdf")


def test_reads_every_element(dut, caplog):
    assert (dut.robot_name, dut.where) == ("duo", "duo.srdf")
    assert list(dut.groups) == ["r_arm", "l_arm", "l_hand", "both", "tips"]
    assert dut.groups["r_arm"].chains == [("torso", "r_tool")]
    assert dut.groups["l_arm"].joints == ["l_elbow", "l_shoulder"]
    assert dut.groups["l_hand"].links == ["l_f1", "l_f2"]
    assert dut.groups["both"].subgroups == ["r_arm", "l_arm"]
    home = dut.group_states["both"]["home"]
    assert home == {"r_shoulder": [0.5], "l_shoulder": [-0.5], "r_elbow": [0.1], "l_elbow": [0.0]}
    assert dut.end_effectors == [mut.EndEffector("l_gripper", "l_hand", "l_tool", "l_arm")]
    assert dut.virtual_joints == [mut.VirtualJoint("world_joint", "fixed", "world", "torso")]
    assert dut.disabled_collisions == [("torso", "r_upper", "Adjacent"), ("r_f1", "r_f2", "")]
    assert dut.passive_joints == ["r_finger1"]


def test_warns_once_about_what_it_does_not_use(caplog):
    with caplog.at_level(logging.WARNING):
        mut.parse_srdf(
            SRDF.replace('<group_state name="open" group="l_hand">', '<group_state name="open">'),
            "duo.srdf",
        )
    lines = [r.getMessage() for r in caplog.records]
    assert lines == [
        "duo.srdf: SRDF elements not used (ignored): link_sphere_approximation, "
        "group_state 'open' (it names no group)"
    ]


def test_group_joints_come_in_the_urdf_depth_first_order(dut, tree):
    # The torso's children by joint name: l_ before r_, whatever the SRDF's order.
    both = ["l_shoulder", "l_elbow", "r_shoulder", "r_elbow"]
    assert mut.group_joint_names(dut, "both", tree) == both
    assert mut.group_joint_names(dut, "l_arm", tree) == ["l_shoulder", "l_elbow"]
    assert mut.group_joint_names(dut, "r_arm", tree) == ["r_shoulder", "r_elbow"]
    assert mut.group_joint_names(dut, "l_hand", tree) == ["l_finger1"]  # finger2 mimics it
    # A chain between two leaves goes through their common ancestor; passive r_finger1 is out.
    tips = ["l_shoulder", "l_elbow", "l_finger1", "r_shoulder", "r_elbow"]
    assert mut.group_joint_names(dut, "tips", tree) == tips


def test_an_unknown_group_is_a_config_error_naming_the_known_ones(dut, tree):
    with pytest.raises(ConfigError, match=r"duo\.srdf: no group 'arm' \(the groups are: r_arm, "):
        mut.group_joint_names(dut, "arm", tree)


@pytest.mark.parametrize(
    "old, new, message",
    [
        ('<joint name="l_elbow"/>', '<joint name="l_wrist"/>', r"'l_arm': joint 'l_wrist' is not"),
        ('<link name="l_f2"/>', '<link name="l_f3"/>', r"'l_hand': link 'l_f3' is not in the URDF"),
        (
            'base_link="torso"',
            'base_link="chest"',
            r"'r_arm': chain 'chest' -> 'r_tool': .*'chest'",
        ),
    ],
)
def test_a_group_naming_what_the_urdf_lacks_is_a_config_error(tree, old, new, message):
    srdf = mut.parse_srdf(SRDF.replace(old, new, 1), "duo.srdf")
    with pytest.raises(ConfigError, match=r"^duo\.srdf: group " + message):
        check_srdf(srdf, tree, strict=True)


def test_check_keeps_what_matches_and_drops_what_moveit_drops(dut, tree, caplog):
    text = SRDF.replace(
        '<disable_collisions link1="r_f1"',
        '<disable_collisions link1="camera" link2="torso"/>\n  <disable_collisions link1="r_f1"',
    ).replace('<joint name="l_finger2" value="0.04"/>', '<joint name="r_elbow" value="1"/>')
    with caplog.at_level(logging.WARNING):
        checked = check_srdf(mut.parse_srdf(text, "duo.srdf"), tree)
    assert checked.disabled_collisions == dut.disabled_collisions
    assert checked.group_states["l_hand"]["open"] == {"l_finger1": [0.04]}
    assert checked.group_states["both"] == dut.group_states["both"]
    assert "1 disable_collisions pairs naming links camera" in caplog.text
    assert "group_state open values of r_elbow (fixed or not in l_hand)" in caplog.text
    assert check_srdf(dut, tree) == dut  # nothing to drop


@pytest.mark.parametrize(
    "old, new, message",
    [
        ('name="r_elbow" value="1e-1"', 'name="r_wrist" value="1"', r"joint 'r_wrist' is not in"),
        ('value="1e-1"', 'value="0.1 0.2"', r"joint 'r_elbow' has 2 values, not 1"),
        ('parent_link="l_tool"', 'parent_link="l_palm"', r"parent_link 'l_palm' is not a link"),
        ('child_link="torso"', 'child_link="pelvis"', r"child_link 'pelvis' is not a link"),
        ('<passive_joint name="r_finger1"/>', '<passive_joint name="r_thumb"/>', r"'r_thumb' is"),
    ],
)
def test_other_names_the_urdf_lacks_are_config_errors(tree, old, new, message):
    assert old in SRDF
    srdf = mut.parse_srdf(SRDF.replace(old, new, 1), "duo.srdf")
    with pytest.raises(ConfigError, match=r"^duo\.srdf: .*" + message):
        check_srdf(srdf, tree, strict=True)


@pytest.mark.parametrize(
    "old, new, message",
    [
        ("<robot name", "<robot name=", r"not XML"),
        ('<robot name="duo">', "<robot>", r"<robot> has no 'name'"),
        ('group="both"', 'group="all"', r"group_state 'home': group 'all' is not a group \(the"),
        ('value="0.5"', 'value="nan"', r"group_state 'home' joint 'r_shoulder': .*'nan' is not a"),
        ('value="0.5"', 'value="half"', r"'r_shoulder': <joint> value='half' is not a finite"),
        ('value="0.5"', 'value=""', r"<joint name='r_shoulder'> has no 'value'"),
        ('name="l_elbow" value="0"', 'name="l_shoulder" value="0"', r"'l_shoulder' is given twice"),
        ("<end_effector", OPEN_AGAIN, r"group_state 'open': group 'l_hand' has two states"),
        ('name="tips"', 'name="both"', r"group 'both' is defined twice"),
        ('<group name="l_arm"/>', '<group name="legs"/>', r"group 'both' has unknown subgroup"),
        ('<group name="l_arm"/>', '<group name="both"/>', r"groups contain themselves: both -> b"),
        ('group="l_hand" parent_link', 'group="hand" parent_link', r"group 'hand' is not a group"),
        ('parent_group="l_arm"', 'parent_group="arm"', r"parent_group 'arm' is not a group"),
        ('type="Fixed"', 'type="ball"', r"virtual_joint 'world_joint': type 'ball' is not one"),
        ('link2="r_upper"', "", r"<disable_collisions> has no 'link2'"),
        ('tip_link="r_tool"', "", r"group 'r_arm': <chain> has no 'tip_link'"),
    ],
)
def test_a_malformed_srdf_is_a_config_error_naming_file_and_element(old, new, message):
    assert old in SRDF
    with pytest.raises(ConfigError, match=r"^duo\.srdf: .*" + message):
        mut.parse_srdf(SRDF.replace(old, new, 1), "duo.srdf")


def test_load_srdf_reads_a_file_and_names_it(tmp_path):
    path = tmp_path / "duo.srdf"
    path.write_text(SRDF)
    assert mut.load_srdf(path) == mut.parse_srdf(SRDF, str(path))
    with pytest.raises(ConfigError, match=r"missing\.srdf: no such SRDF file"):
        mut.load_srdf(tmp_path / "missing.srdf")
    path.write_text("<robot")
    with pytest.raises(ConfigError, match=rf"^{path}: not XML"):
        mut.load_srdf(path)


# The real files.


@pytest.fixture
def panda_tree():
    path = example_robot_data_dir() / "panda_description" / "urdf" / "panda.urdf"
    return read_urdf_tree(path.read_text(), str(path))


@pytest.fixture
def moveit_config(tmp_path):
    """A package map in which the real folder stands for moveit_resources_panda_moveit_config
    (its files sit in the package's config/ folder)."""
    (tmp_path / "config").symlink_to(moveit_srdf_dir())
    return {"moveit_resources_panda_moveit_config": str(tmp_path)}


def check_moveit_panda(srdf: mut.Srdf, panda_tree) -> None:
    """MoveIt's Panda SRDF (panda_moveit_config): its groups, states, pairs and joints."""
    assert srdf.robot_name == "panda"
    assert sorted(srdf.groups) == ["hand", "panda_arm", "panda_arm_hand"]
    assert srdf.groups["panda_arm"].chains == [("panda_link0", "panda_link8")]
    assert list(srdf.group_states["panda_arm"]) == ["ready", "extended", "transport"]
    assert srdf.group_states["panda_arm"]["ready"]["panda_joint4"] == [-2.356]
    assert srdf.group_states["hand"]["open"] == {
        "panda_finger_joint1": [0.035],
        "panda_finger_joint2": [0.035],
    }
    assert srdf.end_effectors == [mut.EndEffector("hand", "hand", "panda_link8", "panda_arm")]
    assert srdf.virtual_joints == [
        mut.VirtualJoint("virtual_joint", "floating", "world", "panda_link0")
    ]
    assert len(srdf.disabled_collisions) == 34
    assert ("panda_hand", "panda_link7", "Adjacent") in srdf.disabled_collisions
    assert srdf.passive_joints == []  # its passive_joint sits inside a group: srdfdom skips it
    arm = [f"panda_joint{i}" for i in range(1, 8)]
    assert mut.group_joint_names(srdf, "panda_arm", panda_tree) == arm
    assert mut.group_joint_names(srdf, "hand", panda_tree) == ["panda_finger_joint1"]
    assert mut.group_joint_names(srdf, "panda_arm_hand", panda_tree) == [
        *arm,
        "panda_finger_joint1",
    ]
    assert check_srdf(srdf, panda_tree) == srdf  # the mimic finger's values stay, as in MoveIt


@pytest.mark.parametrize("name", ["panda.srdf", "vamp_panda.srdf"])
def test_reads_moveits_panda_srdf(name, panda_tree):
    check_moveit_panda(mut.load_srdf(moveit_srdf_dir() / name), panda_tree)


def test_renders_moveits_srdf_xacro_with_a_package_map(moveit_config, panda_tree):
    path = moveit_srdf_dir() / "panda_arm_hand.srdf.xacro"
    dut = mut.load_srdf(path, package_paths=moveit_config)
    check_moveit_panda(dut, panda_tree)
    assert dut.where == str(path)
    generated = mut.load_srdf(moveit_srdf_dir() / "panda.srdf")  # xacro's output, committed
    assert sorted(dut.disabled_collisions) == sorted(generated.disabled_collisions)
    assert dut.group_states == generated.group_states


def test_renders_the_arm_only_srdf_xacro(moveit_config, panda_tree):
    dut = mut.load_srdf(moveit_srdf_dir() / "panda_arm.srdf.xacro", package_paths=moveit_config)
    assert list(dut.groups) == ["panda_arm"]
    assert list(dut.group_states) == ["panda_arm"]
    assert len(dut.disabled_collisions) == 19
    assert check_srdf(dut, panda_tree) == dut


@pytest.mark.parametrize("name", ["panda_arm.xacro", "hand.xacro"])
def test_the_macro_files_define_nothing_by_themselves(name, moveit_config):
    dut = mut.load_srdf(moveit_srdf_dir() / name, package_paths=moveit_config)
    assert (dut.robot_name, dut.groups, dut.disabled_collisions) == ("panda", {}, [])


def test_an_srdf_xacro_without_its_package_is_a_config_error():
    path = moveit_srdf_dir() / "panda_arm_hand.srdf.xacro"
    with pytest.raises(ConfigError, match=r"no folder for package 'moveit_resources_panda_moveit"):
        mut.load_srdf(path)


@pytest.mark.parametrize(
    "robot, group, count, first, pairs",
    [
        ("panda", "panda_arm", 7, "panda_joint1", 34),
        ("ur5", "manipulator", 6, "shoulder_pan_joint", 88),
        ("fetch", "arm_with_torso", 8, "torso_lift_joint", 162 - 87),
        ("baxter", "both_arms", 14, "left_s0", 450 - 112),
    ],
)
def test_reads_the_vamp_srdfs(robot, group, count, first, pairs):
    folder = vamp_robot_dir(robot)
    tree = read_urdf_tree((folder / f"{robot}.urdf").read_text(), f"{robot}.urdf")
    dut = check_srdf(mut.load_srdf(folder / f"{robot}.srdf"), tree)
    names = mut.group_joint_names(dut, group, tree)
    assert (len(names), names[0], len(dut.disabled_collisions)) == (count, first, pairs)
    for states in dut.group_states.values():
        for values in states.values():
            for joint, value in values.items():
                lower, upper = tree.joints[joint].lower, tree.joints[joint].upper
                assert lower <= value[0] <= upper, (robot, joint)


def test_baxters_both_arms_come_left_first_as_motionbenchmaker_lists_them():
    folder = vamp_robot_dir("baxter")
    tree = read_urdf_tree((folder / "baxter.urdf").read_text(), "baxter.urdf")
    dut = mut.load_srdf(folder / "baxter.srdf")
    assert dut.groups["both_arms"].subgroups == ["right_arm", "left_arm"]
    arm = ["s0", "s1", "e0", "e1", "w0", "w1", "w2"]
    expected = [f"left_{j}" for j in arm] + [f"right_{j}" for j in arm]
    assert mut.group_joint_names(dut, "both_arms", tree) == expected
    assert dut.passive_joints == ["virtual_joint"]  # the virtual joint: not an error


def test_reads_the_example_robot_data_panda_srdf(panda_tree):
    dut = mut.load_srdf(example_robot_data_dir() / "panda_description" / "srdf" / "panda.srdf")
    assert list(dut.groups) == ["arm", "hand", "arm_and_hand"]
    assert len(mut.group_joint_names(dut, "arm", panda_tree)) == 7
    assert len(mut.group_joint_names(dut, "arm_and_hand", panda_tree)) == 8
    assert len(dut.group_states["arm_and_hand"]["default"]) == 8
    assert len(dut.disabled_collisions) == 35
    assert check_srdf(dut, panda_tree) == dut
