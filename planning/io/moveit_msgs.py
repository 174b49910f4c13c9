"""MoveIt's message types as YAML schemas, and readers of their poses and primitives.

The dataclasses mirror ``moveit_msgs/PlanningScene`` and what it holds (``CollisionObject``,
``AttachedCollisionObject``, ``RobotState``, ``AllowedCollisionMatrix``, ``shape_msgs/
SolidPrimitive``, ...), so that ``drake_sim.base.config.check_tree`` rejects an unknown key or a
value of the wrong type with its key path (``world.collision_objects[2].primitives[0]``).
Fields that MoveIt writes in more than one form are ``Any`` and read here: a position as
``[x, y, z]`` or ``{x: .., y: .., z: ..}``, an orientation as ``[x, y, z, w]`` or a mapping.

Numbers follow the project's YAML rule: a boolean is not a number, text that reads as a number
is one (PyYAML reads ``1e-3`` as text), and every number must be finite. A byte field as
``ros2 topic echo`` prints it (``b'\\x00'``) reads as its value.
"""

import dataclasses as dc
import math
import re
from typing import Any

from pydrake.math import RigidTransform

from planning.scene_objects import make_pose

# shape_msgs/SolidPrimitive types and the dimensions of those we read.
PRIMITIVE_TYPES = {1: "box", 2: "sphere", 3: "cylinder", 4: "cone", 5: "prism"}
PRIMITIVE_DIMENSIONS = {
    "box": "[x, y, z]",
    "sphere": "[radius]",
    "cylinder": "[height, radius]",
    "cone": "[height, radius]",
    "prism": "[height]",
}
# moveit_msgs/CollisionObject operations.
OPERATIONS = {0: "ADD", 1: "REMOVE", 2: "APPEND", 3: "MOVE"}
_BYTE = re.compile(r"b'(?:\\x([0-9a-fA-F]{2})|(.))'")  # b'\x00' or b'a', as ROS 2 prints bytes


def _list():
    return dc.field(default_factory=list)


@dc.dataclass
class Stamp:
    secs: int = 0  # ROS 1
    nsecs: int = 0
    sec: int = 0  # ROS 2
    nanosec: int = 0


@dc.dataclass
class Header:
    seq: int = 0
    stamp: Stamp | None = None
    frame_id: str = ""


@dc.dataclass
class Pose:
    position: Any = None
    orientation: Any = None


@dc.dataclass
class Transform:
    translation: Any = None
    rotation: Any = None


@dc.dataclass
class Point32:
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@dc.dataclass
class Polygon:
    points: list[Point32] = _list()


@dc.dataclass
class SolidPrimitive:
    type: int | str = 0
    dimensions: list[float] = _list()
    polygon: Polygon | None = None  # ROS 2: a prism's cross-section


@dc.dataclass
class MeshTriangle:
    vertex_indices: list[int] = _list()


@dc.dataclass
class Mesh:
    """shape_msgs/Mesh, plus what robowflex writes instead of triangles: a mesh file
    (``resource``: a path or ``package://`` URI) and its scale per axis (``dimensions``)."""

    triangles: list[MeshTriangle] = _list()
    vertices: list[Any] = _list()  # geometry_msgs/Point: [x, y, z] or {x:, y:, z:}
    resource: str = ""
    dimensions: list[float] = _list()


@dc.dataclass
class Plane:
    coef: list[float] = _list()  # a, b, c, d of ax + by + cz + d = 0


@dc.dataclass
class ObjectType:
    key: str = ""
    db: str = ""


@dc.dataclass
class CollisionObject:
    header: Header | None = None
    pose: Pose | None = None
    id: str = ""
    type: ObjectType | None = None
    primitives: list[SolidPrimitive] = _list()
    primitive_poses: list[Pose] = _list()
    meshes: list[Mesh] = _list()
    mesh_poses: list[Pose] = _list()
    planes: list[Plane] = _list()
    plane_poses: list[Pose] = _list()
    subframe_names: list[str] = _list()
    subframe_poses: list[Pose] = _list()
    operation: int | str = 0


