"""The diff-drive robot model: render the xacro for a robot YAML and add it to a plant."""

from __future__ import annotations

from pathlib import Path

from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex

from drake_sim.base.resources import config_dir
from drake_sim.robots.ddrive_params import RobotParams
from drake_sim.robots.urdf_model import add_robot_urdf, render_robot_urdf

ROBOT_XACRO = "ddrive/ddrive.urdf.xacro"
"""The robot's xacro, relative to ``models/``."""

LEFT_WHEEL_JOINT = "left_wheel_joint"
RIGHT_WHEEL_JOINT = "right_wheel_joint"
BODY_LINK = "base_link"


def default_robot_file() -> Path:
    """Returns ``config/ddrive.yaml``."""
    return config_dir() / "ddrive.yaml"


def robot_urdf(params: RobotParams) -> Path:
    """Renders the robot's URDF for ``params`` (cached) and returns its path.

    The parameters, with every optional key filled in, are written as YAML beside the cache
    and handed to the xacro, which reads them with ``xacro.load_yaml``.
    """
    return render_robot_urdf(ROBOT_XACRO, "ddrive", params)


def add_robot(
    plant: MultibodyPlant, params: RobotParams, *, name: str = "ddrive"
) -> ModelInstanceIndex:
    """Adds the robot to ``plant`` as a free body (not welded) and returns its model instance."""
    return add_robot_urdf(plant, robot_urdf(params), "ddrive", name)
