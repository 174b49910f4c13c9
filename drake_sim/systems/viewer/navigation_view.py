"""Meshcat display of navigation (RViz's map, costmap, particle cloud, path and goal displays),
under ``/navigation``."""

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import Cylinder, Meshcat, Rgba
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.perception import BaseField, Fields, PointCloud
from pydrake.systems.framework import LeafSystem

from drake_sim.base.map_files import OccupancyMap
from drake_sim.systems.viewer.map_view import map_mesh

PARTICLE_COLOR = Rgba(1.0, 0.3, 0.1, 1.0)
PATH_COLOR = Rgba(0.1, 0.7, 0.2, 1.0)
LOCAL_COLOR = Rgba(0.9, 0.1, 0.8, 1.0)
GOAL_COLOR = Rgba(0.95, 0.75, 0.1, 1.0)
COSTMAP_HEIGHT = 0.004  # m: the costmap lies just over the map.
LINE_HEIGHT = 0.02  # m: paths float above both.


def costmap_mesh(costs: np.ndarray, resolution: float, origin, height: float = COSTMAP_HEIGHT):
    """The inflated cells of a costmap (cost 1 to 254) as a coloured triangle mesh for
    ``Meshcat.SetTriangleColorMesh``: from pale blue (low cost) through to red (lethal)."""
    rows, cols = np.nonzero((costs > 0) & (costs < 255))
    value = costs[rows, cols].astype(float) / 254.0
    x0, y0 = origin[0], origin[1]
    xs = x0 + (cols + 0.5) * resolution
    ys = y0 + (rows + 0.5) * resolution
    half = 0.5 * resolution
    corners = np.array([[-half, -half], [half, -half], [half, half], [-half, half]])
    vertices = np.empty((3, 4 * len(xs)))
    vertices[0] = (xs[:, None] + corners[:, 0]).ravel()
    vertices[1] = (ys[:, None] + corners[:, 1]).ravel()
    vertices[2] = height
    first = 4 * np.arange(len(xs))[:, None]
    faces = np.hstack([first + [0, 1, 2], first + [0, 2, 3]]).reshape(-1, 3).T
    colour = np.stack([value, 0.3 * (1 - value), 1 - value])  # blue -> red
    colors = np.repeat(colour.T, 4, axis=0).T
    return vertices, np.ascontiguousarray(faces, dtype=np.int32), np.ascontiguousarray(colors)


class NavigationView(LeafSystem):
    """Draws the map once, then every ``period`` s the particle cloud, the global costmap, the
    global path, the local planner's chosen trajectory and the goal.

    .. pydrake_system::

        name: NavigationView
        input_ports:
        - particles
        - navigation_status

    ``particles`` is AMCL's (n, 3) array of ``[x, y, yaw]``; ``navigation_status`` the
    ``Navigator``'s status (its ``path``, ``local_trajectory``, ``goal`` and ``costmap``
    attributes are drawn when present).
    """

    def __init__(self, *, meshcat: Meshcat, occupancy_map: OccupancyMap, period: float):
        super().__init__()
        self._meshcat = meshcat
        self._particles = self.DeclareAbstractInputPort(
            "particles", AbstractValue.Make(np.zeros((0, 3)))
        )
        self._status = self.DeclareAbstractInputPort("navigation_status", AbstractValue.Make(None))
        self.DeclarePeriodicPublishEvent(period, 0.0, self._draw)
        self.DeclareForcedPublishEvent(self._draw)
        meshcat.SetTriangleColorMesh("/navigation/map", *map_mesh(occupancy_map))
        meshcat.SetObject("/navigation/goal", Cylinder(0.05, 0.3), GOAL_COLOR)
        meshcat.SetProperty("/navigation/goal", "visible", False)

    def _draw(self, context):
        particles = np.asarray(self._particles.Eval(context), dtype=float).reshape(-1, 3)
        if len(particles):
            cloud = PointCloud(len(particles), Fields(BaseField.kXYZs))
            cloud.mutable_xyzs()[:] = np.vstack(
                [particles[:, 0], particles[:, 1], np.full(len(particles), LINE_HEIGHT)]
            )
            self._meshcat.SetObject(
                "/navigation/particles", cloud, point_size=0.03, rgba=PARTICLE_COLOR
            )
        status = self._status.Eval(context)
        if status is None:
            return
        costmap = getattr(status, "costmap", None)
        if costmap is not None:
            mesh = costmap_mesh(costmap.costs, costmap.resolution, costmap.origin)
            self._meshcat.SetTriangleColorMesh("/navigation/costmap", *mesh)
        for name, points, color in (
            ("path", getattr(status, "path", None), PATH_COLOR),
            ("local_trajectory", getattr(status, "local_trajectory", None), LOCAL_COLOR),
        ):
            self._line(name, points, color)
        goal = getattr(status, "goal", None)
        visible = goal is not None
        self._meshcat.SetProperty("/navigation/goal", "visible", visible)
        if visible:
            X = RigidTransform(RollPitchYaw(0, 0, goal[2]), [goal[0], goal[1], 0.15])
            self._meshcat.SetTransform("/navigation/goal", X)

    def _line(self, name: str, points, color: Rgba) -> None:
        path = f"/navigation/{name}"
        points = None if points is None else np.asarray(points, dtype=float)
        if points is None or len(points) < 2:
            self._meshcat.Delete(path)
            return
        vertices = np.vstack([points[:, 0], points[:, 1], np.full(len(points), LINE_HEIGHT)])
        self._meshcat.SetLine(path, vertices, 3.0, color)
