"""MoveIt's planning scenes: ``moveit_msgs/PlanningScene`` YAML and the text ``.scene`` format.

``load_moveit_scene`` picks the reader by the file's extension (``.yaml``/``.yml``, or ``.scene``
for ``planning.io.moveit_text``) and replaces the whole scene, as MoveIt does with a scene that
is not a diff: world objects, held objects, allowed collisions; the place target is cleared.

A PlanningScene YAML is read as MoveIt reads it:

- ``world.collision_objects`` in order, each by its ``operation``: ADD (0; replaces an object
  of the same id), REMOVE (1; every object when the id is empty), APPEND (2; more shapes for an
  object) and MOVE (3; a new ``pose`` for the object, and new ``primitive_poses`` when given).
  Primitives (box ``[x, y, z]``, sphere ``[radius]``, cylinder ``[height, radius]``) sit at their
  ``primitive_poses`` in the object's ``pose``, given in ``header.frame_id``: the world (``""``,
  ``world``), a frame of ``fixed_frame_transforms``, or a link of the Panda (``panda_link0`` is
  the base, at the world origin) at the scene's robot configuration, ``robot_state.joint_state``
  (a joint it does not name is at MoveIt's default: 0, or mid-range when 0 is out of range). An
  object of several primitives becomes objects ``id``, ``id#1``, ``id#2``, ...
- ``robot_state.attached_collision_objects``: held objects, on ``link_name``, which must be the
  hand or a link welded to it; their poses are kept in the hand's attachment frame.
- ``allowed_collision_matrix``: pairs of Panda links allowed to touch become collision filters
  on top of the robot's own; pairs naming anything else are not applied (a warning).

A file with no YAML document (empty, blank, comments only) is an error, like an empty ``.scene``
file; a PlanningScene with neither a ``name`` nor an object loads as an empty scene with one
warning (MoveIt applies such a message as a scene without objects), and one with a name and no
objects is a valid empty scene.

Anything else raises ``PlanningError(INVALID_SCENE)`` naming the file and the key path: unknown
keys, values of the wrong type, NaN, meshes, planes, cones, octomaps, link padding or scaling, a
moved robot base, unknown frames or joints, and scene diffs (``is_diff``).
"""

import logging
from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform

from drake_sim.base.config import check_tree, parse_yaml, read_text
from planning.errors import ErrorCode, PlanningError
from planning.io import moveit_msgs as msgs
from planning.io.moveit_text import parse_scene_text
from planning.model.panda import ATTACHMENT_BODY
from planning.scene_objects import SceneObject

_log = logging.getLogger(__name__)
WORLD_FRAMES = ("", "world")  # the names of the world frame (after a leading "/")
_FINGERS = ("panda_leftfinger", "panda_rightfinger")


def load_moveit_scene(scene, filename: Path | str) -> None:
    """Replaces the whole of ``scene`` by a MoveIt scene file (``.yaml``, ``.yml``, ``.scene``).

    Raises:
        PlanningError: INVALID_SCENE for a missing, unreadable or malformed file, an unsupported
            feature or a bad value, naming the file and the key path (or line); the scene is
            then left as it was.
    """
    path = Path(filename)
    suffix = path.suffix.lower()
    attached, allowed, unnamed = [], [], False
    try:
        if suffix == ".scene":
            world = parse_scene_text(read_text(path, "scene file"), str(path))
        elif suffix in (".yaml", ".yml"):
            data = parse_yaml(read_text(path, "scene file"), str(path))
            if data is None:  # no YAML document: empty, blank or comments only
                raise ValueError(f"{path}: empty scene file (expected a PlanningScene mapping)")
            world, attached, allowed = parse_moveit_scene(data, scene, str(path))
            unnamed = not data.get("name")
        else:
            raise ValueError(f"{path}: not a MoveIt scene file (.scene, .yaml or .yml)")
        scene.replace(world, attached, allowed)
    except (ValueError, PlanningError) as e:
        message = e.message if isinstance(e, PlanningError) else str(e)
        where = "" if message.startswith(str(path)) else f"{path}: "
        raise PlanningError(ErrorCode.INVALID_SCENE, where + message) from None
    if unnamed and not (world or attached):
        _log.warning("%s: a PlanningScene with no name and no objects: the scene is empty", path)


