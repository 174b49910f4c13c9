"""Meshcat display of offline SLAM on a recorded log (``python -m drake_sim.mapping --log``
without ``--headless``): the map and the trajectory so far as they grow, the last scan at its
matched pose and an arrow at the pose, under ``/log``; at the end the final map and the optimised
trajectory, the camera looking down on the whole map. What RViz shows while slam_toolbox or
Cartographer run on a bag.

Not a Drake system: a log is no simulation, so ``LogView.update`` is called after each scan
and draws by the log's own clock (the map and the trail every ``map_period`` s of log, the
scan every ``scan_period`` s), so a long log is drawn at a cost that does not grow with its
rate.
"""

import numpy as np
from pydrake.geometry import Cylinder, Meshcat, Rgba
from pydrake.math import RigidTransform, RollPitchYaw

from drake_sim.systems.estimation.loop_closure import scan_points
from drake_sim.systems.estimation.scan_matcher import transform_points
from drake_sim.systems.viewer.map_view import (
    ESTIMATE_COLOR,
    MAP_HEIGHT,
    SCAN_COLOR,
    map_mesh,
    point_cloud,
)

TRAIL_COLOR = Rgba(0.1, 0.4, 1.0, 1.0)
ROOT = "/log"


class LogView:
    """Draws a log's SLAM run in ``meshcat`` (module docstring).

    Args:
        meshcat: the viewer.
        map_period, scan_period: s of log time between drawings of the map and the trail, and
            of the scan.
    """

    def __init__(self, meshcat: Meshcat, *, map_period: float = 10.0, scan_period: float = 0.5):
        self._meshcat = meshcat
        self._periods = (map_period, scan_period)
        self._last = [-np.inf, -np.inf]  # log times of the last map and scan drawings
        self._trail: list[np.ndarray] = []
        self._framed = False
        meshcat.Delete(ROOT)
        meshcat.SetProperty("/Grid", "visible", False)
        meshcat.SetObject(f"{ROOT}/estimate/shaft", Cylinder(0.02, 0.5), ESTIMATE_COLOR)
        meshcat.SetTransform(
            f"{ROOT}/estimate/shaft", RigidTransform(RollPitchYaw(0, np.pi / 2, 0), [0.25, 0, 0])
        )

    def update(self, slam, time: float, ranges, angles, range_min: float, range_max: float):
        """After ``slam`` took the scan of log ``time`` (its ``ranges`` at ``angles``)."""
        pose = np.asarray(slam.pose, dtype=float)
        self._trail.append(pose[:2].copy())
        if time - self._last[1] >= self._periods[1]:
            self._last[1] = time
            hits = scan_points(ranges, angles, range_max, range_min, slam.X_base_sensor, np.inf)
            self._draw_scan(transform_points(pose, hits), pose)
        if time - self._last[0] >= self._periods[0]:  # the trail too: it grows with the log
            self._last[0] = time
            self._draw_map(slam)
            self._draw_trail(np.array(self._trail))

    def finish(self, slam, trajectory: np.ndarray) -> None:
        """The final map and the whole (optimised) ``trajectory`` ((n, 3) poses)."""
        self._draw_map(slam, frame=True)
        if len(trajectory):
            self._draw_trail(np.asarray(trajectory)[:, :2])
            self._draw_scan(np.zeros((0, 2)), np.asarray(trajectory[-1], dtype=float))

    def _draw_map(self, slam, *, frame: bool = False) -> None:
        """The map; with ``frame`` (or at the first map) the camera looks down on all of it."""
        occupancy_map = slam.map()
        if not occupancy_map.cells.size:
            return
        self._meshcat.SetTriangleColorMesh(f"{ROOT}/map", *map_mesh(occupancy_map))
        if frame or not self._framed:
            self._framed = True
            low = np.array(occupancy_map.origin[:2])
            size = np.array([occupancy_map.width_m, occupancy_map.height_m])
            centre, side = low + size / 2, float(max(size.max(), 4.0))
            self._meshcat.SetCameraPose([*(centre - [0.0, 0.3 * side]), 0.9 * side], [*centre, 0])

    def _draw_scan(self, points: np.ndarray, pose: np.ndarray) -> None:
        X = RigidTransform(RollPitchYaw(0, 0, pose[2]), [pose[0], pose[1], 2 * MAP_HEIGHT])
        self._meshcat.SetTransform(f"{ROOT}/estimate", X)
        if not len(points):
            self._meshcat.Delete(f"{ROOT}/scan")
            return
        cloud = point_cloud(points, 3 * MAP_HEIGHT)
        self._meshcat.SetObject(f"{ROOT}/scan", cloud, point_size=0.06, rgba=SCAN_COLOR)

    def _draw_trail(self, xy: np.ndarray) -> None:
        if len(xy) < 2:
            return
        points = np.vstack([xy.T, np.full(len(xy), 2 * MAP_HEIGHT)])
        self._meshcat.SetLine(f"{ROOT}/trail", points, 2.0, TRAIL_COLOR)
