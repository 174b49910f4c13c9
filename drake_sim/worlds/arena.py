"""Walled arenas for the lidar robot: the YAML schema, its checks, the 2D footprints of the
walls and obstacles, and the ground-truth occupancy grid.

An arena (``config/arenas/*.yaml``, the contract in DESIGN.md) is a walled rectangle centred
on the world frame W's origin, with obstacles standing on the floor:

.. code-block:: yaml

    size: [6.0, 5.0]                  # m, the free interior: inner wall faces at +-size/2
    wall: {height: 0.3, thickness: 0.05}
    obstacles:
      - {box: {size: [0.4, 0.4, 0.3], position: [1.0, 0.5], yaw: 30}}   # m, degrees
      - {cylinder: {radius: 0.15, height: 0.3, position: [-1.2, 0.8]}}
      - {wall: {from: [0.0, -2.5], to: [0.0, 0.5]}}                       # an inner wall
    start: {x: -2.0, y: -1.5, yaw: 0}

Inner walls take the arena's ``wall.thickness`` and ``wall.height`` unless they give their own;
their footprint is the rectangle of that thickness around the segment, extended by half the
thickness past each end (square caps, so walls meeting at a corner close it). Every obstacle
may carry a ``name``. Box positions are centres (the box rests on the floor).

Every shape here is a ``Footprint`` (``drake_sim.worlds.footprints``): a rectangle (outer and
inner walls, boxes) or a circle (cylinders) in W's floor plane, with its height above the floor.
The same footprints make the SDF world (``arena_world``) and the ground-truth grid
(``arena_grid``), so the two agree exactly.
"""

import dataclasses as dc
import math
from pathlib import Path

import numpy as np
import yaml

from drake_sim.base.config import check_tree, load_typed, parse_yaml, read_text
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from drake_sim.base.resources import config_dir
from drake_sim.worlds.footprints import Footprint

ROBOT_RADIUS = 0.2
"""m: the clearance a start pose (and a route's waypoint) needs from every wall and obstacle."""
GRID_TOLERANCE = 1e-9
"""m: a grid cell whose centre is this close to a footprint counts as inside it."""


@dc.dataclass
class WallSpec:
    """The outer walls (and the default for inner walls)."""

    height: float = 0.3  # m, > 0.
    thickness: float = 0.05  # m, > 0.


@dc.dataclass
class BoxSpec:
    """A box standing on the floor."""

    size: list[float] = dc.field(default_factory=list)  # [sx, sy, sz] m, each > 0.
    position: list[float] = dc.field(default_factory=list)  # [x, y] m, its centre in W.
    yaw: float = 0.0  # degrees, about W's z axis.


@dc.dataclass
class CylinderSpec:
    """An upright cylinder standing on the floor."""

    radius: float = math.nan  # m, > 0.
    height: float = math.nan  # m, > 0.
    position: list[float] = dc.field(default_factory=list)  # [x, y] m, its axis in W.


@dc.dataclass
class InnerWallSpec:
    """A wall segment inside the arena; the key ``from`` in the file is ``from_`` here."""

    from_: list[float] = dc.field(default_factory=list)  # [x, y] m, one end of its centreline.
    to: list[float] = dc.field(default_factory=list)  # [x, y] m, the other end.
    height: float | None = None  # m, > 0; default: the arena's wall height.
    thickness: float | None = None  # m, > 0; default: the arena's wall thickness.


@dc.dataclass
class ObstacleSpec:
    """One obstacle: exactly one of ``box``, ``cylinder`` and ``wall``."""

    box: BoxSpec | None = None
    cylinder: CylinderSpec | None = None
    wall: InnerWallSpec | None = None
    name: str = ""  # Optional; default "obstacle_<index>".


@dc.dataclass
class StartSpec:
    """The robot's start pose in W."""

    x: float = math.nan  # m.
    y: float = math.nan  # m.
    yaw: float = 0.0  # degrees, counter-clockwise from W's x axis.