@dc.dataclass
class AttachedCollisionObject:
    link_name: str = ""
    object: CollisionObject | None = None
    touch_links: list[str] = _list()
    detach_posture: Any = None
    weight: float = 0.0


@dc.dataclass
class JointState:
    header: Header | None = None
    name: list[str] = _list()
    position: list[float] = _list()
    velocity: list[float] = _list()
    effort: list[float] = _list()


@dc.dataclass
class MultiDofJointState:
    joint_names: list[str] = _list()
    transforms: list[Transform] = _list()  # of the joints (the virtual joint of the base)
    twist: list[Any] = _list()
    wrench: list[Any] = _list()
    header: Header | None = None


@dc.dataclass
class RobotState:
    joint_state: JointState | None = None
    multi_dof_joint_state: MultiDofJointState | None = None
    attached_collision_objects: list[AttachedCollisionObject] = _list()
    is_diff: bool = False


@dc.dataclass
class TransformStamped:
    header: Header | None = None
    child_frame_id: str = ""
    transform: Transform | None = None


@dc.dataclass
class AllowedCollisionMatrix:
    entry_names: list[str] = _list()
    entry_values: list[Any] = _list()  # rows: [bool, ...] or {enabled: [bool, ...]}
    default_entry_names: list[str] = _list()
    default_entry_values: list[bool] = _list()


@dc.dataclass
class LinkPadding:
    link_name: str = ""
    padding: float = 0.0


@dc.dataclass
class LinkScale:
    link_name: str = ""
    scale: float = 1.0


@dc.dataclass
class ObjectColor:
    id: str = ""
    color: Any = None


@dc.dataclass
class Octomap:
    """octomap_msgs/Octomap (read only to refuse a non-empty one)."""

    header: Header | None = None
    binary: bool = False
    id: str = ""
    resolution: float = 0.0
    data: list = _list()


@dc.dataclass
class OctomapWithPose:
    header: Header | None = None
    origin: Pose | None = None
    octomap: Octomap | None = None


@dc.dataclass
class PlanningSceneWorld:
    collision_objects: list[CollisionObject] = _list()
    octomap: OctomapWithPose | None = None


@dc.dataclass
class PlanningScene:
    """The schema of a ``moveit_msgs/PlanningScene`` YAML file."""

    name: str = ""
    robot_state: RobotState | None = None
    robot_model_name: str = ""
    fixed_frame_transforms: list[TransformStamped] = _list()
    allowed_collision_matrix: AllowedCollisionMatrix | None = None
    link_padding: list[LinkPadding] = _list()
    link_scale: list[LinkScale] = _list()
    object_colors: list[ObjectColor] = _list()
    world: PlanningSceneWorld | None = None
    is_diff: bool = False


def number(value, path: str) -> float:
    """Returns ``value`` as a finite float.

    Raises:
        ValueError: naming ``path``, for a boolean, text that is no number, or NaN/infinity.
    """
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise ValueError(f"{path} must be a number, got {value!r}") from None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{path} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{path} must be finite, got {value!r}")
    return float(value)


def vector(value, keys: str, path: str) -> list[float]:
    """Reads ``[a, b, ..]`` or ``{a: .., b: ..}`` (missing keys are 0, as in a ROS message)
    for the components named by ``keys``, e.g. "xyz".

    Raises:
        ValueError: naming ``path`` and the component at fault.
    """
    if isinstance(value, dict):
        unknown = sorted(str(k) for k in value if k not in keys)
        if unknown:
            raise ValueError(f"{path}: unknown key {unknown[0]!r} (known here: {', '.join(keys)})")
        return [number(value.get(k, 0.0), f"{path}.{k}") for k in keys]
    if not isinstance(value, list):
        raise ValueError(f"{path} must be a list [{', '.join(keys)}] or a mapping, got {value!r}")
    if len(value) != len(keys):
        raise ValueError(f"{path} must have {len(keys)} values [{', '.join(keys)}], got {value!r}")
    return [number(v, f"{path}[{i}]") for i, v in enumerate(value)]


