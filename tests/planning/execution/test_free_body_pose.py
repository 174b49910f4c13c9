"""planning.execution.free_body_pose: FreeBodyPose reads a free body's pose from its first seven
positions (quaternion, then position), whatever the size of its input."""

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw

import planning.execution.free_body_pose as mut
from planning.scene_objects import free_body_positions


def test_free_body_pose_reads_the_first_seven_values():
    dut = mut.FreeBodyPose(input_size=13)
    assert dut.get_input_port().get_name() == "positions" and dut.get_input_port().size() == 13
    assert dut.get_output_port().get_name() == "pose"
    X_WB = RigidTransform(RollPitchYaw(0.1, -0.2, 0.3), [0.4, 0.5, 0.6])
    q = free_body_positions(X_WB)
    q[:4] *= 2.0  # an unnormalised quaternion is normalised
    context = dut.CreateDefaultContext()
    dut.get_input_port().FixValue(context, np.concatenate([q, np.arange(6.0)]))
    assert dut.get_output_port().Eval(context).IsNearlyEqualTo(X_WB, 1e-12)


def test_free_body_pose_default_size_and_too_small_input():
    assert mut.FreeBodyPose().get_input_port().size() == 7
    with pytest.raises(ValueError, match="input_size=6"):
        mut.FreeBodyPose(input_size=6)
