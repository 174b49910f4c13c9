"""Loading and saving planning scenes: our pick-and-place YAML and MoveIt's PlanningScene YAML.

Our format (``config/pickplace.yaml``; world frame, metres, box centres)::

    table:    {size: [sx, sy, sz], position: [x, y, z]}
    object:   {size: [sx, sy, sz], position: [x, y, z], mass: kg, yaw: rad}
    obstacle: {size: [sx, sy, sz], position: [x, y, z], yaw: rad}
    place:    {position: [x, y, z]}
    objects:  # more objects, any shape: size as in scene_objects.SHAPE_SIZES
      - {name: can, shape: cylinder, size: [radius, length], position: [...],
         orientation: [x, y, z, w], color: [r, g, b, a]}
      - {name: hull, shape: convex, vertices: [[x, y, z], ...], position: [...]}
    attached: # held objects, pose in the hand's attachment frame A (same keys as objects)

A convex object is the convex hull of its ``vertices`` (in its frame, m) and has no size;
``color`` (optional, in [0, 1]) is for display.

Loading replaces the whole scene: world objects (the table too), held objects, allowed
collisions (back to the robot's own) and the place target. An empty file (blank, or comments
only) is an error; ``{}`` is an explicitly empty scene.

MoveIt's scene files (PlanningScene YAML and the text ``.scene`` format) are read by
``planning.io.moveit_scene``; ``load_moveit_scene`` (which returns a ``MoveItScene``: the start
configuration, the warnings), ``parse_moveit_objects`` and ``parse_allowed_collisions`` are
importable from here too.
"""

import dataclasses as dc
import math
from pathlib import Path

import yaml

from drake_sim.base.config import load_typed, parse_yaml, read_text
from drake_sim.base.errors import ConfigError
from planning.errors import ErrorCode, PlanningError
from planning.io.moveit_scene import (
    MoveItScene,
    load_moveit_scene,
    parse_allowed_collisions,
    parse_moveit_objects,
)
from planning.scene_objects import SceneObject, make_pose

__all__ = [
    "BoxSpec",
    "MoveItScene",
    "ObjectSpec",
    "PlaceSpec",
    "SceneFile",
    "apply_scene_file",
    "load_moveit_scene",
    "load_scene_yaml",
    "parse_allowed_collisions",
    "parse_moveit_objects",
    "save_scene_yaml",
]


@dc.dataclass
class BoxSpec:
    size: list[float] = dc.field(default_factory=list)  # m, full extents
    position: list[float] = dc.field(default_factory=list)  # m, centre in W
    yaw: float = 0.0  # rad about the world z axis
    mass: float = 0.0  # kg (kept for the simulation; planning ignores it)
    friction: float = 0.0  # Coulomb coefficient (kept for the simulation)


@dc.dataclass
class PlaceSpec:
    position: list[float] = dc.field(default_factory=list)  # m, target of the object's centre


@dc.dataclass
class ObjectSpec:
    name: str = ""
    shape: str = "box"  # box, cylinder, sphere or convex
    size: list[float] = dc.field(default_factory=list)  # m, see scene_objects.SHAPE_SIZES
    position: list[float] = dc.field(default_factory=list)  # m
    orientation: list[float] = dc.field(default_factory=lambda: [0.0, 0.0, 0.0, 1.0])  # x,y,z,w
    vertices: list[list[float]] = dc.field(default_factory=list)  # m, a convex object's points
    color: list[float] = dc.field(default_factory=list)  # r, g, b, a in [0, 1]; [] for none


@dc.dataclass
class SceneFile:
    """The schema of our scene YAML."""

    table: BoxSpec | None = None
    object: BoxSpec | None = None
    obstacle: BoxSpec | None = None
    place: PlaceSpec | None = None
    objects: list[ObjectSpec] = dc.field(default_factory=list)
    attached: list[ObjectSpec] = dc.field(default_factory=list)


