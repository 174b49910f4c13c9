"""Costmaps in the manner of ROS's ``costmap_2d``: a static layer from a saved map, an obstacle
layer from live lidar scans, and inflation; a rolling local window around the robot.

Cell costs are uint8 with costmap_2d's values: ``FREE_SPACE`` 0, ``INSCRIBED`` 253 (the robot's
centre here means a collision: within ``robot_radius`` of an obstacle), ``LETHAL`` 254 (an
obstacle cell) and ``NO_INFORMATION`` 255 (unknown). Inflation is costmap_2d's function of the
distance d (m, between cell centres) to the nearest lethal cell::

    d == 0                 -> LETHAL
    d <= r_in              -> INSCRIBED      (r_in = robot_radius)
    d <= inflation_radius  -> floor((INSCRIBED - 1) * exp(-cost_scaling_factor * (d - r_in)))
    else                   -> FREE_SPACE

The layers are combined as costmap_2d combines them: a cell is lethal when the static or the
obstacle layer says so (the static layer is never cleared by scans); an unknown map cell stays
``NO_INFORMATION`` (or ``unknown_cost_value``) unless a beam crossed it or inflation gives it
``INSCRIBED`` or more. Distances come from scipy's exact Euclidean distance transform; a scan
update re-inflates only the window its beams can have changed (the beams' reach plus twice the
inflation radius). The grid convention is ``OccupancyMap``'s: ``costs[0]`` is the lowest y
row, ``origin`` = (x, y, yaw) of the lower-left corner of cell [0, 0].
"""

import dataclasses as dc
import math

import numpy as np
from scipy import ndimage

from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.planar_grid import PlanarGrid

FREE_SPACE = 0
INSCRIBED = 253
LETHAL = 254
NO_INFORMATION = 255

_TIE = 1e-9  # m: distances this close to a threshold count as within it.


@dc.dataclass
class CostmapConfig:
    """Layers and inflation of the global and local costmaps (costmap_2d / nav2 names)."""

    robot_radius: float = 0.22  # m, the inscribed radius (nav2 TurtleBot3: 0.22).
    # m, where costs fall to FREE_SPACE; >= robot_radius. 0.5 leaves the centre of the maze's
    # 1.2 m corridors (0.6 m from either wall) at zero cost.
    inflation_radius: float = 0.5
    cost_scaling_factor: float = 3.0  # 1/m, exponential decay of the cost past robot_radius.
    lethal_cost_threshold: int = 65  # Map value (0..100) from which a map cell is an obstacle.
    track_unknown_space: bool = True  # Unknown map cells are unknown (else free).
    unknown_cost_value: int = 255  # Cost of unknown cells when tracked (255 NO_INFORMATION).
    obstacle_max_range: float = 2.5  # m, hits up to this range mark obstacles.
    obstacle_min_range: float = 0.0  # m, hits nearer than this are ignored (the robot itself).
    raytrace_max_range: float = 3.0  # m, beams clear the cells they cross up to this range.
    local_width: float = 3.0  # m, the rolling local window's extent along the map's x.
    local_height: float = 3.0  # m, its extent along the map's y.
    # The robot's outline in its base frame, [[x, y], ...] m (a polygon, costmap_2d's
    # ``footprint``); empty for the circle of robot_radius. With one, robot_radius is the
    # polygon's inscribed radius (``footprint_radii``: ``--params`` sets both) and the local
    # planner checks the outline against obstacles at every pose of its rollouts.
    footprint: list[list[float]] = dc.field(default_factory=list)


def check_costmap_config(config: CostmapConfig, where: str = "costmap", prefix: str = "") -> None:
    """Raises ``ConfigError`` naming ``where`` and the first out-of-range field of ``config``.

    Args:
        prefix: prepended to field names, e.g. ``"costmap."`` for a section of a bigger file.
    """

    def fail(name: str, rule: str) -> None:
        raise ConfigError(
            f"{where}: '{prefix}{name}' must be {rule}, got {getattr(config, name)!r}"
        )

    for field in dc.fields(config):
        value = getattr(config, field.name)
        if field.name == "footprint":
            _check_footprint(value, fail)
            continue
        if field.name == "track_unknown_space":
            if not isinstance(value, bool):
                fail(field.name, "true or false")
            continue
        if isinstance(value, bool) or not isinstance(value, int | float):
            fail(field.name, "a number")
        if not math.isfinite(value):
            fail(field.name, "finite")
    for name in ("robot_radius", "local_width", "local_height", "raytrace_max_range"):
        if getattr(config, name) <= 0:
            fail(name, "> 0")
    if config.inflation_radius < config.robot_radius:
        fail("inflation_radius", f">= robot_radius ({config.robot_radius})")
    if config.cost_scaling_factor < 0:
        fail("cost_scaling_factor", ">= 0")
    if not 1 <= config.lethal_cost_threshold <= 100:
        fail("lethal_cost_threshold", "in [1, 100]")
    if not 0 <= config.unknown_cost_value <= 255:
        fail("unknown_cost_value", "in [0, 255]")
    if not 0 <= config.obstacle_min_range < config.obstacle_max_range:
        fail("obstacle_min_range", "in [0, obstacle_max_range)")


