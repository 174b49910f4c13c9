"""A scan matcher's map level (``scan_matcher.MatchMap``) kept up to date with the grid it was
made from, for a cost that follows what a map update changed rather than the size of the map
(``ScanMatchingSlam``'s pyramid; the cost per scan then stays flat as a building is mapped).

``update_level`` gives the same values as ``MatchMap.from_grid`` on the whole grid (no
smoothing; to 1e-12 wherever a point can weigh: the seen cells and their neighbours):

* likelihood field (``field`` > 0): the field is ``exp(-d^2 / (2 s^2))``, d the distance to the
  nearest occupied cell, that is the largest of one such bump per occupied cell; so a cell that
  became occupied stamps its bump (out to ``FIELD_REACH`` widths, where it is below 1e-13)
  into the level with a maximum, and only around cells that stopped being occupied (a wall
  seen through many times, a noisy return's cell cleared) is the field computed again, by a
  distance transform over their box in each ``TILE_CELLS`` tile and its reach;
* probabilities (``field`` 0): the changed box computed again;
* seen cells: each newly seen cell marks itself and its 8 neighbours (``from_grid``'s 3 x 3
  dilation);
* the level grows (by at least ``GROW_CELLS`` on the side it passes) when the seen cells come
  within ``margin`` of its edge; the field is then computed again along its old edges (the
  bumps of the cells near them reach past them).

One difference: while the grid has no occupied cell at all, ``from_grid`` gives 0.5 everywhere
and this 0 (no point scores either way then).
"""

import math

import numpy as np
from scipy import ndimage

from drake_sim.systems.estimation.occupancy_grid import LogOddsGrid
from drake_sim.systems.estimation.scan_matcher import MatchMap

FIELD_REACH = 8.0
"""Field widths: a bump reaches this far (exp(-8^2 / 2) = 1.3e-14: the field is 0 beyond)."""
GROW_CELLS = 64
"""Cells: a level grows by at least this much on the side it passes."""
TILE_CELLS = 32
"""Cells: the field is computed again around cells that stopped being occupied in tiles of
this side (their boxes), not over one box of them all."""
_NEIGHBOURS = np.array([(di, dj) for di in (-1, 0, 1) for dj in (-1, 0, 1)])


