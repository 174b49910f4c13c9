"""A world to simulate in from a map_server map: its occupied cells become walls.

``map_arena`` turns an ``OccupancyMap`` (``drake_sim.base.map_files.load_map``) into an
``Arena`` (``drake_sim.worlds.arena``), so everything that simulates in an arena (the lidar
robot's plant, the ground-truth grid, the start checks) simulates in the map's world too:

* every occupied cell (value >= ``occupied``, 65 %: map_server's ``occupied_thresh`` in
  percent) is covered by exactly one box of the map's cells, ``height`` tall: the cells are
  merged into rectangles (``occupied_rectangles``: runs of a row, then runs of the same columns
  in the rows below), so the lidar sees the walls exactly where the cells are, with a few
  boxes (nav2's 604 x 307 depot: ~1,300). Free and unknown cells are open floor.
* the boxes turn with the map's origin yaw about its origin, as map_server places the grid.
* the arena's own walls stand just outside the map (its ``size`` is the smallest rectangle
  centred on W's origin that holds the map and ``margin`` more), so nothing leaves the world.
* the robot starts at ``start`` (x, y m, yaw rad), which must lie on a free cell of the map and
  ``ROBOT_RADIUS`` from every box (``check_arena``).

The rectangles are cached by the map's content (``cache_dir()/map_worlds``): a large map is
merged once.
"""

from __future__ import annotations

import hashlib
import io
import math

import numpy as np

from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic
from drake_sim.base.map_files import FREE, OCCUPIED, OccupancyMap
from drake_sim.base.resources import cache_dir
from drake_sim.worlds.arena import (
    Arena,
    BoxSpec,
    ObstacleSpec,
    StartSpec,
    WallSpec,
    arena_grid,
    check_arena,
)

OCCUPIED_PERCENT = 65
"""A cell at least this occupied (%) is a wall: map_server's default ``occupied_thresh``."""
WALL_HEIGHT = 0.5
"""m: the walls' height (above any 2D lidar of a ground robot)."""
MARGIN = 0.5
"""m: the arena's walls stand this far outside the map at least."""


def occupied_rectangles(occupied: np.ndarray) -> np.ndarray:
    """Rectangles of cells that cover the True cells of ``occupied`` (rows, cols) exactly once:
    (K, 4) of [row, col, rows, cols]. Each row's runs of True cells are merged with the
    rectangle above that spans the same columns, so a wall along a column is one box."""
    occupied = np.asarray(occupied, dtype=bool)
    open_ = {}  # (col, cols) -> [row, col, rows, cols] still growing down
    done = []
    padded = np.zeros(occupied.shape[1] + 2, dtype=np.int8)
    for row in range(occupied.shape[0]):
        padded[1:-1] = occupied[row]
        edges = np.flatnonzero(np.diff(padded))
        runs = {(int(a), int(b - a)) for a, b in zip(edges[::2], edges[1::2], strict=True)}
        for key in list(open_):
            if key in runs:
                open_[key][2] += 1
            else:
                done.append(open_.pop(key))
        for key in runs - open_.keys():
            open_[key] = [row, key[0], 1, key[1]]
    done.extend(open_.values())
    return np.array(sorted(done), dtype=np.int64).reshape(-1, 4)


def cached_rectangles(occupancy_map: OccupancyMap, occupied: int = OCCUPIED_PERCENT) -> np.ndarray:
    """``occupied_rectangles`` of the map's cells at least ``occupied`` %, cached by content."""
    mask = np.asarray(occupancy_map.cells) >= occupied
    digest = hashlib.sha256(np.packbits(mask).tobytes() + repr(mask.shape).encode()).hexdigest()
    path = cache_dir() / "map_worlds" / f"{digest[:24]}.npy"
    if path.is_file():
        try:
            return np.load(path)
        except (OSError, ValueError):
            pass  # a damaged cache file is made again
    rectangles = occupied_rectangles(mask)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, _npy_bytes(rectangles))
    return rectangles


