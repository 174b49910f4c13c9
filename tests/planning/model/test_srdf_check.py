"""planning.model.srdf_check: what names something the URDF lacks is dropped with one warning
line, as MoveIt drops it, and the rest is kept; ``strict`` raises instead."""

import logging

import pytest

import planning.model.srdf_check as mut
from drake_sim.base.errors import ConfigError
from planning.model.srdf import parse_srdf
from planning.model.urdf_tree import read_urdf_tree
from tests.planning.model.test_srdf import ARM, SRDF, URDF


@pytest.fixture
def tree():
    return read_urdf_tree(URDF.format(arms=ARM.format(s="r") + ARM.format(s="l")), "duo.urdf")


def test_a_group_naming_an_unknown_joint_is_dropped_with_what_is_built_on_it(tree, caplog):
    text = SRDF.replace('<joint name="l_elbow"/>', '<joint name="l_wrist"/>', 1)
    with caplog.at_level(logging.WARNING):
        checked = mut.check_srdf(parse_srdf(text, "duo.srdf"), tree)
    assert "l_arm" not in checked.groups and "r_arm" in checked.groups
    assert all(e.group in checked.groups for e in checked.end_effectors)
    assert set(checked.group_states) <= set(checked.groups)
    assert any("group 'l_arm': joint 'l_wrist' is not" in d for d in checked.dropped)
    assert "dropped on duo.urdf, as MoveIt does" in caplog.text and "l_wrist" in caplog.text
    with pytest.raises(ConfigError, match="l_wrist"):
        mut.check_srdf(parse_srdf(text, "duo.srdf"), tree, strict=True)


@pytest.mark.parametrize(
    "old, new, needle",
    [
        ('name="r_elbow" value="1e-1"', 'name="r_wrist" value="1"', "joint 'r_wrist' is not in"),
        ('value="1e-1"', 'value="0.1 0.2"', "joint 'r_elbow' has 2 values, not 1"),
        ('parent_link="l_tool"', 'parent_link="l_palm"', "parent_link 'l_palm' is not a link"),
        ('child_link="torso"', 'child_link="pelvis"', "child_link 'pelvis' is not a link"),
        ('<passive_joint name="r_finger1"/>', '<passive_joint name="r_thumb"/>', "'r_thumb' is"),
    ],
)
def test_other_unknown_names_drop_their_element_only(tree, old, new, needle):
    text = SRDF.replace(old, new, 1)
    full = mut.check_srdf(parse_srdf(SRDF, "duo.srdf"), tree)
    checked = mut.check_srdf(parse_srdf(text, "duo.srdf"), tree)
    assert any(needle in d for d in checked.dropped)
    assert checked.groups == full.groups  # the groups themselves are kept
