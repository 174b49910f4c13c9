"""Exhaustive scan-to-map search over a window of poses, by branch and bound on two levels.

Olson's correlative scan matching ("Real-time correlative scan matching", ICRA 2009) and
Cartographer's loop closure (Hess et al., ICRA 2016) score every pose of a window: the mean of
a lookup table (here a likelihood field, 1 on the map's hits, falling off with the distance)
at the scan's end points. Done naively that is millions of poses. A coarse table whose cell
(i, j) holds the maximum of the fine table over the ``block`` x ``block`` cells from (i, j)
up bounds the score of every fine translation in that block, so blocks are visited best first
and a block whose bound is below the best fine score found so far is skipped: the result is
the exhaustive search's, exactly, at a fraction of the cost (Cartographer uses more levels;
two were enough for the windows here, measured in the tests).

The answer is on the table's grid (the cell size and ``yaw_step``); ``scan_matcher.match_scan``
refines it.
"""

import dataclasses as dc
import math

import numba
import numpy as np
from scipy import ndimage


@dc.dataclass
class SearchTable:
    """A likelihood field and its block maxima.

    Attributes:
        fine: (rows, cols) values in [0, 1] at cells of ``resolution``; row index grows with y.
        coarse: (rows, cols) the maximum of ``fine`` over [i, i + block) x [j, j + block).
        resolution: m per cell.
        origin: (x, y) of the lower-left corner of cell [0, 0], m.
        block: fine cells per coarse block side.
    """

    fine: np.ndarray
    coarse: np.ndarray
    resolution: float
    origin: tuple[float, float]
    block: int


