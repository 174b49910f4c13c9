"""The scene side of the lidar's ray casting: ``SceneRayCaster`` reads a SceneGraph's
proximity geometry as ``Shapes`` and casts fans of beams against it (``ray_casting.cast_fan``).

Pydrake has no ray-cast query, so ``Lidar`` casts its beams here. The scene is read from the
``QueryObject``'s inspector:

* ``Box``, ``Mesh`` and ``Convex`` shapes become triangles. ``Mesh`` and ``Convex`` shapes are
  read from their OBJ file (``mesh_triangles``, scale included), so a concave mesh's concavity
  is seen, not the convex hull Drake's proximity engine uses for it; other mesh files (and
  in-memory meshes) fall back to that convex hull.
* ``Sphere``, ``Ellipsoid``, ``Cylinder``, ``Capsule`` and ``HalfSpace`` become analytic
  primitives. (``MeshcatCone``, the one other shape, is not seen.)

Geometry on the ignored frames (the robot's own bodies) is never seen. Geometry on the static
frames (the world's and bodies welded to it) is expressed in the world once and cached; the
cache is rebuilt when the scene's proximity geometry (``GeometryVersion``) or a static frame's
pose changes, so a new context or an edited scene is handled. Geometry on other frames is
re-posed at every cast.
"""

import math
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from pydrake.geometry import (
    Box,
    Capsule,
    Convex,
    Cylinder,
    Ellipsoid,
    GeometryVersion,
    HalfSpace,
    Mesh,
    QueryObject,
    ReadObjToTriangleSurfaceMesh,
    Role,
    Sphere,
)

from drake_sim.systems.sensors.ray_casting import (
    CAPSULE,
    CYLINDER,
    ELLIPSOID,
    HALF_SPACE,
    SPHERE,
    Fan,
    Primitives,
    Shapes,
    box_triangles,
    cast_fan,
    polygon_mesh_triangles,
)

_POSE_TOLERANCE = 1e-12  # m (and rad): a static frame moved by more rebuilds the cache.


def mesh_triangles(path: Path | str, scale3=(1.0, 1.0, 1.0)) -> np.ndarray:
    """Returns the triangles (T, 3, 3) of an OBJ file (m, scaled per axis by ``scale3``),
    polygons triangulated by Drake's reader."""
    mesh = ReadObjToTriangleSurfaceMesh(Path(path), np.asarray(scale3, dtype=float))
    vertices = np.array([mesh.vertex(i) for i in range(mesh.num_vertices())])
    faces = np.array([[t.vertex(k) for k in range(3)] for t in mesh.triangles()], dtype=np.int64)
    return vertices[faces].reshape(-1, 3, 3)


def _primitive(kind: int, size, radius: float) -> Primitives:
    return Primitives(
        np.array([kind]),
        np.eye(3)[None],
        np.zeros((1, 3)),
        np.array([size], float),
        np.array([radius]),
    )


