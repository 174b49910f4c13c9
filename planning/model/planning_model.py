"""A robot as the planner holds it: a Drake plant built from a ``RobotModel``, its group's
position indices, a body for held objects, and the collision filters of its SRDF.

``build_planning_model`` reads the robot description the configuration names
(``RobotModelConfig.description``: a shipped name such as "panda" or "ur5", found in
``config/robots/``, a description YAML, or a ``*_moveit_config`` folder), adds the robot to a
``RobotDiagram`` (root welded to the world, ``RobotModel.add_to``) and an attachment body welded
to the description's ``attach_link`` (``<robot>_attachment``): objects the robot holds hang on
it, so they move with that link and are checked against the world and the robot's other
links but not against the attach link or the links below it (a gripper's fingers: MoveIt's
touch links). The SRDF's disabled pairs, and the configuration's extra ones, are declared as
SceneGraph collision filters, so every SceneGraph query (collision checker, IK and
trajectory-optimisation distance constraints) honours them.

A configuration of the plant has the group's joints (``group_indices``, in the group's order)
and the others (``other_indices``: fingers, a head, a second arm outside the group), which stay
where the scene puts them (``default_positions`` at first).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydrake.geometry import CollisionFilterDeclaration, GeometrySet
from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex, SpatialInertia
from pydrake.planning import RobotDiagram, RobotDiagramBuilder

from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from planning.model.model_config import RobotModelConfig
from planning.model.robot_model import RobotModel, load_robot_model


def attachment_body_name(robot_name: str) -> str:
    """The massless body, welded to the attach link, that carries held objects:
    ``<robot>_attachment`` ("panda_attachment" for the Panda)."""
    return f"{robot_name}_attachment"


_SHIPPED = config_dir() / "robots"


def description_file(name: str) -> Path:
    """The description a configuration names: a shipped robot's name
    (``config/robots/<name>.yaml``), else a path to a description YAML or a ``*_moveit_config``
    folder."""
    bare = name and "/" not in name and "\\" not in name
    shipped = _SHIPPED / f"{name}.yaml"
    if bare and shipped.is_file():
        return shipped
    if bare and not name.endswith((".yaml", ".yml")) and not Path(name).exists():
        known = ", ".join(sorted(p.stem for p in _SHIPPED.glob("*.yaml")))
        raise ConfigError(f"model.description: no shipped robot {name!r} (shipped: {known})")
    return Path(name)


def robot_model(config: RobotModelConfig) -> RobotModel:
    """Loads the robot model the configuration names (its ``description`` and ``group``);
    loaded once per process while its description file is unchanged (do not modify it)."""
    name = config.description
    if config.collision_geometry == "primitives":
        if name != "panda":
            raise ConfigError("model.collision_geometry: primitives exist for the Panda only")
        name = "panda_primitives"
    elif config.collision_geometry != "convex_mesh":
        raise ConfigError(
            f"model.collision_geometry must be convex_mesh or primitives, "
            f"got {config.collision_geometry!r}"
        )
    path = description_file(name)
    try:
        stamp = path.stat().st_mtime_ns
    except OSError:
        stamp = None  # load_robot_model names the missing file
    return _load(str(path), stamp, config.group)


@functools.lru_cache(maxsize=16)
def _load(path: str, stamp, group: str) -> RobotModel:
    return load_robot_model(path, group=group or None)


@dataclass
class PlanningModel:
    """A finalized planning model of one robot and the indices planners need.

    Attributes:
        diagram: the RobotDiagram (plant and SceneGraph, plus a visualizer when built with one).
        instance: the robot's model instance.
        robot: the robot's files: group, joint names and limits, named states, frames.
        group_indices: positions of the group's joints in the plant's q, in the group's order.
        other_indices: positions of every other joint in the plant's q.
        default_other: the other joints' default positions (over ``other_indices``).
        finger_mask: which of ``other_indices`` are joints below the attach link (fingers).
        named_configurations: name -> group q, from the description and the configuration.
        ee_frame: the end-effector frame's name.
        disabled_pairs: the link pairs never checked (SRDF, touch links, configuration).
        attachment_body: the name of the body held objects hang on.
        config: the configuration it was built from.
    """

    diagram: RobotDiagram
    instance: ModelInstanceIndex
    robot: RobotModel
    group_indices: np.ndarray
    other_indices: np.ndarray
    default_other: np.ndarray
    finger_mask: np.ndarray
    named_configurations: dict[str, np.ndarray]
    ee_frame: str
    disabled_pairs: list[tuple[str, str]]
    attachment_body: str
    config: RobotModelConfig

    @property
    def plant(self) -> MultibodyPlant:
        return self.diagram.plant()

    @property
    def scene_graph(self):
        return self.diagram.scene_graph()

    @property
    def num_joints(self) -> int:
        """The number of the group's joints (the size of a planning configuration)."""
        return len(self.group_indices)

    @property
    def joint_names(self) -> list[str]:
        return list(self.robot.joint_names)

    @property
    def home(self) -> np.ndarray:
        """The group's start when none is given: the named configuration "ready", else "home",
        else the first named one, else the middle of the joints' limits."""
        return _home(self.robot, self.named_configurations)

    def full_q(self, q, others) -> np.ndarray:
        """The plant's positions for a group q (``others`` over ``other_indices`` added) or for
        all of the plant's positions (returned as they are).

        Raises:
            ValueError: q has the wrong size or is not finite.
        """
        q = np.asarray(q, dtype=float).reshape(-1)
        n, total = self.num_joints, self.plant.num_positions()
        if q.size == n:
            full = np.empty(total)
            full[self.group_indices] = q
            full[self.other_indices] = others
            q = full
        elif q.size != total:
            raise ValueError(
                f"q must have {n} (the group's joints) or {total} (all joints) values, got {q.size}"
            )
        if not np.all(np.isfinite(q)):
            raise ValueError(f"q is not finite: {q.tolist()}")
        return q

    def others_by_name(self, positions: dict[str, float], others) -> np.ndarray:
        """A copy of ``others`` (over ``other_indices``) with the joints ``positions`` names
        set; names the robot does not have and the group's own joints are left out."""
        plant, instance = self.plant, self.instance
        index = {int(i): k for k, i in enumerate(self.other_indices)}
        others = np.array(others, dtype=float)
        for name, value in positions.items():
            if plant.HasJointNamed(name, instance):
                k = index.get(plant.GetJointByName(name, instance).position_start())
                if k is not None:
                    others[k] = value
        return others

    @property
    def arm_indices(self) -> np.ndarray:
        """``group_indices`` (the name planners used when the group was the Panda's arm)."""
        return self.group_indices

    @property
    def finger_names(self) -> list[str]:
        """The finger joints' names, in the order of ``finger_indices``."""
        plant, fingers = self.plant, set(self.finger_indices.tolist())
        joints = [plant.get_joint(j) for j in plant.GetJointIndices(self.instance)]
        return [
            j.name() for j in joints if j.num_positions() == 1 and j.position_start() in fingers
        ]

    @property
    def finger_indices(self) -> np.ndarray:
        """Positions of the joints below the attach link (a gripper's fingers) in the plant's q."""
        return self.other_indices[self.finger_mask]