def _npy_bytes(array: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    np.save(buffer, array)
    return buffer.getvalue()


def map_arena(
    occupancy_map: OccupancyMap,
    start,
    *,
    height: float = WALL_HEIGHT,
    occupied: int = OCCUPIED_PERCENT,
    where: str = "map",
) -> Arena:
    """The arena a map describes, the robot at ``start`` (see the module).

    Args:
        occupancy_map: the map (its cells, resolution and origin).
        start: the robot's start, (x, y, yaw) in m, m, rad.
        height: the walls' height, m.
        occupied: the least cell value (%) that is a wall.
        where: names the map in errors.

    Raises:
        ConfigError: a start that is not finite, off the map, on a cell that is not free, or
            too close to a wall; a height that is not a positive number.
    """
    if not (math.isfinite(height) and height > 0):
        raise ConfigError(f"{where}: the walls' height must be a positive number of m")
    x, y, yaw = (float(v) for v in start)
    if not all(math.isfinite(v) for v in (x, y, yaw)):
        raise ConfigError(f"{where}: the start ({x}, {y}, {yaw}) is not finite")
    rows, cols = occupancy_map.cell_of(np.array([[x, y]]))
    if not occupancy_map.inside(rows, cols)[0]:
        raise ConfigError(f"{where}: the start ({x:g}, {y:g}) is outside the map")
    if occupancy_map.cells[rows[0], cols[0]] != FREE:
        raise ConfigError(f"{where}: the start ({x:g}, {y:g}) is not on a free cell of the map")
    res = occupancy_map.resolution
    ox, oy, oyaw = occupancy_map.origin
    c, s = math.cos(oyaw), math.sin(oyaw)
    obstacles = []
    for row, col, n_rows, n_cols in cached_rectangles(occupancy_map, occupied):
        u, v = (col + 0.5 * n_cols) * res, (row + 0.5 * n_rows) * res  # in the map's frame
        box = BoxSpec(
            size=[n_cols * res, n_rows * res, height],
            position=[ox + c * u - s * v, oy + s * u + c * v],
            yaw=math.degrees(oyaw),
        )
        obstacles.append(ObstacleSpec(box=box, name=f"cells_{row}_{col}"))
    rows_m, cols_m = occupancy_map.cells.shape[0] * res, occupancy_map.cells.shape[1] * res
    corners = np.array([[0, 0], [cols_m, 0], [0, rows_m], [cols_m, rows_m]], dtype=float)
    xs = ox + c * corners[:, 0] - s * corners[:, 1]
    ys = oy + s * corners[:, 0] + c * corners[:, 1]
    half = np.array([np.abs(xs).max(), np.abs(ys).max()]) + MARGIN
    arena = Arena(
        size=[2.0 * half[0], 2.0 * half[1]],
        wall=WallSpec(height=height, thickness=0.05),
        obstacles=obstacles,
        start=StartSpec(x=x, y=y, yaw=math.degrees(yaw)),
    )
    return check_arena(arena, where)


DISAGREE_FRACTION = 0.2
"""Of an arena's wall and obstacle cells, the share the map may call free before the map and
the arena are said not to describe the same place."""


def check_map_agrees(arena: Arena, occupancy_map: OccupancyMap, poses, where: str) -> None:
    """Raises ``ConfigError`` (one line naming ``where``) when ``occupancy_map`` does not
    describe ``arena``: the start (the first of ``poses``, (N, >=2) x, y) off the map's free
    cells, a goal (the others) off its known cells (a goal on a wall is an unreachable goal,
    not a disagreement), or more than ``DISAGREE_FRACTION`` of the arena's wall cells free in
    the map (one cell of tolerance: a wall cell counts when no map cell next to it is
    occupied)."""
    free = np.asarray(occupancy_map.cells) == FREE
    for k, pose in enumerate(np.asarray(poses, dtype=float).reshape(-1, np.shape(poses)[-1])):
        value = occupancy_map.values_at(occupancy_map.cells, pose[None, :2], outside=-2)[0]
        if value != FREE and (k == 0 or value < 0):
            what = "the start" if k == 0 else f"goal {k}"
            place = {-2: "outside the map", -1: "on an unknown cell"}.get(int(value), "on a wall")
            raise ConfigError(
                f"{where}: the map and the arena do not agree: {what} ({pose[0]:g}, "
                f"{pose[1]:g}) is {place} of the map"
            )
    truth = arena_grid(arena, occupancy_map.resolution)
    rows, cols = np.nonzero(truth.cells == OCCUPIED)
    if len(rows) == 0:
        return
    xy = truth.to_world(np.column_stack([cols + 0.5, rows + 0.5]))
    occupied = (np.asarray(occupancy_map.cells) >= OCCUPIED_PERCENT).astype(np.int8)
    near = np.zeros(len(xy), dtype=bool)
    step = occupancy_map.resolution
    for dx in (-step, 0.0, step):
        for dy in (-step, 0.0, step):
            near |= occupancy_map.values_at(occupied, xy + [dx, dy], outside=0) == 1
    in_free = occupancy_map.values_at(free.astype(np.int8), xy, outside=0) == 1
    share = float(np.mean(in_free & ~near))
    if share > DISAGREE_FRACTION:
        raise ConfigError(
            f"{where}: the map and the arena do not agree: {share:.0%} of the arena's wall "
            "cells are free in the map"
        )


def known_truth(truth: OccupancyMap, occupancy_map: OccupancyMap) -> OccupancyMap:
    """``truth`` (a ground-truth grid of the map's arena, ``arena_grid``) with its cells outside
    the map's known cells made unknown: what mapping the map's world can know (the floor beyond
    the map and under its unknown cells is open, but no one has mapped it)."""
    rows, cols = np.indices(truth.cells.shape)
    xy = truth.to_world(np.stack([cols + 0.5, rows + 0.5], axis=-1))
    known = occupancy_map.values_at(occupancy_map.cells, xy, outside=-1) >= 0
    cells = np.where(known, truth.cells, np.int8(-1)).astype(np.int8)
    return OccupancyMap(cells, truth.resolution, truth.origin)