def _check_footprint(footprint, fail) -> None:
    if not footprint:
        return
    ok = len(footprint) >= 3 and all(
        isinstance(p, list | tuple) and len(p) == 2 and all(math.isfinite(float(v)) for v in p)
        for p in footprint
    )
    if not ok:
        fail("footprint", "a polygon of 3 or more [x, y] points (m)")
    if footprint_radii(footprint)[0] <= 0:
        fail("footprint", "a polygon around the robot's origin")


def footprint_radii(footprint) -> tuple[float, float]:
    """(inscribed, circumscribed) radius of a footprint polygon about the robot's origin, m:
    the distance to its nearest edge (0 when the origin is outside it) and to its farthest
    corner."""
    points = np.asarray(footprint, dtype=float)
    a, b = points, np.roll(points, -1, axis=0)
    ab = b - a
    t = np.clip(
        np.einsum("ij,ij->i", -a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-18), 0, 1
    )
    nearest = a + t[:, None] * ab
    inside = _inside_polygon(points, np.zeros(2))
    inscribed = float(np.min(np.hypot(*nearest.T))) if inside else 0.0
    return inscribed, float(np.max(np.hypot(*points.T)))


def _inside_polygon(points: np.ndarray, p: np.ndarray) -> bool:
    x, y = points[:, 0] - p[0], points[:, 1] - p[1]
    x2, y2 = np.roll(x, -1), np.roll(y, -1)
    crosses = (y > 0) != (y2 > 0)
    at = x + (0 - y) * (x2 - x) / np.where(y2 - y == 0, 1e-18, y2 - y)
    return bool(np.sum(crosses & (at > 0)) % 2 == 1)


def footprint_outline(footprint, spacing: float) -> np.ndarray:
    """Points (k, 2) along a footprint polygon's edges, at most ``spacing`` m apart, corners
    included, in the robot's base frame."""
    points = np.asarray(footprint, dtype=float)
    out = []
    for a, b in zip(points, np.roll(points, -1, axis=0), strict=True):
        n = max(1, math.ceil(math.hypot(*(b - a)) / spacing))
        out.append(a + np.outer(np.arange(n) / n, b - a))
    return np.vstack(out)


def inflate(lethal_mask: np.ndarray, resolution: float, config: CostmapConfig) -> np.ndarray:
    """Returns costmap_2d's inflated costs (uint8, the mask's shape) around ``lethal_mask``.

    Args:
        lethal_mask: bool (rows, cols), the obstacle cells.
        resolution: m per cell.
        config: ``robot_radius``, ``inflation_radius`` and ``cost_scaling_factor``.
    """
    lethal = np.asarray(lethal_mask, dtype=bool)
    if not lethal.any():
        return np.zeros(lethal.shape, dtype=np.uint8)
    d = ndimage.distance_transform_edt(~lethal) * resolution
    decay = (INSCRIBED - 1) * np.exp(-config.cost_scaling_factor * (d - config.robot_radius))
    costs = np.where(d <= config.inflation_radius + _TIE, np.floor(decay), FREE_SPACE)
    costs[d <= config.robot_radius + _TIE] = INSCRIBED
    costs[lethal] = LETHAL
    return costs.astype(np.uint8)


