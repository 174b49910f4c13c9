"""2D shapes on the floor: the footprints of walls and obstacles, their signed distances and
ray distances, and the queries on many of them (a clearance, a 2D ray caster) and on a grid
(its occupied cells a lidar can see).

A ``Footprint`` is a rectangle (walls, boxes) or a circle (cylinders) in the world frame W's
floor plane, with its height above the floor. Every query here is exact (closed forms, no
sampling) and vectorised over points or rays. An arena's footprints come from
``drake_sim.worlds.arena.arena_footprints``.
"""

import dataclasses as dc
import math

import numpy as np


@dc.dataclass(frozen=True)
class Footprint:
    """A wall's or obstacle's shape on the floor: a rectangle (``radius`` 0) or a circle.

    Attributes:
        kind: "wall" (outer or inner) , "box" or "cylinder".
        name: unique within the arena (the SDF geometry's name).
        centre: (x, y) m in W.
        half_size: (hx, hy) m, a rectangle's half extents along its own axes; (r, r) for a circle.
        yaw: rad, the rectangle's x axis from W's x axis.
        radius: m, a circle's radius; 0 for a rectangle.
        height: m above the floor.
    """

    kind: str
    name: str
    centre: tuple[float, float]
    half_size: tuple[float, float]
    yaw: float
    radius: float
    height: float

    @property
    def is_circle(self) -> bool:
        """True for a cylinder's circle, False for a rectangle."""
        return self.radius > 0

    def corners(self) -> np.ndarray:
        """Returns the (4, 2) corners (m, W) of a rectangle, or of a circle's bounding square."""
        hx, hy = self.half_size
        local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
        c, s = (1.0, 0.0) if self.is_circle else (math.cos(self.yaw), math.sin(self.yaw))
        return local @ np.array([[c, s], [-s, c]]) + self.centre

    def signed_distance(self, p_WQ: np.ndarray) -> np.ndarray:
        """Returns the signed distance (m; negative inside) from points ``p_WQ`` (..., 2)."""
        d = np.asarray(p_WQ, dtype=float) - self.centre
        if self.is_circle:
            return np.hypot(d[..., 0], d[..., 1]) - self.radius
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        qx = np.abs(c * d[..., 0] + s * d[..., 1]) - self.half_size[0]
        qy = np.abs(-s * d[..., 0] + c * d[..., 1]) - self.half_size[1]
        outside = np.hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0))
        return outside + np.minimum(np.maximum(qx, qy), 0.0)

    def ray_distance(self, p_WO: np.ndarray, u_W: np.ndarray) -> np.ndarray:
        """Returns how far (m) rays from ``p_WO`` along unit ``u_W`` (both (..., 2)) travel
        before entering the shape: 0 from inside, ``inf`` when they miss it."""
        o = np.asarray(p_WO, dtype=float) - self.centre
        u = np.asarray(u_W, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.is_circle:
                b = np.sum(o * u, axis=-1)
                c = np.sum(o * o, axis=-1) - self.radius**2
                disc = b * b - c
                t = -b - np.sqrt(np.maximum(disc, 0.0))
                hit = (disc >= 0) & (t >= 0)
                return np.where(c <= 0, 0.0, np.where(hit, t, np.inf))
            cy, sy = math.cos(self.yaw), math.sin(self.yaw)
            t_near = np.zeros(np.broadcast_shapes(o.shape, u.shape)[:-1])
            t_far = np.full_like(t_near, np.inf)
            for axis, (ax, ay) in enumerate(((cy, sy), (-sy, cy))):
                oa = o[..., 0] * ax + o[..., 1] * ay
                ua = u[..., 0] * ax + u[..., 1] * ay
                h = self.half_size[axis]
                t1, t2 = (-h - oa) / ua, (h - oa) / ua
                parallel = ua == 0
                inside = np.abs(oa) <= h
                lo = np.where(parallel, np.where(inside, -np.inf, np.inf), np.minimum(t1, t2))
                hi = np.where(parallel, np.where(inside, np.inf, -np.inf), np.maximum(t1, t2))
                t_near, t_far = np.maximum(t_near, lo), np.minimum(t_far, hi)
            return np.where(t_near <= t_far, t_near, np.inf)


def clearance(footprints: list[Footprint], p_WQ: np.ndarray) -> np.ndarray:
    """Returns the signed distance (m; negative inside) from each point ``p_WQ`` (..., 2) to
    the nearest of ``footprints`` (``inf`` when there are none)."""
    p = np.asarray(p_WQ, dtype=float)
    result = np.full(p.shape[:-1], np.inf)
    for footprint in footprints:
        result = np.minimum(result, footprint.signed_distance(p))
    return result


def cast_rays(
    footprints: list[Footprint], p_WO: np.ndarray, angles: np.ndarray, max_range: float
) -> np.ndarray:
    """Casts 2D rays against ``footprints``, exactly (no sampling).

    Args:
        footprints: the shapes to hit (e.g. ``arena_footprints(arena, height=scan_height)``).
        p_WO: (m, 2) ray origins, m, in W.
        angles: (k,) ray directions, rad from W's x axis.
        max_range: m; longer rays report ``inf``.

    Returns:
        (m, k) distances (m) to the first surface along each ray; 0 from inside a shape.
    """
    origins = np.atleast_2d(np.asarray(p_WO, dtype=float))[:, None, :]
    u = np.stack([np.cos(angles), np.sin(angles)], axis=-1)[None, :, :]
    ranges = np.full((origins.shape[0], u.shape[1]), np.inf)
    for footprint in footprints:
        ranges = np.minimum(ranges, footprint.ray_distance(origins, u))
    return np.where(ranges <= max_range, ranges, np.inf)


def occupied_boundary(cells: np.ndarray) -> np.ndarray:
    """Returns the mask of occupied cells (>= 50) with a free neighbour (0 <= value < 50,
    8-connected): the cells a lidar can see, as opposed to the insides of obstacles."""
    cells = np.asarray(cells)
    occupied = cells >= 50
    free = (cells >= 0) & (cells < 50)
    padded = np.pad(free, 1)
    near_free = np.zeros_like(free)
    rows, cols = free.shape
    for dr in (-1, 0, 1):
        for dc_ in (-1, 0, 1):
            near_free |= padded[1 + dr : 1 + dr + rows, 1 + dc_ : 1 + dc_ + cols]
    return occupied & near_free