def update_level(
    level: MatchMap,
    grid: LogOddsGrid,
    changes: tuple[np.ndarray, np.ndarray, np.ndarray],
    changed_box,
    *,
    field: float = 0.0,
    margin: int = 4,
) -> MatchMap:
    """``level`` (made by ``MatchMap.from_grid(grid, field=field, margin=margin)``) brought up
    to date after a map update.

    Args:
        changes: ``grid.take_changes()`` (its ``track_changes`` on since ``level`` was made).
        changed_box: ``grid.take_changed_box()`` over the same updates.

    Returns:
        ``level``, changed in place, or a grown copy of it.
    """
    level, r0, c0 = _fitted(level, grid, margin, field)
    became, stopped, seen = changes
    if field > 0:
        _stamp(level, r0, c0, grid.shape[1], np.unique(became), field)
        if stopped.size:  # tile by tile: such cells lie scattered along the beams
            rows, cols = np.divmod(np.unique(stopped), grid.shape[1])
            tiles = np.unique(np.stack([rows // TILE_CELLS, cols // TILE_CELLS], -1), axis=0)
            for ti, tj in tiles:
                in_tile = (rows // TILE_CELLS == ti) & (cols // TILE_CELLS == tj)
                r, c = rows[in_tile], cols[in_tile]
                _recompute(level, r0, c0, grid, [r.min(), r.max(), c.min(), c.max()], field)
    elif changed_box is not None:
        _recompute(level, r0, c0, grid, changed_box, field)
    _mark_seen(level, r0, c0, grid.shape[1], seen)
    return level


def _fitted(level: MatchMap, grid: LogOddsGrid, margin: int, field: float):
    """(the level, grown if the seen cells pass its edge; its first row and column in the grid)."""
    res = grid.resolution
    r0 = round((level.origin[1] - grid.origin[1]) / res)
    c0 = round((level.origin[0] - grid.origin[0]) / res)
    rows, cols = level.values.shape[0] - 2, level.values.shape[1] - 2
    need = _box_around(grid.known_box, margin, grid.shape)
    if need[0] >= r0 and need[1] <= r0 + rows and need[2] >= c0 and need[3] <= c0 + cols:
        return level, r0, c0
    lo_r = max(min(need[0] - GROW_CELLS, r0), 0)
    hi_r = min(max(need[1] + GROW_CELLS, r0 + rows), grid.shape[0])
    lo_c = max(min(need[2] - GROW_CELLS, c0), 0)
    hi_c = min(max(need[3] + GROW_CELLS, c0 + cols), grid.shape[1])
    values = np.full((hi_r - lo_r, hi_c - lo_c), 0.0 if field > 0 else 0.5)
    known = np.zeros(values.shape, bool)
    inner = (slice(r0 - lo_r, r0 - lo_r + rows), slice(c0 - lo_c, c0 - lo_c + cols))
    values[inner] = level.values[1:-1, 1:-1]
    known[inner] = level.known[1:-1, 1:-1]
    origin = (grid.origin[0] + lo_c * res, grid.origin[1] + lo_r * res)
    grown = MatchMap(values, res, origin, known)
    if field > 0:  # the bumps of cells near the old edge reach into the new cells
        last_r, last_c = r0 + rows - 1, c0 + cols - 1
        edges = [[r0, r0, c0, last_c], [last_r, last_r, c0, last_c]]
        edges += [[r0, last_r, c0, c0], [r0, last_r, last_c, last_c]]
        for edge in edges:
            _recompute(grown, lo_r, lo_c, grid, edge, field)
    return grown, lo_r, lo_c


def _stamp(level: MatchMap, r0: int, c0: int, grid_cols: int, cells, field: float) -> None:
    """Raises the level to each of ``cells``' bumps (flat grid indices)."""
    if cells.size == 0:
        return
    reach = max(1, math.ceil(FIELD_REACH * field))
    di, dj = np.mgrid[-reach : reach + 1, -reach : reach + 1]
    disk = di**2 + dj**2 <= reach**2
    di, dj = di[disk], dj[disk]
    bump = np.exp(-0.5 * (di**2 + dj**2) / field**2)
    rows, cols = np.divmod(cells, grid_cols)
    i = (rows - r0 + 1)[:, None] + di[None, :]
    j = (cols - c0 + 1)[:, None] + dj[None, :]
    inside = (i >= 0) & (i < level.values.shape[0]) & (j >= 0) & (j < level.values.shape[1])
    values = np.broadcast_to(bump, i.shape)
    np.maximum.at(level.values, (i[inside], j[inside]), values[inside])


def _mark_seen(level: MatchMap, r0: int, c0: int, grid_cols: int, cells) -> None:
    """Marks ``cells`` (flat grid indices) and their 8 neighbours as seen."""
    if cells.size == 0:
        return
    rows, cols = np.divmod(cells, grid_cols)
    i = (rows - r0 + 1)[:, None] + _NEIGHBOURS[None, :, 0]
    j = (cols - c0 + 1)[:, None] + _NEIGHBOURS[None, :, 1]
    inside = (i >= 0) & (i < level.known.shape[0]) & (j >= 0) & (j < level.known.shape[1])
    level.known[i[inside], j[inside]] = True


def _recompute(level: MatchMap, r0: int, c0: int, grid: LogOddsGrid, box, field: float) -> None:
    """Computes the level again over ``box`` (inclusive grid rows and columns) and the field's
    reach around it, from the grid over that window and its reach."""
    rows, cols = level.values.shape[0] - 2, level.values.shape[1] - 2
    reach = max(1, math.ceil(FIELD_REACH * field)) if field > 0 else 1
    w = _box_around(box, reach, grid.shape)
    w = [max(w[0], r0), min(w[1], r0 + rows), max(w[2], c0), min(w[3], c0 + cols)]
    if w[0] >= w[1] or w[2] >= w[3]:
        return
    e = _box_around([w[0], w[1] - 1, w[2], w[3] - 1], reach, grid.shape)
    log_odds = grid.log_odds[e[0] : e[1], e[2] : e[3]]
    inner = (slice(w[0] - e[0], w[1] - e[0]), slice(w[2] - e[2], w[3] - e[2]))
    if field > 0:
        occupied = log_odds > 0
        if occupied.any():
            distance = ndimage.distance_transform_edt(~occupied)[inner]
            p = np.exp(-0.5 * (distance / field) ** 2)
        else:
            p = np.zeros((w[1] - w[0], w[3] - w[2]))
    else:
        p = 1.0 / (1.0 + np.exp(-log_odds[inner].astype(np.float64)))
    target = (slice(w[0] - r0 + 1, w[1] - r0 + 1), slice(w[2] - c0 + 1, w[3] - c0 + 1))
    level.values[target] = p


def _box_around(box, pad: int, shape) -> list[int]:
    """[row_lo, row_hi, col_lo, col_hi) (``hi`` excluded) of the inclusive box
    [row_min, row_max, col_min, col_max] with ``pad`` cells more each way, clipped to ``shape``
    (the whole grid for None)."""
    if box is None:
        return [0, shape[0], 0, shape[1]]
    return [
        max(box[0] - pad, 0),
        min(box[1] + pad + 1, shape[0]),
        max(box[2] - pad, 0),
        min(box[3] + pad + 1, shape[1]),
    ]
