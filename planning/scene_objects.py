"""Collision objects of a planning scene: a checked shape, its size and its pose.

Boxes, cylinders and spheres are checked exactly. A "convex" object is the convex hull of its
``vertices``: MoveIt's meshes (its FCL checker checks a mesh's triangles as given; Drake's
proximity engine checks any ``Mesh`` or ``Convex`` as its convex hull, so a concave mesh is
checked here as the solid that wraps it), cones and prisms. An object may carry a display
colour and named frames (MoveIt's subframes); neither changes what is checked.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from pydrake.common import MemoryFile
from pydrake.common.eigen_geometry import Quaternion
from pydrake.geometry import Box, Convex, Cylinder, InMemoryMesh, Shape, Sphere
from pydrake.math import RigidTransform

SHAPE_SIZES = {"box": 3, "cylinder": 2, "sphere": 1}
"""Number of size values per shape: box (sx, sy, sz) full extents, cylinder (radius, length)
along its z axis, sphere (radius,); all in m, as Drake's ``Box``, ``Cylinder``, ``Sphere``."""
CONVEX = "convex"
"""The shape of an object checked as the convex hull of its ``vertices`` (it has no size)."""


@dataclass(frozen=True)
class SceneObject:
    """A collision object.

    Attributes:
        name: unique within its scene.
        shape: "box", "cylinder", "sphere" or "convex".
        size: see ``SHAPE_SIZES`` (m); empty for a convex object.
        X_PO: pose of the object's centre frame O in its parent frame P: the world W for a world
            object, the attachment body A (the hand frame) for an attached one.
        vertices: a convex object's points in O (m), ``((x, y, z), ...)``, at least 4 and not
            all on one line; the object is their convex hull. Empty for the other shapes.
        color: (r, g, b, a) in [0, 1] for display, or None for the display's default.
        subframes: named frames on the object, ``((name, X_OS), ...)`` (MoveIt's subframes).
    """

    name: str
    shape: str
    size: tuple[float, ...]
    X_PO: RigidTransform
    vertices: tuple[tuple[float, float, float], ...] = ()
    color: tuple[float, float, float, float] | None = None
    subframes: tuple[tuple[str, RigidTransform], ...] = ()

    def __post_init__(self):
        validate_object(self.name, self.shape, self.size, self.X_PO, self.vertices)
        object.__setattr__(self, "size", tuple(float(s) for s in self.size))
        if self.vertices:
            points = tuple(tuple(float(v) for v in p) for p in self.vertices)
            object.__setattr__(self, "vertices", points)
        if self.color is not None:
            object.__setattr__(self, "color", _color(self.name, self.color))
        if self.subframes:
            object.__setattr__(self, "subframes", _subframes(self.name, self.subframes))

    def drake_shape(self) -> Shape:
        """Returns the Drake shape (in frame O)."""
        if self.shape == "box":
            return Box(*self.size)
        if self.shape == "cylinder":
            return Cylinder(*self.size)
        if self.shape == CONVEX:
            return convex_shape(self.vertices, self.name)
        return Sphere(self.size[0])

    def with_pose(self, X_PO: RigidTransform) -> SceneObject:
        """Returns a copy at another pose (in another parent frame)."""
        return dataclasses.replace(self, X_PO=X_PO)

    def frame(self, name: str) -> RigidTransform:
        """Returns X_PS, the pose of the named frame S (a subframe) in the parent frame P.

        Raises:
            KeyError: the object has no such frame (naming those it has).
        """
        for subframe, X_OS in self.subframes:
            if subframe == name:
                return self.X_PO @ X_OS
        known = ", ".join(s for s, _ in self.subframes) or "none"
        raise KeyError(f"object {self.name!r} has no frame {name!r} (its frames: {known})")


def convex_shape(vertices, name: str = "convex") -> Convex:
    """A Drake ``Convex``: the convex hull of ``vertices`` ((n, 3), m), given to Drake as an
    in-memory OBJ of points (Drake computes the hull)."""
    text = "".join(f"v {float(x)!r} {float(y)!r} {float(z)!r}\n" for x, y, z in vertices)
    return Convex(InMemoryMesh(mesh_file=MemoryFile(text, ".obj", f"{name}.obj")))