def build_planning_model(config: RobotModelConfig, *, meshcat=None) -> PlanningModel:
    """Builds the planning model the configuration names, collision filters applied.

    Args:
        config: the model configuration.
        meshcat: when given, a MeshcatVisualizer (illustration role) is added to the diagram.

    Raises:
        ConfigError: the description cannot be loaded, or the configuration names a frame,
            link or state the robot does not have.
    """
    robot = robot_model(config)
    builder = RobotDiagramBuilder(time_step=0.0)
    plant, scene_graph = builder.plant(), builder.scene_graph()
    instance = robot.add_to(plant)
    attachment_name = attachment_body_name(robot.name)
    if attachment_name in robot.tree.links:
        raise ConfigError(f"{robot.name}: a link is named {attachment_name!r}, the planner's own")
    attachment = plant.AddRigidBody(attachment_name, instance, SpatialInertia.Zero())
    link = plant.GetFrameByName(robot.attach_link, instance)
    plant.WeldFrames(link, attachment.body_frame(), RigidTransform())
    plant.Finalize()
    touch = touch_links(robot)
    pairs = list(robot.disabled_pairs) + [(attachment_name, b) for b in touch]
    pairs += [(a, b) for a, b in config.extra_disabled_collisions]
    apply_disabled_collisions(plant, scene_graph, instance, pairs)
    if meshcat is not None:
        from pydrake.geometry import MeshcatVisualizer, MeshcatVisualizerParams

        params = MeshcatVisualizerParams(prefix="planning/robot")
        MeshcatVisualizer.AddToBuilder(builder.builder(), scene_graph, meshcat, params)
    group = [plant.GetJointByName(n, instance).position_start() for n in robot.joint_names]
    others, defaults, fingers = [], [], []
    below = set(touch)
    for index in plant.GetJointIndices(instance):
        joint = plant.get_joint(index)
        if joint.num_positions() == 1 and joint.name() not in robot.joint_names:
            others.append(joint.position_start())
            defaults.append(robot.default_positions.get(joint.name(), 0.0))
            fingers.append(joint.child_body().name() in below)
    defaults = np.array(defaults, dtype=float)
    fingers = np.array(fingers, dtype=bool)
    if config.finger_position is not None:
        if not fingers.any():
            raise ConfigError(f"model.finger_position: {robot.name} has no finger joints")
        low = plant.GetPositionLowerLimits()[others][fingers]
        high = plant.GetPositionUpperLimits()[others][fingers]
        value = config.finger_position
        if not (np.all(low - 1e-9 <= value) and np.all(value <= high + 1e-9)):
            raise ConfigError(
                f"model.finger_position must be in [{low.max():g}, {high.min():g}], got {value:g}"
            )
        defaults[fingers] = value
    ee_frame = config.ee_frame or robot.ee_frame
    if not plant.HasFrameNamed(ee_frame, instance):
        raise ConfigError(f"model.ee_frame: {robot.name} has no frame {ee_frame!r}")
    return PlanningModel(
        diagram=builder.Build(),
        instance=instance,
        robot=robot,
        group_indices=np.array(group, dtype=int),
        other_indices=np.array(others, dtype=int),
        default_other=defaults,
        finger_mask=fingers,
        named_configurations=_named_configurations(robot, config),
        ee_frame=ee_frame,
        disabled_pairs=pairs,
        attachment_body=attachment_name,
        config=config,
    )


