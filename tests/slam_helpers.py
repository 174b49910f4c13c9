"""Synthetic 2D worlds for the SLAM tests: convex polygons and circles, an exact vectorised ray
caster, the ground-truth grid, and a drive along waypoints with drifting wheel odometry."""

import math

import numpy as np

from drake_sim.base.map_files import OccupancyMap


def box(cx, cy, sx, sy, yaw_deg=0.0) -> np.ndarray:
    """Corners (4, 2), counter-clockwise, of a sx by sy rectangle centred on (cx, cy)."""
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    half = np.array([[-sx, -sy], [sx, -sy], [sx, sy], [-sx, sy]]) / 2
    return half @ np.array([[c, s], [-s, c]]) + [cx, cy]


def wall(a, b, thickness=0.1) -> np.ndarray:
    """A wall from a to b (m) as a rectangle."""
    (ax, ay), (bx, by) = a, b
    length = math.hypot(bx - ax, by - ay)
    yaw = math.degrees(math.atan2(by - ay, bx - ax))
    return box((ax + bx) / 2, (ay + by) / 2, length + thickness, thickness, yaw)


class World:
    """Polygons (convex, counter-clockwise) and circles (x, y, r) inside a room whose inner
    faces are at x = +-half_x, y = +-half_y."""

    def __init__(self, half_x, half_y, polygons=(), circles=(), thickness=0.1):
        t = thickness
        self.half = (half_x, half_y)
        self.thickness = t
        outer = [
            box(0, -half_y - t / 2, 2 * half_x + 2 * t, t),
            box(0, half_y + t / 2, 2 * half_x + 2 * t, t),
            box(-half_x - t / 2, 0, t, 2 * half_y + 2 * t),
            box(half_x + t / 2, 0, t, 2 * half_y + 2 * t),
        ]
        self.polygons = outer + [np.asarray(p, float) for p in polygons]
        self.circles = np.asarray(circles, float).reshape(-1, 3)
        edges = [np.concatenate([p, np.roll(p, -1, 0)], 1) for p in self.polygons]
        self.edges = np.concatenate(edges)  # (m, 4): ax, ay, bx, by

    def cast(self, pose, angles, range_max=np.inf) -> np.ndarray:
        """Exact ranges (n,) from a sensor at pose (x, y, yaw); inf beyond range_max."""
        x, y, yaw = pose
        d = np.stack([np.cos(angles + yaw), np.sin(angles + yaw)], -1)  # (n, 2)
        a, b = self.edges[:, :2], self.edges[:, 2:]
        e = b - a
        denom = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]
        w = a[None] - np.array([x, y])
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (w[..., 0] * e[None, :, 1] - w[..., 1] * e[None, :, 0]) / denom
            u = (w[..., 0] * d[:, None, 1] - w[..., 1] * d[:, None, 0]) / denom
        t = np.where((t > 0) & (u >= 0) & (u <= 1), t, np.inf)
        best = t.min(1)
        if len(self.circles):
            f = np.array([x, y]) - self.circles[None, :, :2]
            bq = (d[:, None, :] * f).sum(-1)
            cq = (f * f).sum(-1) - self.circles[None, :, 2] ** 2
            disc = bq**2 - cq
            with np.errstate(invalid="ignore"):
                tc = -bq - np.sqrt(disc)
            tc = np.where((disc >= 0) & (tc > 0), tc, np.inf)
            best = np.minimum(best, tc.min(1))
        return np.where(best < range_max, best, np.inf)

    def truth(self, resolution=0.05) -> OccupancyMap:
        """Ground truth: cell centres inside the outer walls' outline are free (0) or occupied
        (100, covered by a polygon or circle); none outside the outline."""
        hx = self.half[0] + self.thickness
        hy = self.half[1] + self.thickness
        cols, rows = round(2 * hx / resolution), round(2 * hy / resolution)
        cells = np.zeros((rows, cols), np.int8)
        dut = OccupancyMap(cells, resolution, (-hx, -hy, 0.0))
        xs, ys = dut.centres()
        occupied = np.zeros(cells.shape, bool)
        for p in self.polygons:
            inside = np.ones(cells.shape, bool)
            for (ax, ay), (bx, by) in zip(p, np.roll(p, -1, 0), strict=True):
                inside &= (bx - ax) * (ys - ay) - (by - ay) * (xs - ax) >= 0
            occupied |= inside
        for cx, cy, r in self.circles:
            occupied |= (xs - cx) ** 2 + (ys - cy) ** 2 <= r**2
        cells[occupied] = 100
        return OccupancyMap(cells, resolution, dut.origin)

    def is_free(self, xy, clearance=0.0) -> bool:
        """Whether a point is inside the room and clear of everything by ``clearance`` m."""
        probe = self.cast((xy[0], xy[1], 0.0), np.linspace(-np.pi, np.pi, 72, endpoint=False))
        return bool(np.all(probe > clearance)) and abs(xy[0]) < self.half[0]