def pose(value, path: str, *, position: str = "position", orientation: str = "orientation"):
    """Returns the ``RigidTransform`` of a Pose mapping (identity for None); the orientation is
    optional (identity), the position is not. Also reads a Transform with
    ``position="translation", orientation="rotation"``.

    Raises:
        ValueError: naming ``path``: a missing position, a bad or zero quaternion.
    """
    if value is None:
        return RigidTransform()
    if value.get(position) is None:
        raise ValueError(f"{path}: a pose needs a {position}")
    p = vector(value[position], "xyz", f"{path}.{position}")
    if value.get(orientation) is None:
        return RigidTransform(p)
    q = vector(value[orientation], "xyzw", f"{path}.{orientation}")
    return make_pose(p, q, name=path)


def primitive(value, path: str) -> tuple[str, tuple[float, ...]]:
    """Returns the shape and the size of a SolidPrimitive: box, sphere and cylinder as
    ``scene_objects.SHAPE_SIZES`` (a cylinder's (radius, length)), a cone's (radius, length)
    and a prism's (height,).

    Raises:
        ValueError: naming ``path``: an unknown type, a wrong number of dimensions, or a
            dimension that is not a positive number.
    """
    kind = byte(value.get("type", 0))
    kind = PRIMITIVE_TYPES.get(kind, kind) if _integer(kind) else str(kind).lower()
    if kind not in PRIMITIVE_DIMENSIONS:
        known = ", ".join(f"{k} {n}" for k, n in PRIMITIVE_TYPES.items())
        raise ValueError(f"{path}.type: unknown primitive type {kind!r} (known: {known})")
    dims = [number(d, f"{path}.dimensions[{i}]") for i, d in enumerate(value.get("dimensions", []))]
    expected = PRIMITIVE_DIMENSIONS[kind]
    if len(dims) != expected.count(",") + 1:
        raise ValueError(f"{path}.dimensions: a {kind} needs {expected}, got {dims}")
    for i, d in enumerate(dims):
        if d <= 0.0:
            raise ValueError(f"{path}.dimensions[{i}] must be positive, got {d}")
    if kind in ("cylinder", "cone"):
        return kind, (dims[1], dims[0])  # (radius, length)
    return kind, tuple(dims)


def color(value, path: str) -> tuple[float, float, float, float]:
    """Returns (r, g, b, a) of a std_msgs/ColorRGBA (a mapping or a list), clipped to [0, 1].

    Raises:
        ValueError: naming ``path``, for a value that is no colour.
    """
    if value is None:
        raise ValueError(f"{path}: an object colour needs a color {{r, g, b, a}}")
    return tuple(min(max(c, 0.0), 1.0) for c in vector(value, "rgba", path))


def byte(value):
    """Returns the value of a byte field printed by ``ros2 topic echo`` (``b'\\x00'``), or
    ``value`` unchanged."""
    if isinstance(value, str) and (found := _BYTE.fullmatch(value.strip())):
        return int(found[1], 16) if found[1] else ord(found[2])
    return value


def operation(value, path: str) -> str:
    """Returns "ADD", "REMOVE", "APPEND" or "MOVE" for a CollisionObject's operation (0 to 3 or
    the name).

    Raises:
        ValueError: naming ``path``, for anything else.
    """
    value = byte(value)
    name = OPERATIONS.get(value) if _integer(value) else str(value).upper()
    if name not in OPERATIONS.values():
        raise ValueError(f"{path}: unknown operation {value!r} (0 ADD, 1 REMOVE, 2 APPEND, 3 MOVE)")
    return name


def _integer(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)