def parse_moveit_scene(data, scene=None, where: str = "PlanningScene"):
    """Reads a parsed PlanningScene YAML.

    Args:
        data: the parsed YAML (None reads as an empty scene).
        scene: the ``PlanningScene`` whose robot places objects given in link frames and held
            ones; without it, such objects are an error.
        where: names the source in messages.

    Returns:
        (world objects in W, held objects in the attachment frame A, allowed link pairs).

    Raises:
        ValueError: naming ``where`` and the key path (``ConfigError`` for the schema).
    """
    data = {} if data is None else data
    if not isinstance(data, dict):
        raise ValueError(f"{where}: a PlanningScene must be a mapping, got {type(data).__name__}")
    check_tree(msgs.PlanningScene, data, where)
    try:
        _check_supported(data)
        frames = _Frames(data, scene)
        world = _objects(data.get("world") or {}, frames)
        attached = _attached(data.get("robot_state") or {}, frames)
        allowed = _allowed(data, frames.links)
    except ValueError as e:
        raise ValueError(f"{where}: {e}") from None
    return world, attached, allowed


def parse_moveit_objects(data, scene=None) -> list[SceneObject]:
    """Returns the world objects of a parsed PlanningScene YAML (see ``parse_moveit_scene``)."""
    return parse_moveit_scene(data, scene)[0]


def parse_allowed_collisions(data) -> list[tuple[str, str]]:
    """Returns the name pairs an ``allowed_collision_matrix`` allows to touch (entry ``[i][j]``
    or ``[j][i]`` true), whatever the names are.

    Raises:
        ValueError: naming the key path of a malformed matrix.
    """
    acm = (data or {}).get("allowed_collision_matrix") or {}
    names, rows = acm.get("entry_names", []), acm.get("entry_values", [])
    if len(rows) != len(names):
        raise ValueError(
            f"allowed_collision_matrix: {len(names)} entry_names, {len(rows)} entry_values rows"
        )
    matrix = []
    for i, row in enumerate(rows):
        path = f"allowed_collision_matrix.entry_values[{i}]"
        if isinstance(row, dict):
            if unknown := sorted(map(str, set(row) - {"enabled"})):
                raise ValueError(f"{path}: unknown key {unknown[0]!r} (known here: enabled)")
            row, path = row.get("enabled", []), f"{path}.enabled"
        if not isinstance(row, list) or len(row) != len(names):
            raise ValueError(f"{path} must be a list of {len(names)} booleans, got {row!r}")
        for j, value in enumerate(row):
            if not isinstance(value, bool):
                raise ValueError(f"{path}[{j}] must be true or false, got {value!r}")
        matrix.append(row)
    n = len(names)
    return [
        (names[i], names[j])
        for i in range(n)
        for j in range(i + 1, n)
        if matrix[i][j] or matrix[j][i]
    ]


def _check_supported(data: dict) -> None:
    for path, diff in (("", data), ("robot_state.", data.get("robot_state") or {})):
        if diff.get("is_diff"):
            raise ValueError(f"{path}is_diff: diffs are not supported (a file is a whole scene)")
    for key, field, neutral in (("link_padding", "padding", 0.0), ("link_scale", "scale", 1.0)):
        for i, entry in enumerate(data.get(key, [])):
            path = f"{key}[{i}].{field}"
            if msgs.number(entry.get(field, neutral), path) != neutral:
                raise ValueError(f"{path}: per-link {field} is not supported")
    octomap = (data.get("world") or {}).get("octomap") or {}  # the schema checked its form
    if (octomap.get("octomap") or {}).get("data"):
        raise ValueError("world.octomap: octomaps are not supported")