def make_table(
    points: np.ndarray, resolution: float, *, sigma: float, margin: float, block: int = 8
) -> SearchTable:
    """The table for hits at world ``points`` (n, 2): exp(-d^2 / (2 sigma^2)) with d the
    distance from a cell's centre to the nearest cell holding a hit, over the points' box
    grown by ``margin`` m on every side."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(points) == 0:
        raise ValueError("a search table needs at least one point")
    low = points.min(0) - margin
    shape = np.ceil((points.max(0) + margin - low) / resolution).astype(int) + 1
    cols, rows = (int(v) for v in shape)
    cells = np.floor((points - low) / resolution).astype(int)
    occupied = np.zeros((rows, cols), bool)
    occupied[cells[:, 1], cells[:, 0]] = True
    distance = ndimage.distance_transform_edt(~occupied) * resolution
    fine = np.exp(-0.5 * (distance / sigma) ** 2).astype(np.float32)
    # maximum over [i, i + block): a filter of that size, its window shifted to start at i.
    coarse = ndimage.maximum_filter(
        fine, size=block, mode="constant", cval=0.0, origin=-(block // 2)
    )
    return SearchTable(fine, coarse, float(resolution), (float(low[0]), float(low[1])), block)


def occupied_points(log_odds: np.ndarray, resolution: float, origin, low, high) -> np.ndarray:
    """(n, 2) the centres of the cells with positive ``log_odds`` (a ``LogOddsGrid``'s array:
    row index grows with y, cell [0, 0]'s corner at ``origin``) inside the box [low, high]."""
    first = np.floor((np.asarray(low, float) - origin) / resolution).astype(int)
    last = np.ceil((np.asarray(high, float) - origin) / resolution).astype(int)
    rows, cols = log_odds.shape
    c0, r0 = (max(0, int(v)) for v in first)
    c1, r1 = min(cols, int(last[0])), min(rows, int(last[1]))
    if c1 <= c0 or r1 <= r0:
        return np.zeros((0, 2))
    r, c = np.nonzero(log_odds[r0:r1, c0:c1] > 0)
    return np.column_stack(
        [origin[0] + (c + c0 + 0.5) * resolution, origin[1] + (r + r0 + 0.5) * resolution]
    )


@dc.dataclass
class SearchResult:
    """The best pose of the window and its score (mean table value of the points)."""

    pose: np.ndarray
    score: float


def search(
    table: SearchTable,
    points: np.ndarray,
    center,
    *,
    window_xy: float,
    window_yaw: float,
    yaw_step: float,
) -> SearchResult:
    """The pose within ``window_xy`` m (each axis) and ``window_yaw`` rad of ``center``
    ([x, y, yaw], world) that puts the base-frame ``points`` (n, 2) on the best-scoring cells;
    translations on the table's grid, yaws at multiples of ``yaw_step`` from the centre's."""
    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
    if len(points) == 0:
        return SearchResult(np.array(center, dtype=float), 0.0)
    yaws = center[2] + yaw_step * np.arange(
        -math.floor(window_yaw / yaw_step), math.floor(window_yaw / yaw_step) + 1
    )
    steps = math.floor(window_xy / table.resolution)
    best = _search(
        table.fine,
        table.coarse,
        table.block,
        table.origin[0],
        table.origin[1],
        table.resolution,
        points,
        float(center[0]),
        float(center[1]),
        yaws,
        steps,
    )
    k, dx, dy, score = best
    pose = np.array(
        [center[0] + dx * table.resolution, center[1] + dy * table.resolution, yaws[int(k)]]
    )
    return SearchResult(pose, float(score))


def ambiguous(
    table: SearchTable, points, pose, score: float, *, distance: float, max_ratio: float,
    yaw_step: float,
) -> bool:  # fmt: skip
    """Whether a pose between ``distance`` and three times that from ``pose``, along either of
    the ``points``' principal axes, scores above ``max_ratio`` times ``score``: four small
    searches, each in a square window (half side ``distance`` / sqrt 2, so that no pose of it
    is nearer than that) centred twice that distance away, with yaws ``yaw_step`` either side.
    A corridor seen end-on matches along its length: a pose found there is a guess."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    centred = points - points.mean(0)
    _, vectors = np.linalg.eigh(centred.T @ centred)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    for direction in (np.array([[c, -s], [s, c]]) @ vectors).T:  # the axes, in the world
        for sign in (-1.0, 1.0):
            centre = np.array(pose, dtype=float)
            centre[:2] += sign * 2.0 * distance * direction
            other = search(
                table, points, centre, window_xy=distance / math.sqrt(2.0), window_yaw=yaw_step,
                yaw_step=yaw_step,
            )  # fmt: skip
            if other.score > max_ratio * score:
                return True
    return False


@numba.njit(cache=True)
def _cells(origin_x, origin_y, resolution, points, x, y, yaw):
    """Integer cells (column, row) of the points placed at (x, y, yaw)."""
    c, s = math.cos(yaw), math.sin(yaw)
    n = points.shape[0]
    out = np.empty((n, 2), np.int64)
    for p in range(n):
        wx = x + c * points[p, 0] - s * points[p, 1]
        wy = y + s * points[p, 0] + c * points[p, 1]
        out[p, 0] = int(math.floor((wx - origin_x) / resolution))
        out[p, 1] = int(math.floor((wy - origin_y) / resolution))
    return out


@numba.njit(cache=True)
def _score(table, cells, dx, dy):
    rows, cols = table.shape
    total = 0.0
    for p in range(cells.shape[0]):
        i = cells[p, 1] + dy
        j = cells[p, 0] + dx
        if 0 <= i < rows and 0 <= j < cols:
            total += table[i, j]
    return total / cells.shape[0]


@numba.njit(cache=True)
def _search(fine, coarse, block, origin_x, origin_y, resolution, points, x, y, yaws, steps):
    """(yaw index, dx cells, dy cells, score) of the best pose (module docstring)."""
    blocks = (2 * steps) // block + 1
    n_yaw = yaws.shape[0]
    bounds = np.empty(n_yaw * blocks * blocks)
    all_cells = np.empty((n_yaw, points.shape[0], 2), np.int64)
    for k in range(n_yaw):
        all_cells[k] = _cells(origin_x, origin_y, resolution, points, x, y, yaws[k])
        for bx in range(blocks):
            for by in range(blocks):
                bounds[(k * blocks + bx) * blocks + by] = _score(
                    coarse, all_cells[k], -steps + bx * block, -steps + by * block
                )
    order = np.argsort(-bounds)
    best = (0.0, 0.0, 0.0, -1.0)
    for index in order:
        if bounds[index] <= best[3]:
            break
        k = index // (blocks * blocks)
        bx = (index // blocks) % blocks
        by = index % blocks
        for a in range(block):
            dx = -steps + bx * block + a
            if dx > steps:
                break
            for b in range(block):
                dy = -steps + by * block + b
                if dy > steps:
                    break
                value = _score(fine, all_cells[k], dx, dy)
                if value > best[3]:
                    best = (float(k), float(dx), float(dy), value)
    return best