class Costmap(PlanarGrid):
    """A 2D costmap: static and obstacle layers, inflated and combined into ``costs``; its cells
    and world points convert with ``PlanarGrid``'s methods (``to_grid``, ``cell_of``, ...).

    Attributes:
        resolution: m per cell.
        origin: (x, y, yaw) of the lower-left corner of cell [0, 0] in the world (m, m, rad).
        config: the ``CostmapConfig``.
        costs: uint8 (rows, cols), the combined costs (row 0 = lowest y).
        static_layer: uint8 (rows, cols): FREE_SPACE, LETHAL or NO_INFORMATION, from the map.
        obstacle_layer: uint8 (rows, cols): NO_INFORMATION (never seen), FREE_SPACE (a beam
            crossed it last) or LETHAL (a beam ended in it last).
    """

    def __init__(self, static_layer, resolution: float, origin=(0.0, 0.0, 0.0), config=None):
        """Builds a costmap from a static layer (uint8 FREE_SPACE / LETHAL / NO_INFORMATION)
        with an empty obstacle layer, and inflates it."""
        self.config = config if config is not None else CostmapConfig()
        check_costmap_config(self.config, "Costmap")
        self.static_layer = np.ascontiguousarray(static_layer, dtype=np.uint8)
        if self.static_layer.ndim != 2:
            raise ValueError(f"Costmap layers must be 2D, got shape {self.static_layer.shape}")
        self.resolution = float(resolution)
        self.origin = tuple(float(v) for v in origin)
        self.obstacle_layer = np.full(self.shape, NO_INFORMATION, dtype=np.uint8)
        self.costs = np.zeros(self.shape, dtype=np.uint8)
        self._reinflate(0, self.shape[0], 0, self.shape[1])

    @staticmethod
    def from_map(occupancy_map: OccupancyMap, config: CostmapConfig | None = None) -> "Costmap":
        """Returns the costmap of a map: cells at or above ``lethal_cost_threshold`` are
        LETHAL, unknown cells NO_INFORMATION (FREE_SPACE without ``track_unknown_space``)."""
        config = config if config is not None else CostmapConfig()
        cells = occupancy_map.cells
        static = np.full(cells.shape, FREE_SPACE, dtype=np.uint8)
        if config.track_unknown_space:
            static[cells < 0] = NO_INFORMATION
        static[cells >= config.lethal_cost_threshold] = LETHAL
        return Costmap(static, occupancy_map.resolution, occupancy_map.origin, config)

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols)."""
        return self.static_layer.shape

    def cost_at(self, xy, outside: int = NO_INFORMATION) -> np.ndarray:
        """Costs (uint8) of the cells at world points ``xy`` (..., 2) m; ``outside`` beyond."""
        return self.values_at(self.costs, xy, outside)

    def lethal_mask(self) -> np.ndarray:
        """Mask of the obstacle cells of both layers."""
        return (self.static_layer == LETHAL) | (self.obstacle_layer == LETHAL)

    def update_scan(self, sensor_pose, ranges, angles, range_max: float) -> None:
        """Updates the obstacle layer with one scan and re-inflates what it can have changed.

        Every beam clears the cells it crosses (sampled every half cell), up to one cell short
        of its end point if that lies within ``raytrace_max_range`` (and the lidar's range),
        else up to that range (a beam with no return, ``inf``, up to min(range_max,
        ``raytrace_max_range``)); then beams ending within [``obstacle_min_range``,
        ``obstacle_max_range``] mark their end cells LETHAL. NaN ranges are ignored. The static
        layer is not changed. Cost: about 1.5 ms for 360 beams on the warehouse map (0.05 m).

        Args:
            sensor_pose: (x, y, yaw) of the lidar in the map (world) frame, m, m, rad.
            ranges: (n,) m; ``inf`` for no return.
            angles: (n,) rad, the beams' directions in the lidar frame.
            range_max: m, the lidar's maximum range.
        """
        x, y, yaw = (float(v) for v in sensor_pose)
        ranges = np.asarray(ranges, dtype=float).ravel()
        angles = np.asarray(angles, dtype=float).ravel() + yaw
        if ranges.shape != angles.shape:
            raise ValueError(f"{ranges.shape[0]} ranges but {angles.shape[0]} angles")
        cfg = self.config
        valid = ~np.isnan(ranges)
        ranges, angles = ranges[valid], angles[valid]
        u = np.stack([np.cos(angles), np.sin(angles)], -1)
        finite = np.isfinite(ranges)
        reach = min(cfg.raytrace_max_range, float(range_max))
        # A hit's own cell is left to marking: clear up to one cell short of it.
        clear = np.where(finite & (ranges <= reach), ranges - self.resolution, reach)
        step = 0.5 * self.resolution
        t = np.arange(int(math.ceil(max(float(clear.max(initial=0.0)), 0.0) / step)) + 1) * step
        # Samples every half cell along the beams, in grid units (column, row).
        g0 = self.to_grid(np.array([x, y]))
        u_grid = self.to_grid(u + self.origin[:2]) * self.resolution  # directions in the grid
        along = t[None, :] < clear[:, None]
        tt = np.broadcast_to(t[None, :], along.shape)[along] / self.resolution
        which = np.nonzero(along)[0]
        cols = np.floor(g0[0] + tt * u_grid[which, 0]).astype(np.int64)
        rows = np.floor(g0[1] + tt * u_grid[which, 1]).astype(np.int64)
        ok = self.inside(rows, cols)
        self.obstacle_layer[rows[ok], cols[ok]] = FREE_SPACE
        marks = finite & (ranges >= cfg.obstacle_min_range) & (ranges <= cfg.obstacle_max_range)
        hits = np.array([x, y]) + ranges[marks, None] * u[marks]
        hit_rows, hit_cols = self.cell_of(hits)
        ok = self.inside(hit_rows, hit_cols)
        self.obstacle_layer[hit_rows[ok], hit_cols[ok]] = LETHAL
        # The beams change cells within this radius of the sensor; costs change one inflation
        # radius further.
        radius = max(reach, cfg.obstacle_max_range) + cfg.inflation_radius + self.resolution
        self._reinflate_around((x, y), radius)

    def clear_obstacles(self) -> None:
        """Forgets the obstacle layer (the "clear costmap" recovery) and re-inflates."""
        self.obstacle_layer[:] = NO_INFORMATION
        self._reinflate(0, self.shape[0], 0, self.shape[1])

    def local_window(self, center_xy) -> "Costmap":
        """Returns the rolling local costmap: a ``local_width`` x ``local_height`` (m) window of
        this one (all layers, costs as inflated here), aligned with its cells and centred on
        the cell holding ``center_xy`` (m); cells outside this costmap are NO_INFORMATION."""
        width = max(1, int(round(self.config.local_width / self.resolution)))
        height = max(1, int(round(self.config.local_height / self.resolution)))
        row, col = (int(v) for v in self.cell_of(np.asarray(center_xy, dtype=float)[:2]))
        r0, c0 = row - height // 2, col - width // 2
        window = Costmap.__new__(Costmap)
        window.config = self.config
        window.resolution = self.resolution
        window.origin = (*(float(v) for v in self.to_world(np.array([c0, r0]))), self.origin[2])
        for name in ("static_layer", "obstacle_layer", "costs"):
            setattr(window, name, _crop(getattr(self, name), r0, c0, height, width))
        return window

    def _reinflate_around(self, xy, radius: float) -> None:
        grid = self.to_grid(np.asarray(xy, dtype=float))
        span = radius / self.resolution + 1
        r0, r1 = int(math.floor(grid[1] - span)), int(math.ceil(grid[1] + span)) + 1
        c0, c1 = int(math.floor(grid[0] - span)), int(math.ceil(grid[0] + span)) + 1
        rows, cols = self.shape
        r0, r1, c0, c1 = max(r0, 0), min(r1, rows), max(c0, 0), min(c1, cols)
        if r0 < r1 and c0 < c1:
            self._reinflate(r0, r1, c0, c1)

    def _reinflate(self, r0: int, r1: int, c0: int, c1: int) -> None:
        """Recomputes ``costs[r0:r1, c0:c1]`` from the layers (using lethal cells up to one
        inflation radius beyond the window, which is all that can reach into it)."""
        pad = int(math.ceil(self.config.inflation_radius / self.resolution)) + 1
        rows, cols = self.shape
        R0, R1, C0, C1 = (
            max(r0 - pad, 0),
            min(r1 + pad, rows),
            max(c0 - pad, 0),
            min(c1 + pad, cols),
        )
        static = self.static_layer[R0:R1, C0:C1]
        obstacle = self.obstacle_layer[R0:R1, C0:C1]
        costs = inflate((static == LETHAL) | (obstacle == LETHAL), self.resolution, self.config)
        unknown = (static == NO_INFORMATION) & (obstacle == NO_INFORMATION) & (costs < INSCRIBED)
        costs[unknown] = np.maximum(costs[unknown], self.config.unknown_cost_value)
        self.costs[r0:r1, c0:c1] = costs[r0 - R0 : r1 - R0, c0 - C0 : c1 - C0]


def _crop(layer: np.ndarray, r0: int, c0: int, height: int, width: int) -> np.ndarray:
    """Returns ``layer[r0:r0 + height, c0:c0 + width]``, NO_INFORMATION outside ``layer``."""
    out = np.full((height, width), NO_INFORMATION, dtype=np.uint8)
    rows, cols = layer.shape
    a0, a1 = max(r0, 0), min(r0 + height, rows)
    b0, b1 = max(c0, 0), min(c0 + width, cols)
    if a0 < a1 and b0 < b1:
        out[a0 - r0 : a1 - r0, b0 - c0 : b1 - c0] = layer[a0:a1, b0:b1]
    return out
