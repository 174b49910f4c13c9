"""The shapes of MoveIt's collision objects as the pieces this planner checks.

A ``Piece`` is one shape of an object at its pose ``X_OS`` in the object's frame O:

- boxes, spheres and cylinders are kept as they are (checked exactly);
- a mesh (``shape_msgs/Mesh``: its triangles' vertices, or a mesh file that robowflex names by
  ``resource`` with a scale per axis in ``dimensions``; a path relative to the scene file or a
  ``package://`` URI resolved through a package map by ``drake_sim.robots.files.robot_files``,
  read by trimesh through ``drake_sim.robots.files.mesh_convert``, so STL, COLLADA, OBJ, glTF,
  PLY and OFF) becomes the convex hull of its vertices. MoveIt's FCL checker checks a mesh's
  triangles as they are; Drake's proximity engine checks a ``Mesh`` or ``Convex`` as its convex
  hull, so a concave mesh (a tote, a shelf as one mesh) is checked here as the solid that wraps
  it: more configurations collide than in MoveIt, never fewer;
- a cone (MoveIt's: axis z, base of the radius at z = -length/2, apex at +length/2) becomes the
  hull of its apex and a regular ``CONE_SIDES``-gon circumscribing its base: it contains the
  cone and is at most 0.9 % of the radius wider;
- a prism (ROS 2's ``SolidPrimitive.PRISM``: a polygon in the xy plane, extruded over the
  height about z = 0) becomes the hull of its polygon's corners at both ends;
- a plane ``ax + by + cz + d = 0`` becomes a box on the side its normal (a, b, c) points away
  from: MoveIt's FCL checker collides a link that touches or crosses the plane (and its Bullet
  checker one that is behind it, a half-space), so the box is a half-space cut to
  ``PLANE_BOX_SIZE``, its face on the plane, centred on the point of the plane nearest the world
  origin. A link wholly behind a plane collides here, as with Bullet.

``UnrepresentableError`` is what the caller turns into a warning (the shape skipped): a mesh file
that cannot be found or read, a mesh with no volume or area.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix

from drake_sim.base.errors import ConfigError
from planning.io import moveit_msgs as msgs
from planning.scene_objects import CONVEX

CONE_SIDES = 24
"""Sides of the polygon a cone's base becomes (circumscribed: the hull contains the cone)."""
PLANE_BOX_SIZE = (20.0, 20.0, 10.0)
"""The box a plane becomes (m): 20 m by 20 m along the plane, 10 m deep behind it."""


class UnrepresentableError(Exception):
    """A shape MoveIt would load that cannot be represented here (the message says why)."""


@dataclass(frozen=True)
class Piece:
    """One shape of an object: "box", "cylinder", "sphere" with ``size`` as
    ``scene_objects.SHAPE_SIZES``, or "convex" with ``vertices`` in the shape's frame S; its
    pose ``X_OS`` in the object's frame O."""

    shape: str
    size: tuple[float, ...]
    X_OS: RigidTransform
    vertices: tuple[tuple[float, float, float], ...] = ()

    def at(self, X_OS: RigidTransform) -> Piece:
        return Piece(self.shape, self.size, X_OS, self.vertices)


def solid(kind: str, size: tuple[float, ...], X_OS: RigidTransform, polygon=None) -> Piece:
    """A SolidPrimitive (``moveit_msgs.primitive``'s kind and size) as a piece.

    Args:
        polygon: a prism's cross-section, [(x, y), ...] (at least 3 points).

    Raises:
        UnrepresentableError: a prism whose polygon has no area.
    """
    if kind == "cone":
        return Piece(CONVEX, (), X_OS, hull_vertices(cone_points(*size)))
    if kind == "prism":
        return Piece(CONVEX, (), X_OS, hull_vertices(prism_points(polygon or [], size[0])))
    return Piece(kind, tuple(size), X_OS)


def cone_points(radius: float, length: float, sides: int = CONE_SIDES) -> np.ndarray:
    """The apex and the corners of a regular polygon circumscribing the base, (sides + 1, 3)."""
    wide = radius / math.cos(math.pi / sides)
    angles = 2 * math.pi * np.arange(sides) / sides
    base = np.column_stack([wide * np.cos(angles), wide * np.sin(angles), np.full(sides, -0.5)])
    base[:, 2] *= length
    return np.vstack([base, [0.0, 0.0, length / 2]])


def prism_points(polygon, height: float) -> np.ndarray:
    """The polygon's corners at z = -height/2 and +height/2."""
    xy = np.asarray(polygon, dtype=float).reshape(-1, 2)
    if len(xy) < 3:
        raise UnrepresentableError(f"a prism needs a polygon of 3 points or more, got {len(xy)}")
    half = np.full((len(xy), 1), height / 2)
    return np.vstack([np.hstack([xy, -half]), np.hstack([xy, half])])


