"""ArmLayout: what a station carries of a robot, read from its files."""

import numpy as np
import pytest

from drake_sim.base.errors import ConfigError
from planning.model.arm_layout import ArmLayout
from planning.model.model_config import RobotModelConfig
from planning.model.planning_model import build_planning_model, robot_model
from tests.robot_helpers import XARM7_YAML, make_elbow_robot


def layout_of(description: str) -> ArmLayout:
    return ArmLayout.of(robot_model(RobotModelConfig(description=description)))


def test_the_panda_is_its_arm_then_its_two_fingers():
    dut = layout_of("panda")
    assert dut.robot == "panda" and dut.num_joints == 7
    assert dut.fingers == ("panda_finger_joint1", "panda_finger_joint2") and not dut.others
    assert (dut.finger_closed, dut.finger_open) == (0.0, 0.04)
    assert (dut.num_positions, dut.num_states) == (9, 18)
    x = np.arange(18.0)
    assert x[dut.arm_q].tolist() == list(range(7)) and x[dut.finger_q].tolist() == [7, 8]
    assert x[dut.arm_v].tolist() == list(range(9, 16)) and x[dut.finger_v].tolist() == [16, 17]
    assert dut.port("state") == "panda.state"
    np.testing.assert_array_equal(dut.positions(np.ones(7), 0.02), [1] * 7 + [0.02] * 2)
    with pytest.raises(ConfigError, match="6 joint values for a group of 7"):
        dut.positions(np.ones(6), 0.02)
    model = build_planning_model(RobotModelConfig())
    rows = dut.plant_indices(model.plant, model.instance)
    np.testing.assert_array_equal(rows[7:], model.finger_indices)


def test_an_arm_without_fingers_has_a_virtual_gripper(tmp_path):
    (tmp_path / "xarm7.yaml").write_text(XARM7_YAML)
    dut = layout_of(str(tmp_path / "xarm7.yaml"))
    assert (dut.num_joints, dut.num_fingers, dut.num_positions) == (7, 0, 7)
    assert (dut.finger_closed, dut.finger_open) == (0.0, 1.0)
    assert np.arange(14.0)[dut.finger_v].size == 0


def test_a_joint_outside_the_group_and_the_fingers_keeps_its_default(tmp_path):
    """The elbow arm's block slides on the arm, beside the tool it is attached to."""
    dut = layout_of(str(make_elbow_robot(tmp_path, 1.0, finger=True)))
    assert dut.group == ("pan", "lift") and not dut.fingers
    assert dut.others == ("slide",) and dut.other_positions == (0.0,)


def finger_robot(folder, edit=lambda text: text):
    """The elbow arm with its block below the attach link (a finger); ``edit`` changes its
    URDF."""
    description = make_elbow_robot(folder, 1.0, finger=True)
    description.write_text(description.read_text() + "attach_link: arm\n")
    urdf = folder / "elbow.urdf"
    urdf.write_text(edit(urdf.read_text()))
    return str(description)


def test_fingers_need_limits(tmp_path):
    dut = layout_of(finger_robot(tmp_path / "limited"))
    assert dut.fingers == ("slide",) and (dut.finger_closed, dut.finger_open) == (0.0, 0.05)

    def endless(text):
        text = text.replace('"slide" type="prismatic"', '"slide" type="continuous"')
        return text.replace('<limit lower="0" upper="0.05" velocity="1" effort="1"/>', "")

    with pytest.raises(ConfigError, match="elbow: finger joint slide has no limits"):
        layout_of(finger_robot(tmp_path / "endless", endless))