def apply_disabled_collisions(
    plant: MultibodyPlant, scene_graph, instance: ModelInstanceIndex, pairs
) -> None:
    """Excludes collisions between each pair of link names in the SceneGraph model.

    Raises:
        ConfigError: a pair names a body the robot does not have.
    """
    manager = scene_graph.collision_filter_manager()
    for name_a, name_b in pairs:
        bodies = []
        for name in (name_a, name_b):
            if not plant.HasBodyNamed(name, instance):
                raise ConfigError(f"disabled collision pair ({name_a}, {name_b}): no body {name}")
            bodies.append(plant.GetBodyByName(name, instance))
        sets = [GeometrySet(plant.GetCollisionGeometriesForBody(b)) for b in bodies]
        manager.Apply(CollisionFilterDeclaration().ExcludeBetween(sets[0], sets[1]))


def named_configurations(config: RobotModelConfig) -> dict[str, np.ndarray]:
    """The group's named configurations for a configuration (the description's, then the
    configuration's), read from the files without building a plant.

    Raises:
        ConfigError: the description cannot be loaded or a configuration has the wrong size.
    """
    return _named_configurations(robot_model(config), config)


def finger_defaults(config: RobotModelConfig) -> list[float]:
    """The finger joints' start positions (the joints below the attach link, in the URDF's
    order): ``config.finger_position`` for each, else the description's default positions."""
    robot = robot_model(config)
    below = set(touch_links(robot))
    names = [
        j.name
        for j in robot.tree.joints.values()
        if j.child in below and j.name in robot.default_positions
    ]
    value = config.finger_position
    if value is None:
        return [robot.default_positions[name] for name in names]
    if not names:
        raise ConfigError(f"model.finger_position: {robot.name} has no finger joints")
    for name in names:
        joint = robot.tree.joints[name]
        low = -np.inf if joint.lower is None else joint.lower
        high = np.inf if joint.upper is None else joint.upper
        if not low - 1e-9 <= value <= high + 1e-9:
            raise ConfigError(
                f"model.finger_position must be in [{low:g}, {high:g}] ({name}), got {value:g}"
            )
    return [float(value)] * len(names)


def home_configuration(config: RobotModelConfig) -> np.ndarray:
    """The group's start when none is given (``PlanningModel.home``), without a plant."""
    return _home(robot_model(config), named_configurations(config))


def _home(robot: RobotModel, named: dict) -> np.ndarray:
    for name in ("ready", "home", *named):
        if name in named:
            return np.array(named[name], dtype=float)
    return 0.5 * (robot.lower + robot.upper)


def touch_links(robot: RobotModel) -> list[str]:
    """The links below the attach link (fingers), which held objects may touch."""
    below, stack = [], [robot.attach_link]
    while stack:
        link = stack.pop()
        for joint in robot.tree.child_joints(link):
            below.append(joint.child)
            stack.append(joint.child)
    return below


def _named_configurations(robot: RobotModel, config: RobotModelConfig) -> dict:
    named = {name: q.copy() for name, q in robot.named_states.items()}
    for name, q in config.named_configurations.items():
        if len(q) != robot.num_joints:
            raise ConfigError(
                f"model.named_configurations.{name} has {len(q)} values, group "
                f"{robot.group!r} has {robot.num_joints} joints"
            )
        named[name] = np.asarray(q, dtype=float)
    return named