@dc.dataclass
class Arena:
    """A walled arena: ``size`` is the free interior, centred on W's origin."""

    size: list[float] = dc.field(default_factory=list)  # [sx, sy] m, each > 0.
    wall: WallSpec = dc.field(default_factory=WallSpec)
    obstacles: list[ObstacleSpec] = dc.field(default_factory=list)
    start: StartSpec = dc.field(default_factory=StartSpec)

    def start_pose(self) -> tuple[float, float, float]:
        """Returns the start pose (x m, y m, yaw rad) in W."""
        return self.start.x, self.start.y, math.radians(self.start.yaw)


def load_arena(filename: Path | str) -> Arena:
    """Loads and checks an arena file.

    Raises:
        ConfigError: naming the file and the key, for a missing or malformed file, an unknown or
            missing key, a non-finite number, a non-positive size, an obstacle that is not
            exactly one shape or reaches outside the walls, a zero-length inner wall, or a start
            outside the walls or within ``ROBOT_RADIUS`` of a wall or obstacle.
    """
    where = str(filename)
    tree = parse_yaml(read_text(filename, "arena file"), where)
    if tree is None:
        tree = {}
    if not isinstance(tree, dict):
        raise ConfigError(f"{where}: expected a mapping of keys, got {type(tree).__name__}")
    if tree.get("obstacles", []) is None:
        tree["obstacles"] = []
    obstacles = tree.get("obstacles")
    for item in obstacles if isinstance(obstacles, list) else []:
        wall = item.get("wall") if isinstance(item, dict) else None
        if isinstance(wall, dict):
            if "from_" in wall:
                raise ConfigError(f"{where}: unknown key 'from_' in an inner wall (use 'from')")
            if "from" in wall:
                wall["from_"] = wall.pop("from")
    try:
        check_tree(Arena, tree, where)
        arena = load_typed(Arena, data=yaml.safe_dump(tree), where=where)
    except ConfigError as e:
        raise ConfigError(str(e).replace("from_", "from")) from None
    return check_arena(arena, where)


def shipped_arenas() -> list[Path]:
    """Returns the arena files shipped in ``config/arenas/``, sorted by name."""
    return sorted((config_dir() / "arenas").glob("*.yaml"))


def check_arena(arena: Arena, where: str = "arena") -> Arena:
    """Returns ``arena`` if it is valid; raises ``ConfigError`` naming ``where`` and the key."""
    _check_list(arena.size, 2, where, "size", positive=True)
    _check_positive(arena.wall.height, where, "wall.height")
    _check_positive(arena.wall.thickness, where, "wall.thickness")
    lo, hi = arena_bounds(arena)
    for i, obstacle in enumerate(arena.obstacles):
        key = f"obstacles[{i}]"
        shapes = [k for k in ("box", "cylinder", "wall") if getattr(obstacle, k) is not None]
        if len(shapes) != 1:
            raise ConfigError(
                f"{where}: '{key}' must have exactly one of 'box', 'cylinder' and 'wall'"
                f" (has {len(shapes)})"
            )
        key = f"{key}.{shapes[0]}"
        if obstacle.box is not None:
            _check_list(obstacle.box.size, 3, where, f"{key}.size", positive=True)
            _check_list(obstacle.box.position, 2, where, f"{key}.position")
        elif obstacle.cylinder is not None:
            _check_positive(obstacle.cylinder.radius, where, f"{key}.radius")
            _check_positive(obstacle.cylinder.height, where, f"{key}.height")
            _check_list(obstacle.cylinder.position, 2, where, f"{key}.position")
        else:
            wall = obstacle.wall
            _check_list(wall.from_, 2, where, f"{key}.from")
            _check_list(wall.to, 2, where, f"{key}.to")
            for name in ("height", "thickness"):
                if getattr(wall, name) is not None:
                    _check_positive(getattr(wall, name), where, f"{key}.{name}")
            if math.dist(wall.from_, wall.to) == 0:
                raise ConfigError(f"{where}: '{key}': zero-length inner wall (from == to)")
            for end in ("from", "to"):
                p = wall.from_ if end == "from" else wall.to
                if not _inside(p, lo, hi):
                    raise ConfigError(f"{where}: '{key}.{end}': {_xy(p)} lies outside the walls")
        footprint = _obstacle_footprint(arena, obstacle, i)
        pad = arena.wall.thickness if obstacle.wall is not None else 0.0
        corners = footprint.corners()
        bad = [p for p in corners if not _inside(p, lo - pad, hi + pad)]
        if bad:
            position = obstacle.wall.from_ if obstacle.wall else footprint.centre
            what = "position" if obstacle.wall is None else "from"
            raise ConfigError(
                f"{where}: '{key}.{what}': {_xy(position)} puts it outside the walls "
                f"(it reaches {_xy(bad[0])}; the inside is x in [{lo[0]:g}, {hi[0]:g}], "
                f"y in [{lo[1]:g}, {hi[1]:g}])"
            )
    footprints = arena_footprints(arena)
    seen = {"ground", *(f.name for f in footprints[:4])}
    for i, footprint in enumerate(footprints[4:]):
        if footprint.name in seen:
            raise ConfigError(
                f"{where}: 'obstacles[{i}].name': {footprint.name!r} is taken (names must be "
                "unique and not 'ground' or an outer wall's)"
            )
        seen.add(footprint.name)
    for name in ("x", "y"):
        if math.isnan(getattr(arena.start, name)):
            raise ConfigError(f"{where}: missing key 'start.{name}'")
    check_position(arena, (arena.start.x, arena.start.y), where, "start")
    return arena