class _Frames:
    """The frames a scene names, at its robot configuration ``q`` (9 positions)."""

    def __init__(self, data: dict, scene):
        self.scene = scene
        state = data.get("robot_state") or {}
        for i, transform in enumerate(
            (state.get("multi_dof_joint_state") or {}).get("transforms", [])
        ):
            path = f"robot_state.multi_dof_joint_state.transforms[{i}]"
            if not _identity(_transform(transform, path)):
                raise ValueError(f"{path}: the robot's base is fixed at the world origin")
        self.fixed = _fixed_frames(data.get("fixed_frame_transforms", []))
        self.links, self.q = set(), None
        if scene is not None:
            plant, instance = scene.plant, scene.model.instance
            self.links = {plant.get_body(b).name() for b in plant.GetBodyIndices(instance)}
            self.q = _configuration(scene, state.get("joint_state") or {})

    def X_WF(self, frame_id: str, path: str) -> RigidTransform:
        name = frame_id[1:] if frame_id.startswith("/") else frame_id
        if name in WORLD_FRAMES:
            return RigidTransform()
        if name in self.fixed:
            return self.fixed[name]
        if name in self.links:
            plant = self.scene.plant
            body = plant.GetBodyByName(name, self.scene.model.instance)
            return plant.EvalBodyPoseInWorld(self.scene.plant_context(self.q), body)
        known = ["world", *sorted(self.fixed)] + (["a Panda link"] if self.links else [])
        raise ValueError(f"{path}: unknown frame {frame_id!r} (known: {', '.join(known)})")


def _fixed_frames(entries: list) -> dict[str, RigidTransform]:
    frames = {}
    for i, entry in enumerate(entries):
        path = f"fixed_frame_transforms[{i}]"
        parent = (entry.get("header") or {}).get("frame_id", "").lstrip("/")
        if parent not in WORLD_FRAMES:
            raise ValueError(f"{path}.header.frame_id: only frames in the world are supported")
        X = _transform(entry.get("transform"), f"{path}.transform")
        child = entry.get("child_frame_id", "").lstrip("/")
        if child in WORLD_FRAMES and not _identity(X):
            raise ValueError(f"{path}: the world frame cannot be moved")
        frames[child] = X
    return frames


def _configuration(scene, joint_state: dict) -> np.ndarray:
    """The 9 positions a JointState gives; MoveIt's default for the joints it does not name."""
    plant, instance = scene.plant, scene.model.instance
    lower, upper = plant.GetPositionLowerLimits(), plant.GetPositionUpperLimits()
    q = np.where((lower <= 0.0) & (upper >= 0.0), 0.0, (lower + upper) / 2)
    q[scene.model.finger_indices] = scene.finger_positions
    names, positions = joint_state.get("name", []), joint_state.get("position", [])
    if len(names) != len(positions):
        raise ValueError(f"robot_state.joint_state: {len(names)} names, {len(positions)} positions")
    for i, (name, value) in enumerate(zip(names, positions, strict=True)):
        joint = (
            plant.GetJointByName(name, instance) if plant.HasJointNamed(name, instance) else None
        )
        if joint is None or joint.num_positions() != 1:
            raise ValueError(f"robot_state.joint_state.name[{i}]: the Panda has no joint {name!r}")
        q[joint.position_start()] = msgs.number(value, f"robot_state.joint_state.position[{i}]")
    return q


def _objects(world: dict, frames: _Frames) -> list[SceneObject]:
    objects: dict[str, list] = {}
    for i, entry in enumerate(world.get("collision_objects", [])):
        _apply(objects, entry, f"world.collision_objects[{i}]", frames, "")
    return _flatten(objects)


