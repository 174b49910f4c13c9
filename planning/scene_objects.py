"""Collision objects of a planning scene: a checked shape, its size and its pose."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.geometry import Box, Cylinder, Shape, Sphere
from pydrake.math import RigidTransform

SHAPE_SIZES = {"box": 3, "cylinder": 2, "sphere": 1}
"""Number of size values per shape: box (sx, sy, sz) full extents, cylinder (radius, length)
along its z axis, sphere (radius,); all in m, as Drake's ``Box``, ``Cylinder``, ``Sphere``."""


@dataclass(frozen=True)
class SceneObject:
    """A primitive collision object.

    Attributes:
        name: unique within its scene.
        shape: "box", "cylinder" or "sphere".
        size: see ``SHAPE_SIZES`` (m).
        X_PO: pose of the object's centre frame O in its parent frame P: the world W for a world
            object, the attachment body A (the hand frame) for an attached one.
    """

    name: str
    shape: str
    size: tuple[float, ...]
    X_PO: RigidTransform

    def __post_init__(self):
        validate_object(self.name, self.shape, self.size, self.X_PO)
        object.__setattr__(self, "size", tuple(float(s) for s in self.size))

    def drake_shape(self) -> Shape:
        """Returns the Drake shape (in frame O)."""
        if self.shape == "box":
            return Box(*self.size)
        if self.shape == "cylinder":
            return Cylinder(*self.size)
        return Sphere(self.size[0])

    def with_pose(self, X_PO: RigidTransform) -> SceneObject:
        """Returns a copy at another pose (in another parent frame)."""
        return SceneObject(self.name, self.shape, self.size, X_PO)


def validate_object(name, shape, size, X_PO) -> None:
    """Checks an object's fields.

    Raises:
        ValueError: with a message naming the object and the field at fault.
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"object name must be a non-empty string, got {name!r}")
    if shape not in SHAPE_SIZES:
        raise ValueError(f"object {name!r}: unknown shape {shape!r}; one of {list(SHAPE_SIZES)}")
    try:
        values = [float(s) for s in size]
    except (TypeError, ValueError) as e:
        raise ValueError(f"object {name!r}: size must be numbers, got {size!r}") from e
    if len(values) != SHAPE_SIZES[shape]:
        raise ValueError(
            f"object {name!r}: a {shape} needs {SHAPE_SIZES[shape]} size values "
            f"({_size_help(shape)}), got {len(values)}"
        )
    if not all(math.isfinite(v) and v > 0.0 for v in values):
        raise ValueError(f"object {name!r}: sizes must be finite and positive, got {values}")
    if not isinstance(X_PO, RigidTransform):
        raise ValueError(f"object {name!r}: pose must be a RigidTransform, got {type(X_PO)}")
    if not np.all(np.isfinite(X_PO.GetAsMatrix4())):
        raise ValueError(f"object {name!r}: pose is not finite (NaN or infinity)")


def _size_help(shape: str) -> str:
    return {"box": "sx, sy, sz", "cylinder": "radius, length", "sphere": "radius"}[shape]


def make_pose(position, quaternion_xyzw=None, *, name: str = "pose") -> RigidTransform:
    """Returns a RigidTransform from a position and an optional [x, y, z, w] quaternion.

    The quaternion is normalised; a zero, non-finite or wrongly sized one is an error.

    Raises:
        ValueError: bad sizes or non-finite values, naming ``name``.
    """
    from pydrake.common.eigen_geometry import Quaternion

    p = _finite_vector(position, 3, f"{name} position")
    if quaternion_xyzw is None:
        return RigidTransform(p)
    x, y, z, w = _finite_vector(quaternion_xyzw, 4, f"{name} orientation [x, y, z, w]")
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if norm < 1e-9:
        raise ValueError(f"{name} orientation is a zero quaternion")
    return RigidTransform(Quaternion(w / norm, x / norm, y / norm, z / norm), p)


def _finite_vector(values, size: int, what: str) -> np.ndarray:
    try:
        array = np.asarray(values, dtype=float).reshape(-1)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{what} must be {size} numbers, got {values!r}") from e
    if array.size != size:
        raise ValueError(f"{what} must have {size} values, got {array.size}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{what} is not finite: {array.tolist()}")
    return array


FREE_BODY_POSITIONS = 7
"""Positions of a free body in a plant: its quaternion [qw, qx, qy, qz], then [x, y, z]."""


def free_body_pose(q: np.ndarray) -> RigidTransform:
    """X_WB from a free body's 7 positions [qw, qx, qy, qz, x, y, z] (quaternion normalised)."""
    quaternion = np.asarray(q[:4], dtype=float)
    p_WB = q[4:FREE_BODY_POSITIONS]
    return RigidTransform(Quaternion(quaternion / np.linalg.norm(quaternion)), p_WB)


def free_body_positions(X_WB: RigidTransform) -> np.ndarray:
    """The 7 positions [qw, qx, qy, qz, x, y, z] of a free body at X_WB."""
    return np.concatenate([X_WB.rotation().ToQuaternion().wxyz(), X_WB.translation()])


def describe_scene(scene) -> dict:
    """Returns a JSON-ready description of a scene's world and attached objects."""

    def entry(obj) -> dict:
        quat = obj.X_PO.rotation().ToQuaternion()
        return {
            "name": obj.name,
            "shape": obj.shape,
            "size": [float(s) for s in obj.size],
            "position": obj.X_PO.translation().tolist(),
            "orientation": [quat.x(), quat.y(), quat.z(), quat.w()],
        }

    return {
        "world": [entry(o) for o in scene.world_objects.values()],
        "attached": [entry(o) for o in scene.attached_objects.values()],
    }
