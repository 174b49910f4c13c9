"""The Panda's state layout and gripper constants agree with the model built from its URDF."""

import numpy as np

import planning.model.layout as mut
from planning import PlanningConfig
from planning.model.panda import ARM_JOINTS, FINGER_JOINTS
from planning.model.planning_model import build_planning_model


def test_layout_matches_the_plant():
    model = build_planning_model(PlanningConfig().model)
    assert len(ARM_JOINTS) == mut.NUM_ARM_JOINTS and len(FINGER_JOINTS) == mut.NUM_FINGERS
    assert model.plant.num_positions() == mut.NUM_POSITIONS
    assert model.plant.num_multibody_states() == mut.NUM_STATES
    finger = model.plant.GetJointByName(FINGER_JOINTS[0])
    assert finger.position_upper_limits()[0] == mut.FINGER_OPEN
    assert finger.position_lower_limits()[0] == mut.FINGER_CLOSED


def test_ready_is_within_the_joint_limits_and_is_the_default_named_configuration():
    model = build_planning_model(PlanningConfig().model)
    lower = model.plant.GetPositionLowerLimits()[model.arm_indices]
    upper = model.plant.GetPositionUpperLimits()[model.arm_indices]
    ready = np.asarray(mut.READY_Q)
    assert np.all(ready > lower) and np.all(ready < upper)
    np.testing.assert_allclose(model.named_configurations["ready"], mut.READY_Q, atol=1e-15)
