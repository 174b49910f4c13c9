"""Scripted routes and navigation goals in an arena: the YAML files, their checks, defaults.

A route (``config/routes/<arena>.yaml``) is driven in order from the arena's start by a
diff-drive robot that turns on the spot at each waypoint and drives straight between them:

.. code-block:: yaml

    waypoints: [[-2.0, 1.5], [2.0, 1.5], [2.0, -1.5]]   # m, (x, y) in the arena frame W

A goals file (``config/goals/<arena>.yaml``) lists poses for a navigation stack to reach:

.. code-block:: yaml

    goals: [{x: 1.5, y: 1.0, yaw: 90}]                   # m, m, degrees

With an arena, the loaders check every point lies inside the walls at least ``ROBOT_RADIUS``
from every wall and obstacle, and every route segment keeps that clearance too.
"""

import dataclasses as dc
import math
from pathlib import Path

import numpy as np

from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from drake_sim.worlds.arena import (
    ROBOT_RADIUS,
    Arena,
    arena_footprints,
    check_position,
)
from drake_sim.worlds.footprints import clearance

SEGMENT_CHECK_STEP = 0.01
"""m: how finely a route's segments are sampled when checking their clearance."""


@dc.dataclass
class Route:
    """Waypoints driven in order from the arena's start."""

    waypoints: list[list[float]] = dc.field(default_factory=list)  # [[x, y], ...] m in W.

    def path(self, start_xy) -> np.ndarray:
        """Returns the (n + 1, 2) polyline (m, W): ``start_xy`` then the waypoints."""
        return np.vstack([np.asarray(start_xy, dtype=float)[:2], np.asarray(self.waypoints)])

    def length(self, start_xy) -> float:
        """Returns the route's length (m) from ``start_xy``."""
        return float(np.sum(np.linalg.norm(np.diff(self.path(start_xy), axis=0), axis=1)))

    def sample(self, start_xy, spacing: float) -> np.ndarray:
        """Returns (m, 2) points (m, W) along the route from ``start_xy``, at most ``spacing``
        apart on every segment, including every waypoint."""
        path = self.path(start_xy)
        points = [path[:1]]
        for a, b in zip(path[:-1], path[1:], strict=True):
            n = max(1, math.ceil(float(np.linalg.norm(b - a)) / spacing))
            points.append(a + (b - a) * (np.arange(1, n + 1)[:, None] / n))
        return np.vstack(points)


@dc.dataclass
class Goal:
    """A pose to reach."""

    x: float = math.nan  # m, in W.
    y: float = math.nan  # m, in W.
    yaw: float = 0.0  # degrees, counter-clockwise from W's x axis.

    def pose(self) -> tuple[float, float, float]:
        """Returns (x m, y m, yaw rad)."""
        return self.x, self.y, math.radians(self.yaw)


@dc.dataclass
class _GoalsFile:
    goals: list[Goal] = dc.field(default_factory=list)


def load_route(filename: Path | str, arena: Arena | None = None) -> Route:
    """Loads and checks a route file (against ``arena`` when given).

    Raises:
        ConfigError: naming the file and ``waypoints[i]``, for a malformed file, an unknown
            key, no waypoints, a waypoint that is not two finite numbers, or (with ``arena``)
            one outside the walls or closer than ``ROBOT_RADIUS`` to a wall or obstacle, or a
            segment that passes closer than that.
    """
    route = load_typed(Route, filename=filename)
    return check_route(route, arena, str(filename))