def validate_object(name, shape, size, X_PO, vertices=()) -> None:
    """Checks an object's fields.

    Raises:
        ValueError: with a message naming the object and the field at fault.
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"object name must be a non-empty string, got {name!r}")
    if shape == CONVEX:
        _check_vertices(name, size, vertices)
        _check_pose(name, X_PO)
        return
    if vertices:
        raise ValueError(f"object {name!r}: only a convex object has vertices (a {shape})")
    if shape not in SHAPE_SIZES:
        known = [*SHAPE_SIZES, CONVEX]
        raise ValueError(f"object {name!r}: unknown shape {shape!r}; one of {known}")
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
    _check_pose(name, X_PO)


def _check_pose(name: str, X_PO) -> None:
    if not isinstance(X_PO, RigidTransform):
        raise ValueError(f"object {name!r}: pose must be a RigidTransform, got {type(X_PO)}")
    if not np.all(np.isfinite(X_PO.GetAsMatrix4())):
        raise ValueError(f"object {name!r}: pose is not finite (NaN or infinity)")


def _check_vertices(name: str, size, vertices) -> None:
    if len(tuple(size)):
        raise ValueError(f"object {name!r}: a convex object has no size, got {size!r}")
    try:
        points = np.asarray(vertices, dtype=float)
    except (TypeError, ValueError) as e:
        raise ValueError(f"object {name!r}: vertices must be (x, y, z) numbers") from e
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 4:
        raise ValueError(
            f"object {name!r}: a convex object needs at least 4 vertices (x, y, z), "
            f"got shape {points.shape}"
        )
    if not np.all(np.isfinite(points)):
        raise ValueError(f"object {name!r}: vertices are not finite (NaN or infinity)")
    spread = points - points.mean(axis=0)
    singular = np.linalg.svd(spread, compute_uv=False)
    if singular[1] <= 1e-9 * max(singular[0], 1e-300):
        raise ValueError(f"object {name!r}: the vertices lie on one line (no area, no volume)")


def _color(name: str, color) -> tuple[float, float, float, float]:
    try:
        values = tuple(float(c) for c in color)
    except (TypeError, ValueError) as e:
        raise ValueError(f"object {name!r}: color must be 4 numbers (r, g, b, a)") from e
    if len(values) != 4 or not all(0.0 <= c <= 1.0 for c in values):
        raise ValueError(f"object {name!r}: color must be (r, g, b, a) in [0, 1], got {color!r}")
    return values


def _subframes(name: str, subframes) -> tuple[tuple[str, RigidTransform], ...]:
    result, seen = [], set()
    for entry in subframes:
        frame, X_OS = entry
        if not isinstance(frame, str) or not frame or frame in seen:
            raise ValueError(f"object {name!r}: subframe names must be unique, got {frame!r}")
        _check_pose(f"{name}/{frame}", X_OS)
        seen.add(frame)
        result.append((frame, X_OS))
    return tuple(result)


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


def subframe_pose(scene, frame: str, q=None) -> RigidTransform:
    """Returns X_WS of a named frame ``"object/subframe"`` (MoveIt's naming) of a world object,
    or of a held one with the robot at q; ``"object"`` alone is the object's own frame.

    Raises:
        KeyError: no such object or frame (naming what there is).
    """
    name, _, sub = frame.partition("/")
    found = scene.world_objects.get(name) or scene.attached_objects.get(name)
    if found is None:
        raise KeyError(f"no object named {name!r} for frame {frame!r}")
    X_WO = scene.object_pose(name, q)
    return X_WO if not sub else X_WO @ found.X_PO.inverse() @ found.frame(sub)


def describe_scene(scene) -> dict:
    """Returns a JSON-ready description of a scene's world and attached objects (a convex
    object's entry holds its ``vertices`` too)."""

    def entry(obj) -> dict:
        quat = obj.X_PO.rotation().ToQuaternion()
        described = {
            "name": obj.name,
            "shape": obj.shape,
            "size": [float(s) for s in obj.size],
            "position": obj.X_PO.translation().tolist(),
            "orientation": [quat.x(), quat.y(), quat.z(), quat.w()],
        }
        if obj.vertices:
            described["vertices"] = [list(p) for p in obj.vertices]
        return described

    return {
        "world": [entry(o) for o in scene.world_objects.values()],
        "attached": [entry(o) for o in scene.attached_objects.values()],
    }
