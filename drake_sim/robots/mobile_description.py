"""A wheeled robot simulated from its own ROS description, as ROS users have it: the real
``turtlebot3_description`` (burger, waffle, waffle_pi) or another differential-drive robot's
URDF or xacro, its ``package://`` meshes and ``$(find pkg)`` includes resolved by a package map
(``drake_sim.robots.files.robot_files``; no ROS needed).

A robot YAML (``config/turtlebot3.yaml``'s schema) names it in its ``description`` section; the
rest of that YAML then defaults to the shipped TurtleBot3's values and only what a URDF does not
hold is read from it (the wheels' torque, the ``cmd_vel`` limits). Read from the description,
at its joints' zero positions, in the base frame (``base_frame``, on the floor under the axle,
as REP 120's ``base_footprint``):

- the wheel radius: the left wheel link's collision cylinder (or sphere);
- the wheel separation: the distance between the two wheel joints along their axis;
- a wheel's mass: the left wheel link's;
- the lidar's mount: the origin of ``lidar_frame`` (level, facing forward).

The controller, the odometry and the lidar use those numbers, so they match the model the
plant simulates. A description without actuators (a URDF's ``transmission`` elements are for
ros_control; Drake leaves them out) gets one actuator per wheel joint, limited to
``motor.max_torque``.
"""

import dataclasses as dc
import math
import xml.etree.ElementTree as ET

import numpy as np
from pydrake.geometry import Cylinder, SceneGraph, Sphere
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex, RevoluteJoint

from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic
from drake_sim.base.resources import make_parser
from drake_sim.robots.files import robot_files


@dc.dataclass
class MobileDescription:
    """A wheeled robot's own description files and the names the simulation needs.

    ``urdf`` "" means the project's own model (``models/turtlebot3``). Paths are relative to
    the robot YAML (``source``, set by the loader).
    """

    urdf: str = ""  # URDF or xacro: a path, or package://pkg/path
    package_paths: dict[str, str] = dc.field(default_factory=dict)  # {package: folder}
    xacro_args: dict[str, str] = dc.field(default_factory=dict)
    base_frame: str = "base_footprint"  # on the floor under the axle's midpoint
    wheel_joints: list[str] = dc.field(
        default_factory=lambda: ["wheel_left_joint", "wheel_right_joint"]
    )  # [left, right]
    lidar_frame: str = "base_scan"
    # Set by the loader, not YAML keys: the robot YAML, and +1 where a wheel joint's positive
    # turn drives forward (read from the description).
    source: str = ""
    wheel_signs: list[float] = dc.field(default_factory=lambda: [1.0, 1.0])


@dc.dataclass(frozen=True)
class DescribedNumbers:
    """What the simulation reads from a description (SI units)."""

    wheel_radius: float
    wheel_separation: float
    wheel_mass: float
    wheel_signs: tuple[float, float]  # +1 where a wheel's positive turn drives forward
    lidar_mount: tuple[float, float, float]  # the lidar frame's origin in the base frame


def add_described(
    plant: MultibodyPlant,
    description: MobileDescription,
    name: str,
    max_torque: float,
    *,
    warn: bool = False,
) -> ModelInstanceIndex:
    """Adds the described robot to ``plant`` as the model ``name`` (a free base) with an
    actuator per wheel joint ([left, right], effort ``max_torque``) unless it has them;
    ``warn``: as ``robot_files.drake_urdf`` (loading the robot file has warned once)."""
    urdf = robot_files.drake_urdf(description, warn=warn)
    renamed = urdf.with_name(f"{urdf.stem}.as_{name}.urdf")  # beside it: its meshes' paths hold
    ET.register_namespace("drake", "http://drake.mit.edu")
    root = ET.parse(urdf).getroot()
    root.set("name", name)
    text = ET.tostring(root, encoding="unicode")
    if not renamed.is_file() or renamed.read_text() != text:
        write_atomic(renamed, text, "renamed URDF")
    parser = make_parser(plant)
    parser.SetAutoRenaming(False)
    (instance,) = parser.AddModels(str(renamed))
    for joint_name in description.wheel_joints:
        joint = _joint(plant, description, joint_name, instance)
        if joint.num_velocities() != 1:
            raise ConfigError(
                f"{description.source}: description.wheel_joints: {joint_name!r} is not "
                "revolute or continuous"
            )
        if not any(
            plant.get_joint_actuator(a).joint().index() == joint.index()
            for a in plant.GetJointActuatorIndices(instance)
        ):
            plant.AddJointActuator(f"{joint_name}_motor", joint, max_torque)
    return instance


