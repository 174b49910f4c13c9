"""MoveIt's collision objects applied one by one, as MoveIt applies a scene's messages, and
turned into ``SceneObject``s.

An object in progress (``Entry``) is its pose in the world, its shapes (``moveit_shapes.Piece``,
each at its pose in the object's frame) and its subframes (poses in the object's frame).
``apply`` applies one ``moveit_msgs/CollisionObject`` by its operation: ADD (replaces an object
of the same id), REMOVE (every object when the id is empty), APPEND (more shapes) and MOVE (a
new pose, and new ``primitive_poses`` when given). ``flatten`` makes each shape an object:
``id``, ``id#1``, ``id#2``, ..., the first carrying the subframes (as frames of its own) and
every one the object's colour.

What MoveIt would load but cannot be represented here (a frame this robot does not have, a mesh
file that cannot be read, ...) goes to ``Issues``: a warning naming the object (the object or
shape skipped), or an error in strict mode. A malformed message raises ``ValueError``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

from pydrake.math import RigidTransform

from planning.io import moveit_msgs as msgs
from planning.io import moveit_shapes as shapes
from planning.scene_objects import SceneObject

_log = logging.getLogger("planning.io.moveit_scene")


class Issues:
    """What a scene file holds that cannot be represented here: each is a warning (logged on
    ``planning.io.moveit_scene``, one line naming the file, the key path or object and why; the
    object or value skipped), or, when ``strict``, a ``ValueError`` with the same message.

    Attributes:
        warnings: the messages of the warnings given, in order.
        skipped: the ids of the objects left out, in order.
    """

    def __init__(self, where: str, strict: bool = False):
        self.where, self.strict = where, strict
        self.warnings: list[str] = []
        self.skipped: list[str] = []

    def drop(self, path: str, message: str, object_id: str | None = None) -> None:
        """Reports one thing left out (``object_id``: the object skipped, if it is one).

        Raises:
            ValueError: in strict mode, naming the file, ``path`` and ``message``.
        """
        if path.isdigit():  # a line of a text file
            text = f"{self.where}:{path}: {message}"
        else:
            text = f"{self.where}: {path}: {message}" if path else f"{self.where}: {message}"
        if self.strict:
            raise ValueError(f"{text} (strict: nothing is left out)")
        _log.warning("%s", text)
        self.warnings.append(text)
        if object_id is not None and object_id not in self.skipped:
            self.skipped.append(object_id)


@dataclass
class Entry:
    """An object in progress: its pose X_WO, its shapes in O and its subframes X_OS."""

    X_WO: RigidTransform
    pieces: list[shapes.Piece]
    subframes: dict[str, RigidTransform] = field(default_factory=dict)


@dataclass
class Context:
    """What reading objects needs besides the message: the frames (``X_WF(frame_id, path)``
    returns a pose or None for an unknown frame), the issues, and where mesh files are found
    (``base``: the scene file's folder; ``package_paths``: ``{package: folder}``)."""

    frames: object
    issues: Issues
    base: Path = Path(".")
    package_paths: dict | None = None


def apply(
    objects: dict[str, Entry], entry: dict, path: str, ctx: Context, default_frame: str = ""
) -> None:
    """Applies one CollisionObject to ``objects`` (by id, in order of first addition).

    Raises:
        ValueError: a malformed object, naming ``path``.
    """
    operation = msgs.operation(entry.get("operation", 0), f"{path}.operation")
    name = entry.get("id", "")
    if operation == "REMOVE":
        if not name:
            objects.clear()
        elif objects.pop(name, None) is None:
            _log.warning("%s: %s: REMOVE of %r, which is not there", ctx.issues.where, path, name)
        return
    if not name:
        raise ValueError(f"{path}.id: a collision object needs an id")
    frame = (entry.get("header") or {}).get("frame_id", "") or default_frame
    X_WF = ctx.frames.X_WF(frame, objects)
    if X_WF is None:
        known = ctx.frames.describe()
        message = f"object {name!r} skipped: unknown frame {frame!r} (known: {known})"
        ctx.issues.drop(f"{path}.header.frame_id", message, None if name in objects else name)
        return
    X_WO = X_WF @ msgs.pose(entry.get("pose"), f"{path}.pose")
    poses = _poses(entry, "primitive_poses", path)
    if operation == "MOVE":
        _move(objects, name, X_WO, poses, path)
        return
    pieces = _pieces(entry, name, poses, X_WO, path, ctx)
    subframes = _subframes(entry, path)
    if operation == "APPEND" and name in objects:
        old = objects[name]
        X_OW = old.X_WO.inverse() @ X_WO
        old.pieces.extend(p.at(X_OW @ p.X_OS) for p in pieces)
        old.subframes.update({s: X_OW @ X for s, X in subframes.items()})
    elif pieces:
        objects[name] = Entry(X_WO, pieces, subframes)
    else:  # every shape was left out (with a warning each)
        objects.pop(name, None)
        if name not in ctx.issues.skipped:
            ctx.issues.skipped.append(name)


def _poses(entry: dict, key: str, path: str) -> list[RigidTransform]:
    return [msgs.pose(p, f"{path}.{key}[{k}]") for k, p in enumerate(entry.get(key, []))]


def _move(objects: dict, name: str, X_WO, poses: list, path: str) -> None:
    if name not in objects:
        raise ValueError(f"{path}.id: MOVE of {name!r}, which is not there")
    old = objects[name]
    if poses and len(poses) != len(old.pieces):
        raise ValueError(f"{path}.primitive_poses: {len(poses)} poses, {len(old.pieces)} shapes")
    pieces = [p.at(X) for p, X in zip(old.pieces, poses, strict=True)] if poses else old.pieces
    objects[name] = Entry(X_WO, pieces, old.subframes)


def _pieces(entry: dict, name: str, poses: list, X_WO, path: str, ctx: Context) -> list:
    """The object's shapes in MoveIt's order (primitives, meshes, planes); those that cannot be
    represented are left out, one warning each."""
    primitives, meshes, planes = (entry.get(k, []) for k in ("primitives", "meshes", "planes"))
    if not (primitives or meshes or planes):
        raise ValueError(f"{path}.primitives: object {name!r} has no primitives, meshes or planes")
    shape_lists = [
        ("primitives", "primitive_poses", primitives, poses),
        ("meshes", "mesh_poses", meshes, _poses(entry, "mesh_poses", path)),
        ("planes", "plane_poses", planes, _poses(entry, "plane_poses", path)),
    ]
    for key, pose_key, values, key_poses in shape_lists:
        if len(values) != len(key_poses):
            raise ValueError(
                f"{path}: object {name!r} has {len(values)} {key}, {len(key_poses)} {pose_key}"
            )
    pieces = []
    p_O_origin = X_WO.inverse().translation()  # the world origin, in O (planes centre near it)
    for key, _, values, key_poses in shape_lists:
        for k, (value, X_OS) in enumerate(zip(values, key_poses, strict=True)):
            where = f"{path}.{key}[{k}]"
            try:
                pieces.append(_piece(key, value, X_OS, p_O_origin, where, ctx))
            except shapes.UnrepresentableError as e:
                kind = {"primitives": "primitive", "meshes": "mesh", "planes": "plane"}[key]
                ctx.issues.drop(where, f"object {name!r}: {kind} skipped: {e}", None)
    return pieces


def _piece(key: str, value: dict, X_OS, p_O_origin, where: str, ctx: Context) -> shapes.Piece:
    if key == "primitives":
        kind, size = msgs.primitive(value, where)
        polygon = [(p.get("x", 0.0), p.get("y", 0.0)) for p in _polygon(value, kind, where)]
        return shapes.solid(kind, size, X_OS, polygon)
    if key == "meshes":
        return shapes.mesh(value, X_OS, where, ctx.base, ctx.package_paths)
    return shapes.plane(value.get("coef", []), X_OS, p_O_origin, where)


def _polygon(value: dict, kind: str, where: str) -> list[dict]:
    points = (value.get("polygon") or {}).get("points", [])
    for i, point in enumerate(points):
        for axis in ("x", "y"):
            msgs.number(point.get(axis, 0.0), f"{where}.polygon.points[{i}].{axis}")
    if kind == "prism" and len(points) < 3:
        raise ValueError(f"{where}.polygon: a prism needs 3 points or more, got {len(points)}")
    return points


def _subframes(entry: dict, path: str) -> dict[str, RigidTransform]:
    names, poses = entry.get("subframe_names", []), entry.get("subframe_poses", [])
    if len(names) != len(poses):
        raise ValueError(f"{path}: {len(names)} subframe_names, {len(poses)} subframe_poses")
    result = {}
    for k, (name, pose) in enumerate(zip(names, poses, strict=True)):
        if not name or "/" in name or name in result:
            raise ValueError(f"{path}.subframe_names[{k}]: {name!r} (names are unique, no '/')")
        result[name] = msgs.pose(pose, f"{path}.subframe_poses[{k}]")
    return result


def flatten(objects: dict[str, Entry], colors: dict | None = None) -> list[SceneObject]:
    """One SceneObject per shape, in the world: ``id``, ``id#1``, ...; the first carries the
    object's subframes (moved into its own frame), each the object's colour."""
    colors = colors or {}
    result = []
    for name, entry in objects.items():
        for k, piece in enumerate(entry.pieces):
            subframes = ()
            if k == 0 and entry.subframes:
                X_SO = piece.X_OS.inverse()
                subframes = tuple((s, X_SO @ X) for s, X in entry.subframes.items())
            result.append(
                SceneObject(
                    name if k == 0 else f"{name}#{k}",
                    piece.shape,
                    piece.size,
                    entry.X_WO @ piece.X_OS,
                    vertices=piece.vertices,
                    color=colors.get(name),
                    subframes=subframes,
                )
            )
    return result
