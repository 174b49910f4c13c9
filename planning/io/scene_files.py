"""Loading and saving planning scenes: our pick-and-place YAML and MoveIt's PlanningScene YAML.

Our format (``config/pickplace.yaml``; world frame, metres, box centres)::

    table:    {size: [sx, sy, sz], position: [x, y, z]}
    object:   {size: [sx, sy, sz], position: [x, y, z], mass: kg, yaw: rad}
    obstacle: {size: [sx, sy, sz], position: [x, y, z], yaw: rad}
    place:    {position: [x, y, z]}
    objects:  # more objects, any shape: size as in scene_objects.SHAPE_SIZES
      - {name: can, shape: cylinder, size: [radius, length], position: [...],
         orientation: [x, y, z, w]}
    attached: # held objects, pose in the hand's attachment frame A (same keys as objects)

MoveIt's ``moveit_msgs/PlanningScene`` YAML (e.g. the MotionBenchMaker files): each of
``world.collision_objects`` has an ``id``, ``primitives`` (box ``dimensions: [x, y, z]``,
cylinder ``[height, radius]``, sphere ``[radius]``) and ``primitive_poses`` (position and an
``[x, y, z, w]`` quaternion, composed with the object's ``pose`` when it has one). An object with
several primitives becomes objects ``id``, ``id#1``, ``id#2``, ... ``allowed_collision_matrix``
entries that allow two robot links to touch become collision filters.
"""

import dataclasses as dc
import logging
import math
from pathlib import Path

import yaml

from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from planning.errors import ErrorCode, PlanningError
from planning.scene_objects import SceneObject, make_pose

_log = logging.getLogger(__name__)
# libyaml's parser when PyYAML has it: the MBM scene files parse about 10 times faster.
_SafeLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_MOVEIT_TYPES = {1: "box", 2: "sphere", 3: "cylinder", 4: "cone"}


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
    shape: str = "box"  # box, cylinder or sphere
    size: list[float] = dc.field(default_factory=list)  # m, see scene_objects.SHAPE_SIZES
    position: list[float] = dc.field(default_factory=list)  # m
    orientation: list[float] = dc.field(default_factory=lambda: [0.0, 0.0, 0.0, 1.0])  # x,y,z,w


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
    """Replaces the world objects of ``scene`` (the table too) by those of our scene YAML.

    Raises:
        PlanningError: INVALID_SCENE for a malformed file or bad values, naming the file.
    """
    try:
        spec = load_typed(SceneFile, filename=filename)
    except ConfigError as e:
        raise PlanningError(ErrorCode.INVALID_SCENE, str(e)) from None
    apply_scene_file(scene, spec, where=str(filename))