def read_numbers(description: MobileDescription) -> DescribedNumbers:
    """The wheels' and the lidar's numbers of a description (module docstring).

    Raises:
        ConfigError: a frame or joint it names is missing, a wheel joint is not revolute or
            its axis not along the base's y axis, a wheel without a cylinder or sphere, a lidar
            frame that is not level and facing forward.
    """
    plant = MultibodyPlant(0.0)
    scene_graph = SceneGraph()
    plant.RegisterAsSourceForSceneGraph(scene_graph)
    instance = add_described(plant, description, "robot", 1.0, warn=True)
    plant.Finalize()
    context = plant.CreateDefaultContext()
    where = f"{description.source}: description"
    base = _frame(plant, description, description.base_frame, instance, "base_frame")
    if len(description.wheel_joints) != 2:
        raise ConfigError(f"{where}: wheel_joints must name two joints, [left, right]")
    points, signs, axes = [], [], []
    for name in description.wheel_joints:
        joint = _joint(plant, description, name, instance)
        if not isinstance(joint, RevoluteJoint):
            raise ConfigError(f"{where}: wheel joint {name!r} is not revolute or continuous")
        X_BJ = plant.CalcRelativeTransform(context, base, joint.frame_on_parent())
        axis = X_BJ.rotation() @ joint.revolute_axis()
        if abs(axis[1]) < 0.999:
            raise ConfigError(
                f"{where}: wheel joint {name!r} turns about {np.round(axis, 3).tolist()} in "
                f"{description.base_frame}, not about its y axis (the axle)"
            )
        points.append(X_BJ.translation())
        signs.append(1.0 if axis[1] > 0 else -1.0)
        axes.append(axis)
    separation = abs(float(np.dot(points[0] - points[1], axes[0])))
    if points[0][1] <= points[1][1]:
        raise ConfigError(f"{where}: wheel_joints must be [left, right] (left has the larger y)")
    left = _joint(plant, description, description.wheel_joints[0], instance).child_body()
    radius = _wheel_radius(plant, scene_graph, left, where)
    lidar = _frame(plant, description, description.lidar_frame, instance, "lidar_frame")
    X_BL = plant.CalcRelativeTransform(context, base, lidar)
    if not np.allclose(X_BL.rotation().matrix(), np.eye(3), atol=1e-3):
        raise ConfigError(
            f"{where}: lidar frame {description.lidar_frame!r} is not level and facing "
            f"forward in {description.base_frame} (only such a mount is simulated)"
        )
    mount = tuple(float(v) for v in X_BL.translation())
    return DescribedNumbers(
        wheel_radius=radius,
        wheel_separation=separation,
        wheel_mass=float(left.default_mass()),
        wheel_signs=(signs[0], signs[1]),
        lidar_mount=mount,
    )


def _wheel_radius(plant, scene_graph, body, where: str) -> float:
    inspector = scene_graph.model_inspector()
    for geometry in plant.GetCollisionGeometriesForBody(body):
        shape = inspector.GetShape(geometry)
        if isinstance(shape, Cylinder | Sphere):
            radius = float(shape.radius())
            if math.isfinite(radius) and radius > 0:
                return radius
    raise ConfigError(
        f"{where}: wheel link {body.name()!r} has no collision cylinder or sphere to read its "
        "radius from"
    )


def _frame(plant, description, name: str, instance, key: str):
    if not plant.HasFrameNamed(name, instance):
        raise ConfigError(
            f"{description.source}: description.{key} {name!r} is not a link or frame of "
            f"{description.urdf}"
        )
    return plant.GetFrameByName(name, instance)


def _joint(plant, description, name: str, instance):
    if not plant.HasJointNamed(name, instance):
        raise ConfigError(
            f"{description.source}: description.wheel_joints: {name!r} is not a joint of "
            f"{description.urdf}"
        )
    return plant.GetJointByName(name, instance)
