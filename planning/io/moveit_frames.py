"""The frames a MoveIt PlanningScene names, and the robot configuration it is given at.

A ``header.frame_id`` is looked up as MoveIt's ``PlanningScene::getFrameTransform`` looks it up
(a leading "/" ignored): the world ("", "world"), a link of the scene's robot at the scene's
robot state, an object added earlier or one of its subframes ("object/subframe"), then a frame of
``fixed_frame_transforms``. The robot's links are the bodies of the scene's plant (its robot
instance), never a list of names: a scene written for another robot names links this one does
not have, and its objects in those frames are left out with a warning each.

``fixed_frame_transforms`` is read as MoveIt writes it (``Transforms::copyTransforms``): the
``child_frame_id`` is the planning frame and the transform is the pose of ``header.frame_id`` in
it; an entry whose header names a known frame and whose child does not is read as tf reads it
(the pose of the child in the header's frame). An entry that relates two frames neither known is
left out with a warning; one relating a frame to itself by the identity says nothing.

The robot state: ``joint_state`` gives the joints it names (joints of another robot are left out
with one warning); the others keep the values of ``base`` (MoveIt's default when none: 0, or
mid-range where 0 is out of range; the scene's finger positions for the fingers). A virtual
joint's transform (``multi_dof_joint_state``) that moves the robot's base: the base here is
fixed at the world origin, so the world is moved instead (every pose in a world frame is
expressed relative to the base), with a warning.
"""

from __future__ import annotations

import numpy as np
from pydrake.math import RigidTransform

from planning.io import moveit_msgs as msgs

WORLD_FRAMES = ("", "world")  # the names of the world frame (after a leading "/")


class SceneFrames:
    """The frames of one scene at its robot configuration ``q`` (the plant's positions).

    Args:
        data: the parsed PlanningScene.
        scene: the ``PlanningScene`` (its plant's links become frames), or None (world and
            fixed frames only).
        issues: ``moveit_objects.Issues``.
        base: the configuration the joints the scene does not name keep (plant positions).
    """

    def __init__(self, data: dict, scene, issues, base=None):
        self.scene = scene
        state = data.get("robot_state") or {}
        self.links = robot_links(scene)
        self.q, self.joints = None, {}
        if scene is not None:
            self.q, self.joints = configuration(scene, state.get("joint_state") or {}, issues, base)
        self.world = _world_pose(state, issues)
        self.fixed: dict[str, RigidTransform] = {}
        _fixed_frames(data.get("fixed_frame_transforms", []), self, issues)

    def X_WF(self, frame_id: str, objects=None) -> RigidTransform | None:
        """The pose of a frame in the world, or None when it is unknown.

        Args:
            objects: the objects so far (``moveit_objects.Entry`` by id), for frames on them.
        """
        name = frame_id[1:] if frame_id.startswith("/") else frame_id
        if name in WORLD_FRAMES:
            return self.world
        if name in self.links:
            context = self.scene.plant_context(self.q)
            return self.scene.plant.EvalBodyPoseInWorld(context, self.links[name])
        entry, _, sub = name.partition("/")
        if objects and entry in objects:
            found = objects[entry]
            if not sub:
                return found.X_WO
            if sub in found.subframes:
                return found.X_WO @ found.subframes[sub]
        return self.fixed.get(name)

    def describe(self) -> str:
        """The frames known, for messages."""
        known = ["world", *sorted(self.fixed)]
        if self.links:
            known.append(f"the links of {robot_name(self.scene)}")
        return ", ".join(known) + ", objects and their subframes"


def robot_links(scene) -> dict:
    """The scene's robot links by name: the bodies of its robot instance (every body of the
    plant but the world's when the model names no instance); {} without a scene."""
    if scene is None:
        return {}
    plant = scene.plant
    bodies = [plant.get_body(i) for i in plant.GetBodyIndices(scene.model.instance)]
    return {body.name(): body for body in bodies}


def robot_name(scene) -> str:
    """The robot's name, for messages (its URDF's)."""
    return scene.model.robot.name


def default_configuration(scene) -> np.ndarray:
    """MoveIt's default configuration for the group's joints (0, or mid-range where 0 is out of
    range), with the joints outside the group where the scene has them."""
    plant = scene.plant
    lower, upper = plant.GetPositionLowerLimits(), plant.GetPositionUpperLimits()
    q = np.where((lower <= 0.0) & (upper >= 0.0), 0.0, (lower + upper) / 2)
    q[scene.model.other_indices] = scene.other_positions
    return q