def check_position(arena: Arena, p_WR, where: str, key: str) -> None:
    """Raises ``ConfigError`` (naming ``where`` and ``key``) unless the robot's position
    ``p_WR`` (x, y m) lies inside the walls at least ``ROBOT_RADIUS`` from every footprint."""
    lo, hi = arena_bounds(arena)
    if not _inside(p_WR, lo, hi):
        raise ConfigError(f"{where}: '{key}': {_xy(p_WR)} lies outside the walls")
    for footprint in arena_footprints(arena):
        distance = float(footprint.signed_distance(np.asarray(p_WR, dtype=float)[:2]))
        if distance < ROBOT_RADIUS:
            place = "inside" if distance <= 0 else f"{distance:.3f} m from"
            raise ConfigError(
                f"{where}: '{key}': {_xy(p_WR)} is {place} '{footprint.name}' (the robot needs "
                f"{ROBOT_RADIUS} m)"
            )


def _check_positive(value: float, where: str, name: str) -> None:
    if math.isnan(value):
        raise ConfigError(f"{where}: missing key '{name}'")
    if not (math.isfinite(value) and value > 0):
        raise ConfigError(f"{where}: '{name}' must be positive, got {value!r}")


def _check_list(values: list, n: int, where: str, name: str, positive: bool = False) -> None:
    if not values:
        raise ConfigError(f"{where}: missing key '{name}'")
    if len(values) != n:
        raise ConfigError(f"{where}: '{name}' must have {n} numbers, got {len(values)}")
    for k, value in enumerate(values):
        if not math.isfinite(value):
            raise ConfigError(f"{where}: '{name}[{k}]' must be finite, got {value!r}")
        if positive and value <= 0:
            raise ConfigError(f"{where}: '{name}[{k}]' must be positive, got {value!r}")


def _inside(p, lo, hi, tol: float = 1e-9) -> bool:
    return bool(np.all(np.asarray(p) >= lo - tol) and np.all(np.asarray(p) <= hi + tol))


def _xy(p) -> str:
    return f"({float(p[0]):g}, {float(p[1]):g})"