def check_route(route: Route, arena: Arena | None = None, where: str = "route") -> Route:
    """Returns ``route`` if valid (see ``load_route``); raises ``ConfigError`` otherwise."""
    if not route.waypoints:
        raise ConfigError(f"{where}: 'waypoints' is empty; a route needs at least one")
    for i, p in enumerate(route.waypoints):
        if len(p) != 2:
            raise ConfigError(f"{where}: 'waypoints[{i}]' must be [x, y], got {len(p)} numbers")
        if arena is not None:
            check_position(arena, p, where, f"waypoints[{i}]")
    if arena is not None:
        path = route.path(arena.start_pose()[:2])
        footprints = arena_footprints(arena)
        for i, (a, b) in enumerate(zip(path[:-1], path[1:], strict=True)):
            n = max(1, math.ceil(float(np.linalg.norm(b - a)) / SEGMENT_CHECK_STEP))
            points = a + (b - a) * (np.arange(n + 1)[:, None] / n)
            for footprint in footprints:
                d = footprint.signed_distance(points)
                if d.min() < ROBOT_RADIUS:
                    q = points[int(np.argmin(d))]
                    origin = "the start" if i == 0 else f"waypoints[{i - 1}]"
                    raise ConfigError(
                        f"{where}: 'waypoints[{i}]': the segment from {origin} passes "
                        f"{max(float(d.min()), 0.0):.3f} m from '{footprint.name}' at "
                        f"({q[0]:.2f}, {q[1]:.2f}) (the robot needs {ROBOT_RADIUS} m)"
                    )
    return route


def load_goals(filename: Path | str, arena: Arena | None = None) -> list[Goal]:
    """Loads and checks a goals file (against ``arena`` when given).

    Raises:
        ConfigError: naming the file and ``goals[i]``, for a malformed file, an unknown or
            missing key, no goals, a non-finite number, or (with ``arena``) a goal outside
            the walls or closer than ``ROBOT_RADIUS`` to a wall or obstacle.
    """
    where = str(filename)
    goals = load_typed(_GoalsFile, filename=filename).goals
    if not goals:
        raise ConfigError(f"{where}: 'goals' is empty; give at least one goal")
    for i, goal in enumerate(goals):
        for key in ("x", "y"):
            if math.isnan(getattr(goal, key)):
                raise ConfigError(f"{where}: missing key 'goals[{i}].{key}'")
        if arena is not None:
            check_position(arena, (goal.x, goal.y), where, f"goals[{i}]")
    return goals


def default_route_file(arena_path: Path | str) -> Path:
    """Returns ``config/routes/<arena stem>.yaml``: where the shipped route for an arena file
    is (it may not exist for an arena that is not shipped)."""
    return config_dir() / "routes" / f"{Path(arena_path).stem}.yaml"


def default_goals_file(arena_path: Path | str) -> Path:
    """Returns ``config/goals/<arena stem>.yaml``: where the shipped goals for an arena file
    are (it may not exist for an arena that is not shipped)."""
    return config_dir() / "goals" / f"{Path(arena_path).stem}.yaml"


def route_clearance(route: Route, arena: Arena, spacing: float = SEGMENT_CHECK_STEP) -> float:
    """Returns the smallest distance (m) from the route (from the arena's start) to any wall or
    obstacle."""
    points = route.sample(arena.start_pose()[:2], spacing)
    return float(clearance(arena_footprints(arena), points).min())


def random_goals(
    arena: Arena, count: int, seed: int, *, margin: float = 0.4, spacing: float = 1.0
) -> list[np.ndarray]:
    """``count`` goals ``[x, y, yaw]`` (m, m, rad) drawn uniformly in ``arena`` (seeded), each
    at least ``margin`` m from every wall and obstacle and ``spacing`` m from the one before
    (the first from the start). Not every one need be reachable from the start (an enclosed
    pocket would not be); the shipped arenas have none."""
    footprints = arena_footprints(arena)
    rng = np.random.default_rng(seed)
    half = 0.5 * np.asarray(arena.size, dtype=float)
    goals, previous = [], np.asarray(arena.start_pose()[:2])
    for _ in range(10_000 * count):
        if len(goals) == count:
            break
        xy = rng.uniform(-half, half)
        if clearance(footprints, xy[None])[0] >= margin and math.dist(xy, previous) >= spacing:
            goals.append(np.array([*xy, rng.uniform(-math.pi, math.pi)]))
            previous = xy
    if len(goals) < count:
        raise ValueError(f"found only {len(goals)} of {count} goals with that margin")
    return goals