def load_scene_yaml(scene, filename: Path | str) -> None:
    """Replaces the whole of ``scene`` by our scene YAML (see the module's docstring).

    Raises:
        PlanningError: INVALID_SCENE for a malformed or empty file (no YAML document: blank or
            comments only; ``{}`` is an explicitly empty scene) or bad values, naming the file.
    """
    where = str(filename)
    try:
        text = read_text(filename, "scene file")
        if parse_yaml(text, where) is None:
            raise ConfigError(f"{where}: empty scene file (expected keys such as table, objects)")
        spec = load_typed(SceneFile, data=text, where=where)
    except ConfigError as e:
        raise PlanningError(ErrorCode.INVALID_SCENE, str(e)) from None
    apply_scene_file(scene, spec, where=str(filename))


def apply_scene_file(scene, spec: SceneFile, *, where: str = "scene") -> None:
    """Replaces the whole of ``scene`` by a parsed ``SceneFile`` (``place_position`` included).

    Raises:
        PlanningError: INVALID_SCENE for bad values, naming ``where`` and the object.
    """
    try:
        objects = [
            _box_object(name, box)
            for name, box in (
                ("table", spec.table),
                ("object", spec.object),
                ("obstacle", spec.obstacle),
            )
            if box is not None
        ]
        objects += [_spec_object(o) for o in spec.objects]
        attached = [_spec_object(o) for o in spec.attached]
        place = None if spec.place is None else make_pose(spec.place.position, name="place")
    except ValueError as e:
        raise PlanningError(ErrorCode.INVALID_SCENE, f"{where}: {e}") from e
    try:
        scene.replace(objects, attached)
    except PlanningError as e:
        raise PlanningError(ErrorCode.INVALID_SCENE, f"{where}: {e.message}") from None
    scene.place_position = None if place is None else place.translation()


def save_scene_yaml(scene, filename: Path | str) -> None:
    """Writes the scene's world and held objects in our YAML (everything under ``objects`` and
    ``attached``, with the table, object and obstacle boxes under their own keys when they are
    yaw-only boxes)."""
    data: dict = {}
    objects = []
    for name, obj in scene.world_objects.items():
        yaw = _yaw_only(obj)
        if name in ("table", "object", "obstacle") and obj.shape == "box" and yaw is not None:
            entry = {"size": list(obj.size), "position": obj.X_PO.translation().tolist()}
            if yaw != 0.0:
                entry["yaw"] = yaw
            data[name] = entry
        else:
            objects.append(_object_entry(obj))
    if scene.place_position is not None:
        data["place"] = {"position": [float(v) for v in scene.place_position]}
    if objects:
        data["objects"] = objects
    if scene.attached_objects:
        data["attached"] = [_object_entry(o) for o in scene.attached_objects.values()]
    Path(filename).write_text(yaml.safe_dump(data, sort_keys=False, default_flow_style=None))


def _box_object(name: str, box: BoxSpec) -> SceneObject:
    from pydrake.math import RigidTransform, RollPitchYaw

    X = make_pose(box.position, name=name)
    return SceneObject(
        name, "box", tuple(box.size), RigidTransform(RollPitchYaw(0, 0, box.yaw), X.translation())
    )


def _spec_object(spec: ObjectSpec) -> SceneObject:
    X = make_pose(spec.position, spec.orientation, name=f"object {spec.name!r}")
    color = tuple(spec.color) if spec.color else None
    vertices = tuple(map(tuple, spec.vertices))
    return SceneObject(spec.name, spec.shape, tuple(spec.size), X, vertices, color)


def _object_entry(obj: SceneObject) -> dict:
    q = obj.X_PO.rotation().ToQuaternion()
    entry = {"name": obj.name, "shape": obj.shape}
    if obj.vertices:
        entry["vertices"] = [list(p) for p in obj.vertices]
    else:
        entry["size"] = list(obj.size)
    entry["position"] = obj.X_PO.translation().tolist()
    entry["orientation"] = [q.x(), q.y(), q.z(), q.w()]
    if obj.color is not None:
        entry["color"] = list(obj.color)
    return entry


def _yaw_only(obj: SceneObject) -> float | None:
    R = obj.X_PO.rotation().matrix()
    if abs(R[2, 2] - 1.0) > 1e-9:
        return None
    return float(math.atan2(R[1, 0], R[0, 0]))