def hull_vertices(points) -> tuple[tuple[float, float, float], ...]:
    """The vertices of the convex hull of ``points`` ((n, 3), m), by Drake's qhull (a flat set
    gives its polygon's corners).

    Raises:
        UnrepresentableError: fewer than 4 points, or all on one line (no area).
    """
    from pydrake.geometry.optimization import VPolytope

    points = np.unique(np.asarray(points, dtype=float).reshape(-1, 3), axis=0)
    if len(points) < 3:
        raise UnrepresentableError(f"{len(points)} distinct vertices: no area, no volume")
    spread = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)
    if spread[1] <= 1e-9 * spread[0]:
        raise UnrepresentableError("its vertices lie on one line: no area, no volume")
    hull = VPolytope(points.T).GetMinimalRepresentation().vertices().T  # flat sets too
    return tuple(map(tuple, hull))


def mesh(value: dict, X_OS: RigidTransform, path: str, base: Path, package_paths) -> Piece:
    """A ``shape_msgs/Mesh`` (inline triangles and vertices, or a ``resource`` file scaled by
    ``dimensions``) as the convex hull of its vertices.

    Raises:
        ValueError: a malformed message (a vertex index out of range, a bad number or scale).
        UnrepresentableError: an empty mesh, a file that cannot be found or read, no volume or area.
    """
    scale = _scale(value.get("dimensions", []), f"{path}.dimensions")
    if value.get("resource"):
        points = mesh_file_points(value["resource"], base, package_paths)
    else:
        points = _inline_points(value, path)
    return Piece(CONVEX, (), X_OS, hull_vertices(points * scale))


def _scale(dimensions: list, path: str) -> np.ndarray:
    if not dimensions:
        return np.ones(3)
    values = [msgs.number(d, f"{path}[{i}]") for i, d in enumerate(dimensions)]
    if len(values) != 3 or min(values) <= 0.0:
        raise ValueError(f"{path}: a mesh's scale is 3 positive numbers, got {values}")
    return np.array(values)


def _inline_points(value: dict, path: str) -> np.ndarray:
    vertices = [
        msgs.vector(v, "xyz", f"{path}.vertices[{i}]")
        for i, v in enumerate(value.get("vertices", []))
    ]
    triangles = value.get("triangles", [])
    if not vertices or not triangles:
        raise UnrepresentableError("an empty mesh (no triangles or no vertices)")
    used = set()
    for k, triangle in enumerate(triangles):
        indices = triangle.get("vertex_indices", [])
        where = f"{path}.triangles[{k}].vertex_indices"
        if len(indices) != 3 or any(not 0 <= i < len(vertices) for i in indices):
            raise ValueError(
                f"{where}: a triangle is 3 indices of the {len(vertices)} vertices, got {indices}"
            )
        used.update(indices)
    return np.asarray(vertices)[sorted(used)]


def mesh_file_points(uri: str, base: Path, package_paths) -> np.ndarray:
    """The vertices (m) of a mesh file named by a path (relative to ``base``) or a URI.

    Raises:
        UnrepresentableError: an unknown package, a missing or unreadable file.
    """
    from drake_sim.robots.files.robot_files import resolve_uri

    try:
        file = resolve_uri(uri, base, package_paths).resolve()
    except ConfigError as e:
        raise UnrepresentableError(f"mesh {uri}: {e}") from None
    if not file.is_file():
        raise UnrepresentableError(f"mesh {uri}: no such file {file}")
    stat = file.stat()
    try:
        return _file_points(str(file), stat.st_mtime_ns, stat.st_size)
    except ConfigError as e:
        raise UnrepresentableError(str(e)) from None


@functools.lru_cache(maxsize=64)
def _file_points(file: str, mtime_ns: int, size: int) -> np.ndarray:
    """A mesh file's vertices, read once per version of the file (its time and size)."""
    from drake_sim.robots.files.mesh_convert import load_mesh_scene

    scene = load_mesh_scene(Path(file))
    points = np.asarray(scene.to_mesh().vertices, dtype=float)
    points.setflags(write=False)
    return points


def plane(coef: list, X_OP: RigidTransform, p_O_near, path: str) -> Piece:
    """A plane (``coef`` [a, b, c, d] in its frame P, at ``X_OP`` in the object's frame O) as
    the box ``PLANE_BOX_SIZE`` behind it, centred along the plane on the point nearest
    ``p_O_near`` (the world origin, in O).

    Raises:
        ValueError: not 4 numbers, or a zero normal.
    """
    values = [msgs.number(c, f"{path}.coef[{i}]") for i, c in enumerate(coef)]
    if len(values) != 4:
        raise ValueError(f"{path}.coef: a plane is [a, b, c, d] (ax + by + cz + d = 0)")
    normal = np.array(values[:3])
    length = float(np.linalg.norm(normal))
    if length < 1e-12:
        raise ValueError(f"{path}.coef: the normal (a, b, c) is zero")
    n_P, offset = normal / length, values[3] / length  # n.x + offset = 0
    n_O = X_OP.rotation() @ n_P
    p_O_plane = X_OP @ (-offset * n_P)  # a point of the plane
    near = np.asarray(p_O_near, dtype=float)
    foot = near - float(n_O @ (near - p_O_plane)) * n_O
    depth = PLANE_BOX_SIZE[2]
    R_OB = RotationMatrix.MakeFromOneVector(n_O, 2)  # the box's z axis along the normal
    return Piece("box", PLANE_BOX_SIZE, RigidTransform(R_OB, foot - n_O * depth / 2))
