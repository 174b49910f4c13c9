"""The arm station's settings: the layout its ports carry, its start and its checks."""

import dataclasses as dc

import numpy as np
import pytest

import diagrams.arm_station_config as mut
from drake_sim.base.errors import ConfigError
from planning.model.layout import FINGER_OPEN, READY_Q
from planning.model.model_config import RobotModelConfig
from tests.robot_helpers import XARM7_YAML


def test_the_panda_starts_at_ready_with_open_fingers():
    config = mut.ArmStationConfig()
    layout = mut.station_layout(config)
    assert (layout.robot, layout.num_joints, layout.num_fingers) == ("panda", 7, 2)
    np.testing.assert_allclose(mut.initial_positions(config), [*READY_Q, FINGER_OPEN, FINGER_OPEN])
    mut.validate_station_config(config, "physics")


def test_checks_count_the_group_and_the_mode(tmp_path):
    arm = tmp_path / "xarm7.yaml"
    arm.write_text(XARM7_YAML)
    xarm = mut.ArmStationConfig(model=RobotModelConfig(description=str(arm)))
    with pytest.raises(ConfigError, match="initial_q has 9 values, expected 7"):
        mut.validate_station_config(dc.replace(xarm, initial_q=[0.0] * 9))
    six = dc.replace(xarm, arm_kd=[1.0] * 6)
    mut.validate_station_config(six, "kinematic")  # gains are not used there
    with pytest.raises(ConfigError, match="station.arm_kd needs 7 values"):
        mut.validate_station_config(six, "physics")