def arena_bounds(arena: Arena, *, walls: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Returns the lower and upper (x, y) corners (m, W) of the free interior, or with
    ``walls=True`` of the outer walls' outer boundary."""
    half = 0.5 * np.asarray(arena.size, dtype=float)
    if walls:
        half = half + arena.wall.thickness
    return -half, half


def _obstacle_footprint(arena: Arena, obstacle: ObstacleSpec, index: int) -> Footprint:
    name = obstacle.name or f"obstacle_{index}"
    if obstacle.box is not None:
        sx, sy, sz = obstacle.box.size
        return Footprint(
            "box",
            name,
            _pair(obstacle.box.position),
            (sx / 2, sy / 2),
            math.radians(obstacle.box.yaw),
            0.0,
            sz,
        )
    if obstacle.cylinder is not None:
        r = obstacle.cylinder.radius
        return Footprint(
            "cylinder",
            name,
            _pair(obstacle.cylinder.position),
            (r, r),
            0.0,
            r,
            obstacle.cylinder.height,
        )
    wall = obstacle.wall
    t = wall.thickness if wall.thickness is not None else arena.wall.thickness
    height = wall.height if wall.height is not None else arena.wall.height
    a, b = np.asarray(wall.from_, dtype=float), np.asarray(wall.to, dtype=float)
    length = float(np.linalg.norm(b - a))
    yaw = math.atan2(b[1] - a[1], b[0] - a[0])
    centre = (float(a[0] + b[0]) / 2, float(a[1] + b[1]) / 2)
    return Footprint("wall", name, centre, ((length + t) / 2, t / 2), yaw, 0.0, height)


def _pair(values) -> tuple[float, float]:
    return float(values[0]), float(values[1])


def arena_footprints(arena: Arena, height: float | None = None) -> list[Footprint]:
    """Returns the footprints of the four outer walls (named ``wall_north``, ``wall_south``,
    ``wall_east``, ``wall_west``; north and south span the corners) and of every obstacle in
    file order; with ``height`` (m), only those at least that tall (what a lidar scanning that
    high above the floor sees)."""
    sx, sy = (0.5 * v for v in arena.size)
    t, h = arena.wall.thickness, arena.wall.height
    shapes = [
        Footprint("wall", "wall_north", (0.0, sy + t / 2), (sx + t, t / 2), 0.0, 0.0, h),
        Footprint("wall", "wall_south", (0.0, -sy - t / 2), (sx + t, t / 2), 0.0, 0.0, h),
        Footprint("wall", "wall_east", (sx + t / 2, 0.0), (t / 2, sy), 0.0, 0.0, h),
        Footprint("wall", "wall_west", (-sx - t / 2, 0.0), (t / 2, sy), 0.0, 0.0, h),
    ]
    shapes += [_obstacle_footprint(arena, o, i) for i, o in enumerate(arena.obstacles)]
    return [f for f in shapes if height is None or f.height >= height]


def arena_grid(arena: Arena, resolution: float = 0.05, *, height: float | None = None):
    """Returns the ground-truth ``OccupancyMap`` of ``arena`` at ``resolution`` (m/cell).

    The grid covers the outer walls' outer boundary plus one cell on every side, centred on W's
    origin (origin yaw 0). A cell whose centre lies inside a footprint (or within
    ``GRID_TOLERANCE`` of it, so that a centre on a face counts as inside on any machine; with
    ``height``, only footprints at least that tall) is ``OCCUPIED``; other cells inside the
    outer walls' outer boundary are ``FREE`` and the rest ``UNKNOWN``.
    """
    if not (math.isfinite(resolution) and resolution > 0):
        raise ConfigError(f"arena_grid: 'resolution' must be positive, got {resolution!r}")
    lo, hi = arena_bounds(arena, walls=True)
    cols, rows = (int(math.ceil((hi[k] - lo[k]) / resolution - 1e-9)) + 2 for k in range(2))
    x0, y0 = -0.5 * cols * resolution, -0.5 * rows * resolution
    xs = x0 + (np.arange(cols) + 0.5) * resolution
    ys = y0 + (np.arange(rows) + 0.5) * resolution
    inside = (np.abs(ys)[:, None] <= hi[1] + GRID_TOLERANCE) & (
        np.abs(xs)[None, :] <= hi[0] + GRID_TOLERANCE
    )
    cells = np.where(inside, FREE, UNKNOWN).astype(np.int8)
    for footprint in arena_footprints(arena, height):
        corners = footprint.corners()
        c0, c1 = np.searchsorted(xs, [corners[:, 0].min() - 1e-9, corners[:, 0].max() + 1e-9])
        r0, r1 = np.searchsorted(ys, [corners[:, 1].min() - 1e-9, corners[:, 1].max() + 1e-9])
        if c1 <= c0 or r1 <= r0:
            continue
        gx, gy = np.meshgrid(xs[c0:c1], ys[r0:r1])
        hit = footprint.signed_distance(np.stack([gx, gy], axis=-1)) <= GRID_TOLERANCE
        window = cells[r0:r1, c0:c1]
        window[hit & (window != UNKNOWN)] = OCCUPIED
    return OccupancyMap(cells=cells, resolution=float(resolution), origin=(x0, y0, 0.0))