class SceneRayCaster:
    """Casts fans of beams against the proximity geometry of a SceneGraph (see the module).

    Args:
        ignore_frames: SceneGraph frames whose geometry is never seen (the sensor's robot).
        static_frames: SceneGraph frames that do not move (bodies welded to the world); the
            world frame is always static.
    """

    def __init__(self, *, ignore_frames: Iterable = (), static_frames: Iterable = ()):
        self._ignore = set(ignore_frames)
        self._static = set(static_frames)
        self._cache = None  # (version, static frame ids, their poses, Shapes in W)
        self._local: dict = {}  # GeometryId -> Shapes in the geometry's frame
        self._version = None  # the GeometryVersion that _local and _classes were read from
        self._classes = ([], [])  # static frames and dynamic geometries (_classify)
        self._mesh_files: dict = {}  # (path, scale3) -> triangles

    def cast(self, query_object: QueryObject, X_WS, fan: Fan, max_distance: float) -> np.ndarray:
        """Returns the distance (m) along each beam of ``fan`` from the sensor frame S at
        ``X_WS`` (a ``RigidTransform``) to the first surface, inf where none is within
        ``max_distance``."""
        static, dynamic = self.world_shapes(query_object)
        R_WS, p_WS = X_WS.rotation().matrix(), X_WS.translation()
        ranges = cast_fan(static, R_WS, p_WS, fan, max_distance)
        if len(dynamic.triangles) or len(dynamic.primitives.kind):
            np.minimum(ranges, cast_fan(dynamic, R_WS, p_WS, fan, max_distance), out=ranges)
        return ranges

    def world_shapes(self, query_object: QueryObject) -> tuple[Shapes, Shapes]:
        """Returns the seen geometry in the world frame: the static part (cached) and the
        moving part (posed now)."""
        inspector = query_object.inspector()
        version = inspector.geometry_version()
        if self._version is None or not self._version.IsSameAs(version, Role.kProximity):
            self._local.clear()  # shapes may have changed: read them again
            self._classes = self._classify(inspector)
            self._version = GeometryVersion(version)
        static_frames, dynamic_ids = self._classes
        static = self._static_shapes(query_object, static_frames)
        parts = []
        for geometry_id in dynamic_ids:
            X_WG = query_object.GetPoseInWorld(geometry_id)
            local = self._local_shapes(inspector, geometry_id)
            parts.append(local.posed(X_WG.rotation().matrix(), X_WG.translation()))
        return static, Shapes.concatenate(parts)

    def _classify(self, inspector):
        """The static frames holding seen geometry, and the seen geometries on other frames."""
        world = inspector.world_frame_id()
        static_frames, dynamic_ids = set(), []
        for geometry_id in inspector.GetAllGeometryIds(Role.kProximity):
            frame_id = inspector.GetFrameId(geometry_id)
            if frame_id in self._ignore:
                continue
            if frame_id == world or frame_id in self._static:
                static_frames.add(frame_id)
            else:
                dynamic_ids.append(geometry_id)
        return sorted(static_frames, key=lambda f: f.get_value()), dynamic_ids

    def _static_shapes(self, query_object, static_frames) -> Shapes:
        inspector = query_object.inspector()
        version = inspector.geometry_version()
        poses = np.array(
            [query_object.GetPoseInWorld(f).GetAsMatrix34() for f in static_frames]
        ).reshape(-1, 3, 4)
        if self._cache is not None:
            old_version, old_frames, old_poses, shapes = self._cache
            if (
                old_version.IsSameAs(version, Role.kProximity)
                and old_frames == static_frames
                and np.allclose(old_poses, poses, rtol=0.0, atol=_POSE_TOLERANCE)
            ):
                return shapes
        parts = []
        for frame_id in static_frames:
            for geometry_id in inspector.GetGeometries(frame_id, Role.kProximity):
                X_WG = query_object.GetPoseInWorld(geometry_id)
                local = self._local_shapes(inspector, geometry_id)
                parts.append(local.posed(X_WG.rotation().matrix(), X_WG.translation()))
        shapes = Shapes.concatenate(parts)
        self._cache = (GeometryVersion(version), static_frames, poses, shapes)
        return shapes

    def _local_shapes(self, inspector, geometry_id) -> Shapes:
        """The geometry's shape in its own frame G (cached per geometry)."""
        cached = self._local.get(geometry_id)
        if cached is not None:
            return cached
        shape = inspector.GetShape(geometry_id)
        shapes = Shapes(np.zeros((0, 3, 3)), Primitives.empty())
        if isinstance(shape, Box):
            shapes.triangles = box_triangles([shape.width(), shape.depth(), shape.height()])
        elif isinstance(shape, Mesh | Convex):
            shapes.triangles = self._mesh(inspector, geometry_id, shape)
        elif isinstance(shape, Sphere):
            r = shape.radius()
            shapes.primitives = _primitive(SPHERE, (r, r, r), r)
        elif isinstance(shape, Ellipsoid):
            axes = (shape.a(), shape.b(), shape.c())
            shapes.primitives = _primitive(ELLIPSOID, axes, max(axes))
        elif isinstance(shape, Cylinder):
            r, length = shape.radius(), shape.length()
            shapes.primitives = _primitive(CYLINDER, (r, length, 0.0), math.hypot(r, length / 2))
        elif isinstance(shape, Capsule):
            r, length = shape.radius(), shape.length()
            shapes.primitives = _primitive(CAPSULE, (r, length, 0.0), r + length / 2)
        elif isinstance(shape, HalfSpace):
            shapes.primitives = _primitive(HALF_SPACE, (0.0, 0.0, 0.0), np.inf)
        self._local[geometry_id] = shapes
        return shapes

    def _mesh(self, inspector, geometry_id, shape) -> np.ndarray:
        source = shape.source()
        if source.is_path() and source.extension() == ".obj":
            key = (str(source.path()), tuple(shape.scale3()))
            if key not in self._mesh_files:
                self._mesh_files[key] = mesh_triangles(source.path(), shape.scale3())
            return self._mesh_files[key]
        return polygon_mesh_triangles(inspector.GetConvexHull(geometry_id))
