"""MoveIt's planning scenes: ``moveit_msgs/PlanningScene`` YAML and the text ``.scene`` format.

``load_moveit_scene`` picks the reader by the file's extension (``.yaml``/``.yml``, or ``.scene``
for ``planning.io.moveit_text``) and replaces the whole scene, as MoveIt does with a scene that
is not a diff: world objects, held objects, allowed collisions; the place target is cleared. It
returns a ``MoveItScene``: what was loaded, the scene's robot state as a start configuration,
and the warnings given.

A PlanningScene YAML is read as MoveIt reads it:

- ``world.collision_objects`` in order, each by its ``operation`` (``moveit_objects``): ADD,
  REMOVE, APPEND, MOVE. Shapes (``moveit_shapes``): boxes, spheres and cylinders as they are;
  meshes (inline, or a file by path or ``package://`` URI through ``package_paths``), cones and
  prisms as their convex hulls; planes as a large box behind them. Poses are given in
  ``header.frame_id`` (``moveit_frames``): the world, a link of the scene's robot at the scene's
  robot state, an earlier object or its subframe, a frame of ``fixed_frame_transforms``. An
  object of several shapes becomes objects ``id``, ``id#1``, ``id#2``, ...; its subframes become
  frames of ``id`` (``SceneObject.frame``, ``scene_objects.subframe_pose``) and its colour in
  ``object_colors`` the colour of each.
- ``robot_state``: ``joint_state`` is the start configuration (``MoveItScene.start``: joints it
  does not name keep their values) at which link frames are placed; its
  ``attached_collision_objects`` are held objects, on ``link_name``, which must be the link held
  objects hang on (the hand) or a link welded to it; their poses are kept in that attachment
  frame.
- ``allowed_collision_matrix``: pairs of the robot's links allowed to touch become collision
  filters on top of the robot's own.
- A diff (``is_diff: true``) is applied to an empty scene, as robowflex loads a scene file.

What MoveIt would load but cannot be represented here is left out with a warning (logged on
this module's logger, one line naming the file, the key path or object, and why), not a
rejection of the file: an object in a frame this robot does not have (a link of another robot),
joints of another robot, a mesh file that cannot be found or read, an object held on a link that
does not carry held objects, allowed pairs naming objects or other robots' links, default
allowed entries, link padding and scaling, an octomap. ``strict=True`` makes each of those an
error instead.

A file with no YAML document (empty, blank, comments only) is an error, like an empty ``.scene``
file; a PlanningScene with neither a ``name`` nor an object loads as an empty scene with one
warning (MoveIt applies such a message as a scene without objects), and one with a name and no
objects is a valid empty scene. A malformed file raises ``PlanningError(INVALID_SCENE)`` naming
the file and the key path: unknown keys, values of the wrong type, NaN, a zero quaternion,
counts that do not match (shapes and poses, names and positions), unknown primitive types or
operations, mesh triangles naming vertices that are not there.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drake_sim.base.config import check_tree, parse_yaml, read_text
from planning.errors import ErrorCode, PlanningError
from planning.io import moveit_msgs as msgs
from planning.io.moveit_frames import SceneFrames, robot_links
from planning.io.moveit_objects import Context, Issues, apply, flatten
from planning.io.moveit_text import read_scene_text
from planning.scene_objects import SceneObject

_log = logging.getLogger(__name__)


@dataclass
class MoveItScene:
    """What a MoveIt scene file held, as loaded.

    Attributes:
        name: the scene's name ("" when it has none).
        world: the world objects (poses in the world W).
        attached: the held objects (poses in the attachment frame A).
        allowed: the pairs of robot links allowed to touch.
        start: the scene's robot state as the plant's positions (joints it does not name at
            their defaults), or None for a ``.scene`` file, which has no robot state.
        joint_positions: {joint: value} of the joints the robot state names and the robot has.
        warnings: the warnings given, one line each.
        skipped: the ids of the objects left out.
    """

    name: str = ""
    world: list[SceneObject] = field(default_factory=list)
    attached: list[SceneObject] = field(default_factory=list)
    allowed: list[tuple[str, str]] = field(default_factory=list)
    start: np.ndarray | None = None
    joint_positions: dict[str, float] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)


def load_moveit_scene(
    scene, filename: Path | str, *, strict: bool = False, package_paths=None, base=None
) -> MoveItScene:
    """Replaces the whole of ``scene`` by a MoveIt scene file (``.yaml``, ``.yml``, ``.scene``).

    Args:
        scene: the ``PlanningScene``.
        filename: the file.
        strict: make what cannot be represented an error, not a warning.
        package_paths: ``{package: folder}`` for ``package://`` mesh files (besides the
            packages ``drake_sim.robots.files.robot_files`` knows); relative paths are
            relative to the scene file's folder.
        base: plant positions that joints the scene's robot state does not name keep
            (MoveIt's defaults when None).

    Returns:
        What was loaded, with the start configuration and the warnings.

    Raises:
        PlanningError: INVALID_SCENE for a missing, unreadable or malformed file, a bad value,
            or (``strict``) anything left out, naming the file and the key path (or line); the
            scene is then left as it was.
    """
    path = Path(filename)
    suffix = path.suffix.lower()
    issues = Issues(str(path), strict)
    unnamed = False
    try:
        if suffix == ".scene":
            text = read_text(path, "scene file")
            name, world = read_scene_text(text, str(path), issues, path.parent, package_paths)
            loaded = MoveItScene(name=name, world=world)
        elif suffix in (".yaml", ".yml"):
            data = parse_yaml(read_text(path, "scene file"), str(path))
            if data is None:  # no YAML document: empty, blank or comments only
                raise ValueError(f"{path}: empty scene file (expected a PlanningScene mapping)")
            loaded = read_moveit_scene(
                data,
                scene,
                str(path),
                issues=issues,
                folder=path.parent,
                package_paths=package_paths,
                base=base,
            )
            unnamed = not data.get("name")
        else:
            raise ValueError(f"{path}: not a MoveIt scene file (.scene, .yaml or .yml)")
        scene.replace(loaded.world, loaded.attached, loaded.allowed)
    except (ValueError, PlanningError) as e:
        message = e.message if isinstance(e, PlanningError) else str(e)
        where = "" if message.startswith(str(path)) else f"{path}: "
        raise PlanningError(ErrorCode.INVALID_SCENE, where + message) from None
    if unnamed and not (loaded.world or loaded.attached or loaded.skipped):
        _log.warning("%s: a PlanningScene with no name and no objects: the scene is empty", path)
    loaded.warnings, loaded.skipped = issues.warnings, issues.skipped
    return loaded


def read_moveit_scene(
    data,
    scene=None,
    where: str = "PlanningScene",
    *,
    issues: Issues | None = None,
    strict: bool = False,
    folder: Path | None = None,
    package_paths=None,
    base=None,
) -> MoveItScene:
    """Reads a parsed PlanningScene YAML (see ``load_moveit_scene`` for the arguments).

    Args:
        scene: the ``PlanningScene`` whose robot places objects given in link frames and held
            ones; without it, link frames are unknown and held objects an error.
        issues: where warnings go (a new ``Issues(where, strict)`` when None).
        folder: the folder relative mesh paths are relative to (the working folder if None).

    Raises:
        ValueError: naming ``where`` and the key path (``ConfigError`` for the schema).
    """
    data = {} if data is None else data
    if not isinstance(data, dict):
        raise ValueError(f"{where}: a PlanningScene must be a mapping, got {type(data).__name__}")
    check_tree(msgs.PlanningScene, data, where)
    issues = Issues(where, strict) if issues is None else issues
    try:
        _unsupported(data, issues)
        frames = SceneFrames(data, scene, issues, base)
        ctx = Context(frames, issues, Path(folder or "."), package_paths)
        colors = _colors(data.get("object_colors", []))
        objects: dict = {}
        for i, entry in enumerate((data.get("world") or {}).get("collision_objects", [])):
            apply(objects, entry, f"world.collision_objects[{i}]", ctx)
        world = flatten(objects, colors)
        attached = _attached(data.get("robot_state") or {}, ctx, colors)
        allowed = _allowed(data, set(frames.links), issues)
    except ValueError as e:
        message = str(e)
        raise ValueError(message if message.startswith(where) else f"{where}: {message}") from None
    return MoveItScene(
        name=data.get("name", ""),
        world=world,
        attached=attached,
        allowed=allowed,
        start=frames.q,
        joint_positions=frames.joints,
        warnings=issues.warnings,
        skipped=issues.skipped,
    )


def parse_moveit_scene(data, scene=None, where: str = "PlanningScene", **options):
    """Returns (world objects in W, held objects in the attachment frame A, allowed link pairs)
    of a parsed PlanningScene YAML (see ``read_moveit_scene``, which takes the same options).

    Raises:
        ValueError: naming ``where`` and the key path (``ConfigError`` for the schema).
    """
    loaded = read_moveit_scene(data, scene, where, **options)
    return loaded.world, loaded.attached, loaded.allowed


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


def _unsupported(data: dict, issues: Issues) -> None:
    """Warns of what the scene sets that is not applied here (link padding and scale, an
    octomap); a diff is read as a whole scene."""
    if data.get("is_diff") or (data.get("robot_state") or {}).get("is_diff"):
        _log.info("%s: a scene diff (is_diff), applied to an empty scene", issues.where)
    for key, value, neutral in (("link_padding", "padding", 0.0), ("link_scale", "scale", 1.0)):
        for i, entry in enumerate(data.get(key, [])):
            path = f"{key}[{i}].{value}"
            if msgs.number(entry.get(value, neutral), path) != neutral:
                link = entry.get("link_name", "")
                issues.drop(path, f"per-link {value} of {link!r} is not applied")
    octomap = (data.get("world") or {}).get("octomap") or {}  # the schema checked its form
    if (octomap.get("octomap") or {}).get("data"):
        issues.drop("world.octomap", "octomaps are not applied (the scene keeps its objects)")


def _colors(entries: list) -> dict[str, tuple]:
    colors = {}
    for i, entry in enumerate(entries):
        colors[entry.get("id", "")] = msgs.color(entry.get("color"), f"object_colors[{i}].color")
    return colors


def attachment_links(scene) -> tuple[str, set[str]]:
    """The body held objects hang on and the links welded to it (where objects may attach)."""
    model, plant = scene.model, scene.plant
    body = plant.GetBodyByName(model.attachment_body, model.instance)
    return model.attachment_body, {b.name() for b in plant.GetBodiesWeldedTo(body)}


def _attached(state: dict, ctx: Context, colors: dict) -> list[SceneObject]:
    entries = state.get("attached_collision_objects", [])
    if not entries:
        return []
    scene = ctx.frames.scene
    if scene is None:
        raise ValueError("robot_state.attached_collision_objects: held objects need the robot")
    attachment, hand = attachment_links(scene)
    X_AW = scene.attachment_pose(ctx.frames.q).inverse()
    result = []
    for i, entry in enumerate(entries):
        path = f"robot_state.attached_collision_objects[{i}]"
        body = entry.get("object") or {}
        name, link = body.get("id", ""), entry.get("link_name", "")
        operation = msgs.operation(body.get("operation", 0), f"{path}.object.operation")
        if link not in hand:
            links = ", ".join(sorted(hand - {attachment}))
            ctx.issues.drop(
                f"{path}.link_name",
                f"held object {name!r} skipped: objects are held on {links} here, not {link!r}",
                name,
            )
            continue
        if operation != "ADD":
            ctx.issues.drop(
                f"{path}.object.operation",
                f"{operation} of held object {name!r} "
                "not applied (a scene file attaches objects by ADD)",
                name,
            )
            continue
        objects: dict = {}
        apply(objects, body, f"{path}.object", ctx, link)
        result += [o.with_pose(X_AW @ o.X_PO) for o in flatten(objects, colors)]
        extra = sorted(set(entry.get("touch_links", [])) - _touching(scene, attachment))
        if extra:
            _log.warning(
                "%s: %s: touch links %s not applied (held objects touch only the links the "
                "robot's model lets them: the hand and its fingers)",
                ctx.issues.where,
                path,
                extra,
            )
    return result


def _touching(scene, attachment: str) -> set[str]:
    """The links held objects are not checked against: those the checker filters against the
    attachment body (the hand and what the model lets touch it, such as fingers)."""
    links = robot_links(scene)
    body = links[attachment]
    return {n for n, b in links.items() if scene.checker.IsCollisionFilteredBetween(body, b)}


def _allowed(data: dict, links: set[str], issues: Issues) -> list[tuple[str, str]]:
    pairs, others = [], []
    for a, b in parse_allowed_collisions(data):
        (pairs if a in links and b in links else others).append((a, b))
    if others:
        shown = ", ".join(f"{a} <-> {b}" for a, b in others[:3])
        more = f" and {len(others) - 3} more" if len(others) > 3 else ""
        issues.drop(
            "allowed_collision_matrix",
            f"{len(others)} allowed pairs not applied (only pairs of this robot's links): "
            f"{shown}{more}",
        )
    acm = data.get("allowed_collision_matrix") or {}
    names, values = acm.get("default_entry_names", []), acm.get("default_entry_values", [])
    if len(names) != len(values):
        raise ValueError(
            f"allowed_collision_matrix: {len(names)} default_entry_names, {len(values)} values"
        )
    if any(values):
        allowed = [n for n, v in zip(names, values, strict=True) if v]
        issues.drop("allowed_collision_matrix", f"default entries not applied: {allowed}")
    return pairs