def configuration(scene, joint_state: dict, issues, base=None) -> tuple[np.ndarray, dict]:
    """The plant positions a JointState gives (the others as ``base``), and {joint: value} of
    the joints it names that the robot has.

    Raises:
        ValueError: names and positions of different lengths, a position that is no number.
    """
    plant = scene.plant
    q = default_configuration(scene) if base is None else np.array(base, dtype=float)
    if q.shape != (plant.num_positions(),):
        raise ValueError(f"base: {plant.num_positions()} positions expected, got {q.shape}")
    names, positions = joint_state.get("name", []), joint_state.get("position", [])
    if len(names) != len(positions):
        raise ValueError(f"robot_state.joint_state: {len(names)} names, {len(positions)} positions")
    instance = scene.model.instance
    named, unknown = {}, []
    for i, (name, value) in enumerate(zip(names, positions, strict=True)):
        value = msgs.number(value, f"robot_state.joint_state.position[{i}]")
        joint = _joint(plant, name, instance)
        if joint is None or joint.num_positions() != 1:
            unknown.append(name)
            continue
        q[joint.position_start()] = named[name] = value
    if unknown:
        more = f" and {len(unknown) - 6} more" if len(unknown) > 6 else ""
        shown = ", ".join(unknown[:6]) + more
        issues.drop(
            "robot_state.joint_state",
            f"{len(unknown)} joints that {robot_name(scene)} does not have left out ({shown})",
        )
    return q, named


def _joint(plant, name: str, instance):
    if instance is None:
        return plant.GetJointByName(name) if plant.HasJointNamed(name) else None
    return plant.GetJointByName(name, instance) if plant.HasJointNamed(name, instance) else None


def _world_pose(state: dict, issues) -> RigidTransform:
    """The pose of the file's world relative to the robot's base: the identity unless the
    virtual joint moves the base (then the world moves, with a warning)."""
    multi = state.get("multi_dof_joint_state") or {}
    X_WB = RigidTransform()
    for i, transform in enumerate(multi.get("transforms", [])):
        path = f"robot_state.multi_dof_joint_state.transforms[{i}]"
        X = msgs.pose(transform, path, position="translation", orientation="rotation")
        if i == 0:
            X_WB = X
        elif not _identity(X):
            issues.drop(path, "a second multi-DOF joint is not applied (the base is fixed)")
    if _identity(X_WB):
        return RigidTransform()
    p = np.round(X_WB.translation(), 4).tolist()
    issues.drop(
        "robot_state.multi_dof_joint_state.transforms[0]",
        f"the robot's base is at {p} in the file's world; its base is fixed here, so the "
        "world's objects and frames are placed relative to the base",
    )
    return X_WB.inverse()


def _fixed_frames(entries: list, frames: SceneFrames, issues) -> None:
    unrelated = []  # (header, child) of entries between two frames neither known
    for i, entry in enumerate(entries):
        path = f"fixed_frame_transforms[{i}]"
        header = (entry.get("header") or {}).get("frame_id", "").lstrip("/")
        child = entry.get("child_frame_id", "").lstrip("/")
        X = msgs.pose(
            entry.get("transform"),
            f"{path}.transform",
            position="translation",
            orientation="rotation",
        )
        if header == child or (header in WORLD_FRAMES and child in WORLD_FRAMES):
            if not _identity(X):
                what = "the world frame" if child in WORLD_FRAMES else f"frame {child!r}"
                issues.drop(path, f"{what} cannot be moved relative to itself: not applied")
            continue
        X_W_child, X_W_header = frames.X_WF(child), frames.X_WF(header)
        if X_W_child is not None and X_W_header is None:  # MoveIt's: header's pose in child
            frames.fixed[header] = X_W_child @ X
        elif X_W_header is not None and X_W_child is None:  # tf's: child's pose in header
            frames.fixed[child] = X_W_header @ X
        elif X_W_child is None:
            unrelated.append((header, child))
        elif not (X_W_child @ X).IsNearlyEqualTo(X_W_header, 1e-6):
            issues.drop(path, f"{header!r} and {child!r} are both known and elsewhere: not applied")
    if unrelated:
        names = sorted({h for h, _ in unrelated})
        shown = ", ".join(names[:4]) + (f" and {len(names) - 4} more" if len(names) > 4 else "")
        parents = ", ".join(sorted({c for _, c in unrelated}))
        issues.drop(
            "fixed_frame_transforms",
            f"{len(unrelated)} frames given relative to frames this robot does not have "
            f"({parents}) not applied: {shown}",
        )


def _identity(X: RigidTransform) -> bool:
    return X.IsNearlyEqualTo(RigidTransform(), 1e-9)