def room() -> World:
    """An 8 m x 6 m room with boxes, cylinders and an inner wall."""
    return World(
        4.0,
        3.0,
        polygons=[
            box(1.5, 1.0, 0.4, 0.4, 30),
            box(-2.2, 1.6, 0.6, 0.3, 0),
            box(2.6, -1.8, 0.5, 0.5, 15),
            wall((0.0, -3.0), (0.0, -0.6)),
            wall((-4.0, -0.4), (-2.4, -0.4)),
        ],
        circles=[(-1.2, 0.8, 0.15), (2.8, 1.9, 0.2), (-2.5, -1.8, 0.2)],
    )


# About 30 m through the room with at least 0.25 m of clearance: it sees every surface.
ROOM_ROUTE = [
    (-1.0, -2.3),
    (-1.0, 0.1),
    (-3.4, 0.2),
    (-3.3, 2.4),
    (-0.5, 2.4),
    (0.6, 0.1),
    (0.8, -2.4),
    (3.3, -2.4),
    (3.4, -0.6),
    (3.4, 2.5),
    (1.0, 2.5),
    (-0.4, 1.4),
    (-0.5, 0.0),
]
ROOM_START = (-3.2, -2.3, 0.0)


def doorways():
    """A corridor 1.2 m wide whose walls have a 0.9 m doorway every 3 m, rooms behind them:
    every surface faces across it, but the jambs are depth steps along it."""
    walls = [
        box(x + 1.05, side * 0.65, 2.1, 0.1) for x in np.arange(-15.0, 15.0, 3.0)
        for side in (-1, 1)
    ]  # fmt: skip
    return World(15.0, 3.0, polygons=walls)


def drive(waypoints, start, *, speed=0.2, turn_rate=0.8, rate=5.0):
    """Truth poses (k, 3) of a robot that turns on the spot towards each waypoint then drives
    straight to it, sampled at ``rate`` Hz."""
    dt = 1.0 / rate
    pose = np.array(start, float)
    poses = [pose.copy()]
    for wx, wy in waypoints:
        while True:
            dx, dy = wx - pose[0], wy - pose[1]
            dist = math.hypot(dx, dy)
            if dist < 1e-6:
                break
            err = (math.atan2(dy, dx) - pose[2] + math.pi) % (2 * math.pi) - math.pi
            if abs(err) > 1e-6:
                pose[2] += math.copysign(min(abs(err), turn_rate * dt), err)
            else:
                step = min(dist, speed * dt)
                pose[:2] += step * np.array([math.cos(pose[2]), math.sin(pose[2])])
            poses.append(pose.copy())
    return np.array(poses)


def compose(a, b):
    """a (x) b for planar poses (x, y, yaw)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2]])


def relative(a, b):
    """a^-1 (x) b."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    dyaw = (b[2] - a[2] + math.pi) % (2 * math.pi) - math.pi
    return np.array([c * dx + s * dy, -s * dx + c * dy, dyaw])


def drifting_odometry(truth, *, seed, scale=0.02, yaw_deg_per_m=0.5, noise=0.002):
    """Wheel odometry along ``truth`` (k, 3): each step's motion scaled by 1 + scale, a yaw
    drift of yaw_deg_per_m degrees per metre plus Gaussian noise (per step, m and rad)."""
    rng = np.random.default_rng(seed)
    yaw_per_m = math.radians(yaw_deg_per_m)
    odom = [np.array(truth[0], float)]
    for prev, now in zip(truth[:-1], truth[1:], strict=True):
        step = relative(prev, now)
        dist = math.hypot(step[0], step[1])
        step[:2] *= 1 + scale
        step[2] += yaw_per_m * dist + rng.normal(0, noise) * (dist > 0 or abs(step[2]) > 0)
        step[:2] += rng.normal(0, noise / 4, 2) * (dist > 0)
        odom.append(compose(odom[-1], step))
    return np.array(odom)


def lidar_scans(world, sensor_poses, *, seed, beams=360, range_max=3.5, sigma=0.01):
    """Noisy ranges (k, n) and the beam angles (n,) from sensors at ``sensor_poses``."""
    rng = np.random.default_rng(seed)
    angles = np.linspace(-np.pi, np.pi, beams, endpoint=False)
    ranges = np.array([world.cast(p, angles) for p in sensor_poses])
    ranges = ranges + rng.normal(0.0, sigma, ranges.shape)
    return np.where(ranges < range_max, ranges, np.inf), angles