def _apply(objects: dict, entry: dict, path: str, frames: _Frames, default_frame: str) -> None:
    """Applies one CollisionObject to ``objects`` (id -> [X_WO, [(shape, size, X_OS), ...]])."""
    operation = msgs.operation(entry.get("operation", 0), f"{path}.operation")
    name = entry.get("id", "")
    if operation == "REMOVE":
        if not name:
            objects.clear()
        elif objects.pop(name, None) is None:
            _log.warning("%s: REMOVE of %r, which is not there", path, name)
        return
    if not name:
        raise ValueError(f"{path}.id: a collision object needs an id")
    for key in ("meshes", "planes"):
        if entry.get(key):
            raise ValueError(f"{path}.{key}: object {name!r}: {key} are not supported")
    frame = (entry.get("header") or {}).get("frame_id", "") or default_frame
    X_WO = frames.X_WF(frame, f"{path}.header.frame_id") @ msgs.pose(
        entry.get("pose"), f"{path}.pose"
    )
    poses = [
        msgs.pose(p, f"{path}.primitive_poses[{k}]")
        for k, p in enumerate(entry.get("primitive_poses", []))
    ]
    if operation == "MOVE":
        if name not in objects:
            raise ValueError(f"{path}.id: MOVE of {name!r}, which is not there")
        shapes = objects[name][1]
        if poses and len(poses) != len(shapes):
            raise ValueError(f"{path}.primitive_poses: {len(poses)} poses, {len(shapes)} shapes")
        if poses:
            shapes = [(s, size, X) for (s, size, _), X in zip(shapes, poses, strict=True)]
        objects[name] = [X_WO, shapes]
        return
    primitives = [
        msgs.primitive(p, f"{path}.primitives[{k}]")
        for k, p in enumerate(entry.get("primitives", []))
    ]
    if len(primitives) != len(poses):
        raise ValueError(
            f"{path}: object {name!r} has {len(primitives)} primitives, {len(poses)} poses"
        )
    if not primitives:
        raise ValueError(f"{path}.primitives: object {name!r} has no primitives")
    shapes = [(s, size, X) for (s, size), X in zip(primitives, poses, strict=True)]
    if operation == "APPEND" and name in objects:
        X_old = objects[name][0]
        objects[name][1].extend((s, size, X_old.inverse() @ X_WO @ X) for s, size, X in shapes)
    else:
        objects[name] = [X_WO, shapes]


def _flatten(objects: dict) -> list[SceneObject]:
    return [
        SceneObject(name if k == 0 else f"{name}#{k}", shape, size, X_WO @ X_OS)
        for name, (X_WO, shapes) in objects.items()
        for k, (shape, size, X_OS) in enumerate(shapes)
    ]


def _attached(state: dict, frames: _Frames) -> list[SceneObject]:
    entries = state.get("attached_collision_objects", [])
    if not entries:
        return []
    if frames.scene is None:
        raise ValueError("robot_state.attached_collision_objects: held objects need the robot")
    scene = frames.scene
    attachment = scene.plant.GetBodyByName(ATTACHMENT_BODY, scene.model.instance)
    hand = {body.name() for body in scene.plant.GetBodiesWeldedTo(attachment)}
    X_AW = scene.attachment_pose(frames.q).inverse()
    result = []
    for i, entry in enumerate(entries):
        path = f"robot_state.attached_collision_objects[{i}]"
        link = entry.get("link_name", "")
        if link not in hand:
            links = ", ".join(sorted(hand))
            raise ValueError(
                f"{path}.link_name: objects attach to the hand ({links}), got {link!r}"
            )
        body = entry.get("object") or {}
        if msgs.operation(body.get("operation", 0), f"{path}.object.operation") != "ADD":
            raise ValueError(f"{path}.object.operation: a scene file attaches objects by ADD only")
        objects: dict[str, list] = {}
        _apply(objects, body, f"{path}.object", frames, link)
        result += [o.with_pose(X_AW @ o.X_PO) for o in _flatten(objects)]
        extra = sorted(set(entry.get("touch_links", [])) - hand - set(_FINGERS))
        if extra:
            _log.warning(
                "%s: touch links %s not applied (held objects touch the hand only)", path, extra
            )
    return result


def _allowed(data: dict, links: set[str]) -> list[tuple[str, str]]:
    pairs = []
    for a, b in parse_allowed_collisions(data):
        if a in links and b in links:
            pairs.append((a, b))
        else:
            _log.warning("allowed collision %s <-> %s not applied (only Panda link pairs)", a, b)
    acm = data.get("allowed_collision_matrix") or {}
    names, values = acm.get("default_entry_names", []), acm.get("default_entry_values", [])
    if len(names) != len(values):
        raise ValueError(
            f"allowed_collision_matrix: {len(names)} default_entry_names, {len(values)} values"
        )
    if any(values):
        _log.warning("allowed_collision_matrix: default entries not applied")
    return pairs


def _transform(value, path: str) -> RigidTransform:
    return msgs.pose(value, path, position="translation", orientation="rotation")


def _identity(X: RigidTransform) -> bool:
    return X.IsNearlyEqualTo(RigidTransform(), 1e-9)