def apply_scene_file(scene, spec: SceneFile, *, where: str = "scene") -> None:
    """Replaces the world objects of ``scene`` (the table too) by those of a parsed
    ``SceneFile`` and sets ``scene.place_position``.

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
    _replace(scene, objects, attached, where)
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


def load_moveit_scene(scene, filename: Path | str) -> None:
    """Replaces the world objects of ``scene`` (the table too) by a MoveIt PlanningScene's.

    Raises:
        PlanningError: INVALID_SCENE for a malformed file, an unsupported shape (meshes, cones)
            or bad values; the message names the file and the object.
    """
    filename = Path(filename)
    try:
        data = yaml.load(filename.read_text(), Loader=_SafeLoader)
    except (OSError, yaml.YAMLError) as e:
        raise PlanningError(ErrorCode.INVALID_SCENE, f"{filename}: {e}") from e
    try:
        objects = parse_moveit_objects(data)
        allowed = parse_allowed_collisions(data)
    except (ValueError, KeyError, TypeError) as e:
        raise PlanningError(ErrorCode.INVALID_SCENE, f"{filename}: {e}") from e
    _replace(scene, objects, [], str(filename))
    scene.place_position = None
    for link_a, link_b in allowed:
        if scene.model.plant.HasBodyNamed(link_a) and scene.model.plant.HasBodyNamed(link_b):
            scene.allow_collision(link_a, link_b)
        else:
            _log.warning("%s: allowed collision %s <-> %s not applied", filename, link_a, link_b)


def parse_moveit_objects(data) -> list[SceneObject]:
    """Returns the world objects of a parsed ``moveit_msgs/PlanningScene`` mapping."""
    if not isinstance(data, dict):
        raise ValueError("a PlanningScene must be a mapping")
    world = data.get("world") or {}
    result = []
    for entry in world.get("collision_objects") or []:
        name = entry.get("id")
        if not isinstance(name, str) or not name:
            raise ValueError(f"collision object without an id: {entry}")
        if entry.get("meshes") or entry.get("planes"):
            raise ValueError(f"object {name!r}: meshes and planes are not supported")
        primitives = entry.get("primitives") or []
        poses = entry.get("primitive_poses") or []
        if len(primitives) != len(poses):
            raise ValueError(f"object {name!r}: {len(primitives)} primitives, {len(poses)} poses")
        X_WP = _moveit_pose(entry["pose"], name) if "pose" in entry else None
        for k, (primitive, pose) in enumerate(zip(primitives, poses, strict=True)):
            X_PO = _moveit_pose(pose, name)
            X_WO = X_PO if X_WP is None else X_WP @ X_PO
            shape, size = _moveit_shape(primitive, name)
            result.append(SceneObject(name if k == 0 else f"{name}#{k}", shape, size, X_WO))
    return result


def parse_allowed_collisions(data) -> list[tuple[str, str]]:
    """Returns the name pairs an ``allowed_collision_matrix`` allows to collide."""
    acm = data.get("allowed_collision_matrix") or {}
    names = acm.get("entry_names") or []
    values = acm.get("entry_values") or []
    if len(values) != len(names):
        raise ValueError(f"allowed_collision_matrix: {len(names)} names, {len(values)} rows")
    pairs = []
    for i, row in enumerate(values):
        row = row.get("enabled", []) if isinstance(row, dict) else row
        if len(row) != len(names):
            raise ValueError(f"allowed_collision_matrix row {i} has {len(row)} values")
        pairs += [(names[i], names[j]) for j in range(i + 1, len(names)) if row[j]]
    return pairs


def _moveit_pose(pose, name):
    if not isinstance(pose, dict) or "position" not in pose:
        raise ValueError(f"object {name!r}: pose needs a position, got {pose!r}")
    position = pose["position"]
    if isinstance(position, dict):
        position = [position.get(k) for k in "xyz"]
    orientation = pose.get("orientation", [0, 0, 0, 1])
    if isinstance(orientation, dict):
        orientation = [orientation.get(k) for k in "xyzw"]
    return make_pose(position, orientation, name=f"object {name!r}")


def _moveit_shape(primitive, name) -> tuple[str, tuple[float, ...]]:
    kind = primitive.get("type")
    kind = _MOVEIT_TYPES.get(kind, kind) if isinstance(kind, int) else str(kind).lower()
    dims = list(primitive.get("dimensions") or [])
    if kind == "box":
        return "box", tuple(dims)
    if kind == "sphere":
        return "sphere", tuple(dims)
    if kind == "cylinder":
        if len(dims) != 2:
            raise ValueError(f"object {name!r}: a cylinder needs [height, radius], got {dims}")
        return "cylinder", (dims[1], dims[0])
    raise ValueError(f"object {name!r}: unsupported primitive type {kind!r}")


def _box_object(name: str, box: BoxSpec) -> SceneObject:
    from pydrake.math import RigidTransform, RollPitchYaw

    X = make_pose(box.position, name=name)
    return SceneObject(
        name, "box", tuple(box.size), RigidTransform(RollPitchYaw(0, 0, box.yaw), X.translation())
    )


def _spec_object(spec: ObjectSpec) -> SceneObject:
    X = make_pose(spec.position, spec.orientation, name=f"object {spec.name!r}")
    return SceneObject(spec.name, spec.shape, tuple(spec.size), X)


def _object_entry(obj: SceneObject) -> dict:
    q = obj.X_PO.rotation().ToQuaternion()
    return {
        "name": obj.name,
        "shape": obj.shape,
        "size": list(obj.size),
        "position": obj.X_PO.translation().tolist(),
        "orientation": [q.x(), q.y(), q.z(), q.w()],
    }


def _yaw_only(obj: SceneObject) -> float | None:
    R = obj.X_PO.rotation().matrix()
    if abs(R[2, 2] - 1.0) > 1e-9:
        return None
    return float(math.atan2(R[1, 0], R[0, 0]))


def _replace(scene, objects: list[SceneObject], attached: list[SceneObject], where: str) -> None:
    """Checks names, then replaces the scene's world objects (and held ones when given)."""
    names = [o.name for o in objects + attached]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise PlanningError(
            ErrorCode.INVALID_SCENE, f"{where}: duplicate object names {duplicates}"
        )
    scene.clear()
    if attached:
        for name in list(scene.attached_objects):
            scene.remove_object(name)
    for obj in objects:
        scene.add_object(obj)
    for obj in attached:
        scene.attach_new(obj)
