"""The TurtleBot3 Waffle model: render its xacro for a robot YAML, add it to a plant, and the
names and numbers a diagram builder needs (frames, wheel joints, start pose, drive limits).

See ``models/turtlebot3/turtlebot3.urdf.xacro`` for the frames. The plant's free body is
``base_footprint`` (F, on the floor under the axle's midpoint); the robot's planar pose
``(x, y, yaw)`` is F's.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex

from drake_sim.base.resources import config_dir, models_dir
from drake_sim.robots.mobile_description import add_described
from drake_sim.robots.turtlebot3_params import Turtlebot3Params
from drake_sim.robots.urdf_model import add_robot_urdf, render_robot_urdf

ROBOT_XACRO = "turtlebot3/turtlebot3.urdf.xacro"
"""The robot's xacro, relative to ``models/``."""
SOLID_MACROS = "ddrive/macros.xacro"
"""The shared solid-link macros the xacro includes, relative to ``models/``."""

BASE_FOOTPRINT = "base_footprint"
"""The free body: on the floor under the axle's midpoint; the robot's planar pose is its."""
BASE_LINK = "base_link"
"""The chassis body, welded to ``base_footprint`` with its origin on the axle."""
LEFT_WHEEL_JOINT = "left_wheel_joint"
RIGHT_WHEEL_JOINT = "right_wheel_joint"
WHEEL_JOINTS = (LEFT_WHEEL_JOINT, RIGHT_WHEEL_JOINT)
"""In the order of the plant's actuation input: [left, right]."""
WHEEL_LINKS = ("left_wheel", "right_wheel")
CASTER_LINKS = ("left_caster", "right_caster")
IMU_FRAME = "imu_link"
CAMERA_FRAME = "camera_rgb_frame"
"""The camera's optical centre; x along the optical axis (forward), y left, z up."""
CAMERA_OPTICAL_FRAME = "camera_rgb_optical_frame"
"""The camera's optical centre; z along the optical axis, x right, y down: Drake's camera
frame C (``RgbdSensor``). Attach a camera here with X_PC = I."""
LIDAR_FRAME = "base_scan"
"""The lidar's scan centre, with F's axes, ``params.scan_height`` above the floor."""

START_LIFT = 1e-3
"""m: how far ``start_pose`` lifts the robot, so the first step does not start in contact."""


def default_turtlebot3_file() -> Path:
    """Returns ``config/turtlebot3.yaml``."""
    return config_dir() / "turtlebot3.yaml"


def robot_urdf(params: Turtlebot3Params) -> Path:
    """Renders the TurtleBot3's URDF for ``params`` (cached) and returns its path.

    The parameters are written as YAML beside the cache and handed to the xacro, which reads
    them with ``xacro.load_yaml``.
    """
    # The shared macros are named so that the cache key covers them too.
    macros = str(models_dir() / SOLID_MACROS)
    return render_robot_urdf(ROBOT_XACRO, "turtlebot3", params, solid_macros=macros)


def add_turtlebot3(
    plant: MultibodyPlant, params: Turtlebot3Params, *, name: str = "turtlebot3"
) -> ModelInstanceIndex:
    """Adds the TurtleBot3 to ``plant`` as a free body (``base_footprint``, not welded) and
    returns its model instance: the project's model, or the robot's own description when
    ``params.description`` names one (``mobile_description``).

    Its two actuators drive the left and the right wheel, in that order. The plant needs a
    registered SceneGraph (the robot has visual and collision geometry).
    """
    if params.description.urdf:
        return add_described(plant, params.description, name, params.motor.max_torque)
    return add_robot_urdf(plant, robot_urdf(params), "turtlebot3", name)


def frame_names(params: Turtlebot3Params) -> dict[str, str]:
    """The names of the robot's ``base`` (free body's frame, on the floor under the axle),
    ``lidar`` frame and ``left``/``right`` wheel joints: the project's model's, or those its
    description names."""
    if params.description.urdf:
        d = params.description
        return dict(base=d.base_frame, lidar=d.lidar_frame, left=d.wheel_joints[0],
                    right=d.wheel_joints[1])  # fmt: skip
    return dict(base=BASE_FOOTPRINT, lidar=LIDAR_FRAME, left=LEFT_WHEEL_JOINT,
                right=RIGHT_WHEEL_JOINT)  # fmt: skip


def wheel_signs(params: Turtlebot3Params) -> np.ndarray:
    """(2,) +1 where a wheel joint's positive turn drives the robot forward, else -1 (the
    project's model: both +1)."""
    return np.array(params.description.wheel_signs, dtype=float)


def start_pose(x: float, y: float, yaw: float) -> RigidTransform:
    """X_WF: ``base_footprint`` standing on the floor at ``(x, y)`` (m) heading ``yaw``
    (rad), lifted ``START_LIFT``; for ``plant.SetDefaultFloatingBaseBodyPose``."""
    return RigidTransform(RollPitchYaw(0.0, 0.0, yaw), [x, y, START_LIFT])


def wheel_state_selector(
    plant: MultibodyPlant,
    instance: ModelInstanceIndex,
    joints: tuple[str, str] = WHEEL_JOINTS,
    signs=(1.0, 1.0),
) -> np.ndarray:
    """The 4 x (nq + nv) matrix that picks ``[q_left, q_right, v_left, v_right]`` (rad,
    rad/s, forward positive: each joint's times its sign) from the finalised plant's full state
    (for a ``MatrixGain`` on its state output)."""
    found = [plant.GetJointByName(name, instance) for name in joints]
    rows = [j.position_start() for j in found]
    rows += [plant.num_positions() + j.velocity_start() for j in found]
    return np.tile(signs, 2)[:, None] * np.eye(plant.num_multibody_states())[rows]


def drive_limits(params: Turtlebot3Params) -> dict[str, float]:
    """The robot's ``cmd_vel`` limits (m/s, rad/s, m/s^2, rad/s^2) under the field names of
    ``DiffDriveConfig``: ``dc.replace(DiffDriveConfig(), **drive_limits(params))``."""
    limits = params.limits
    return {
        "max_linear_velocity": limits.max_linear_velocity,
        "max_angular_velocity": limits.max_angular_velocity,
        "max_linear_acceleration": limits.max_linear_acceleration,
        "max_angular_acceleration": limits.max_angular_acceleration,
    }
