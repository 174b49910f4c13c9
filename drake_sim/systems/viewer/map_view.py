"""Meshcat display of mapping: the growing map, the last scan and the estimated pose (RViz's map,
LaserScan and pose displays), under ``/mapping``."""

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import Cylinder, Meshcat, Rgba
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.perception import BaseField, Fields, PointCloud
from pydrake.systems.framework import LeafSystem

from drake_sim.base.map_files import OccupancyMap
from drake_sim.systems.estimation.slam import EMPTY_MAP, NO_SCAN

OCCUPIED_COLOR = (0.05, 0.05, 0.05)
FREE_COLOR = (0.85, 0.85, 0.8)
SCAN_COLOR = Rgba(1.0, 0.1, 0.1, 1.0)
ESTIMATE_COLOR = Rgba(0.1, 0.4, 1.0, 1.0)
MAP_HEIGHT = 0.002  # m above the floor: the map lies on it, as in RViz.


def map_mesh(
    occupancy_map: OccupancyMap, height: float = MAP_HEIGHT
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The known cells of ``occupancy_map`` as a coloured triangle mesh at ``height`` (m), for
    ``Meshcat.SetTriangleColorMesh``: a square of two triangles per cell, occupied cells dark,
    free cells light; unknown cells are left out.

    Returns:
        ``vertices`` (3, 4n) m, ``faces`` (3, 2n) vertex indices, ``colors`` (3, 4n) in [0, 1].
    """
    occupied, free = occupancy_map.occupied(), occupancy_map.free()
    known = occupied | free
    xs, ys = occupancy_map.centres()
    x, y = xs[known], ys[known]
    n, half = len(x), 0.5 * occupancy_map.resolution
    corners = np.array([[-half, -half], [half, -half], [half, half], [-half, half]])
    vertices = np.empty((3, 4 * n))
    vertices[0] = (x[:, None] + corners[:, 0]).ravel()
    vertices[1] = (y[:, None] + corners[:, 1]).ravel()
    vertices[2] = height
    first = 4 * np.arange(n)[:, None]
    faces = np.hstack([first + [0, 1, 2], first + [0, 2, 3]]).reshape(-1, 3).T
    palette = np.array([FREE_COLOR, OCCUPIED_COLOR])
    colors = np.repeat(palette[occupied[known].astype(int)], 4, axis=0).T
    return vertices, np.ascontiguousarray(faces, dtype=np.int32), np.ascontiguousarray(colors)


def point_cloud(xy: np.ndarray, height: float) -> PointCloud:
    """A ``PointCloud`` of the (n, 2) world points ``xy`` at ``height`` (m), for Meshcat."""
    cloud = PointCloud(len(xy), Fields(BaseField.kXYZs))
    cloud.mutable_xyzs()[:] = np.vstack([np.asarray(xy).T, np.full(len(xy), height)])
    return cloud


class MapView(LeafSystem):
    """Draws the SLAM map every ``map_period`` s, and the last scan (as seen from the estimated
    pose) and an arrow at the estimated pose every ``scan_period`` s from ``scan_offset`` (set
    it just after the SLAM has matched each scan, so the scan is drawn at its own pose).

    .. pydrake_system::

        name: MapView
        input_ports:
        - map
        - scan
        - pose

    ``map`` is an ``OccupancyMap``; ``scan`` a ``LaserScan`` taken from the sensor at
    ``X_base_sensor`` ([x, y, yaw] on the robot); ``pose`` the estimated ``[x, y, yaw]`` of the
    robot in the map frame. With a recording running, the arrow's motion is recorded; with
    ``keyframes`` the map and the scan are recorded too, each drawing a new object shown from its
    time on (the scan then every ``map_period``: a replay grows its map as the run did), else a
    replay shows their final state.
    """

    def __init__(
        self,
        *,
        meshcat: Meshcat,
        map_period: float,
        scan_period: float,
        scan_offset: float = 0.0,
        X_base_sensor=(0.0, 0.0, 0.0),
        scan_height: float = 0.17,
        keyframes: bool = False,
    ):
        super().__init__()
        self._meshcat = meshcat
        self._X_base_sensor = np.asarray(X_base_sensor, dtype=float)
        self._scan_height = scan_height
        self._keyframes = keyframes
        self._map_period = map_period
        self._map = self.DeclareAbstractInputPort("map", AbstractValue.Make(EMPTY_MAP))
        self._scan = self.DeclareAbstractInputPort("scan", AbstractValue.Make(NO_SCAN))
        self._pose = self.DeclareVectorInputPort("pose", 3)
        self.DeclarePeriodicPublishEvent(map_period, 0.0, self._draw_map)
        scan_period = map_period if keyframes else scan_period
        self.DeclarePeriodicPublishEvent(scan_period, scan_offset, self._draw_scan)
        self.DeclareForcedPublishEvent(self._draw_all)
        meshcat.SetObject("/mapping/estimate/shaft", Cylinder(0.01, 0.25), ESTIMATE_COLOR)
        meshcat.SetTransform(
            "/mapping/estimate/shaft",
            RigidTransform(RollPitchYaw(0, np.pi / 2, 0), [0.125, 0, 0]),
        )

    def _draw_all(self, context):
        self._draw_map(context)
        self._draw_scan(context)

    def _draw_map(self, context):
        occupancy_map = self._map.Eval(context)
        if occupancy_map.cells.size:
            self._put("map", map_mesh(occupancy_map), None, None, context.get_time())

    def _draw_scan(self, context):
        pose = np.asarray(self._pose.Eval(context), dtype=float)
        X = RigidTransform(RollPitchYaw(0, 0, pose[2]), [pose[0], pose[1], MAP_HEIGHT])
        self._meshcat.SetTransform("/mapping/estimate", X, time_in_recording=context.get_time())
        scan = self._scan.Eval(context)
        points = scan.points() if scan.ranges.size else np.zeros((0, 2))
        if len(points) == 0:
            return
        c, s = np.cos(pose[2]), np.sin(pose[2])
        x, y, yaw = self._X_base_sensor
        sensor = np.array([pose[0] + c * x - s * y, pose[1] + s * x + c * y, pose[2] + yaw])
        cs, ss = np.cos(sensor[2]), np.sin(sensor[2])
        world = np.column_stack(
            [
                sensor[0] + cs * points[:, 0] - ss * points[:, 1],
                sensor[1] + ss * points[:, 0] + cs * points[:, 1],
            ]
        )
        cloud = point_cloud(world, self._scan_height)
        self._put("scan", cloud, 0.04, SCAN_COLOR, context.get_time())

    def _put(self, name: str, shape, point_size: float | None, rgba, time: float) -> None:
        """Draws ``shape`` (a ``PointCloud``, or a ``map_mesh``) at ``/mapping/<name>``, or
        with keyframes as the ``name`` keyframe of ``time``: shown from ``time`` on, and the
        one before it hidden from then."""
        if not self._keyframes:
            self._draw(f"/mapping/{name}", shape, point_size, rgba)
            return
        k = round(time / self._map_period)
        path = f"/mapping/{name}/{k}"
        self._draw(path, shape, point_size, rgba)
        self._meshcat.SetProperty(path, "visible", False, time_in_recording=0.0)
        self._meshcat.SetProperty(path, "visible", True, time_in_recording=time)
        if k > 0:
            self._meshcat.SetProperty(
                f"/mapping/{name}/{k - 1}", "visible", False, time_in_recording=time
            )

    def _draw(self, path: str, shape, point_size, rgba) -> None:
        if isinstance(shape, PointCloud):
            self._meshcat.SetObject(path, shape, point_size=point_size, rgba=rgba)
        else:
            self._meshcat.SetTriangleColorMesh(path, *shape)
