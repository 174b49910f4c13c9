"""planning.scene_positions through the Panda's scene: group q and full q, the joints outside
the group (its fingers) set as a whole, as fingers or by name, and the group's limits."""

import numpy as np
import pytest

from planning import PlanningConfig, PlanningScene


@pytest.fixture
def scene():
    return PlanningScene(PlanningConfig(table=None))


def test_group_q_gets_the_other_joints_and_full_q_stays(scene):
    assert scene.num_joints == 7
    q = np.arange(7) * 0.1
    full = scene.full_q(q)
    np.testing.assert_array_equal(full, [*q, 0.04, 0.04])
    np.testing.assert_array_equal(scene.full_q(full), full)
    np.testing.assert_array_equal(scene.arm_q(full), q)
    for bad in (np.zeros(8), [np.nan] * 7):
        with pytest.raises(ValueError):
            scene.full_q(bad)


def test_the_other_joints_by_value_as_fingers_and_by_name(scene):
    version = scene.version
    scene.finger_positions = 0.01
    np.testing.assert_array_equal(scene.other_positions, [0.01, 0.01])
    scene.set_positions({"panda_finger_joint2": 0.03, "panda_joint1": 2.0, "elbow": 1.0})
    np.testing.assert_array_equal(scene.finger_positions, [0.01, 0.03])  # the group's ignored
    assert scene.version > version
    with pytest.raises(ValueError, match="finite"):
        scene.other_positions = [np.inf, 0.0]


def test_limits_are_the_robot_model_s(scene):
    np.testing.assert_array_equal(scene.lower, scene.model.robot.lower)
    assert scene.upper[0] == pytest.approx(2.8973)
    scene.lower[0] = 99.0  # a copy
    assert scene.lower[0] == pytest.approx(-2.8973)
