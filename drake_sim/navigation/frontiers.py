"""Frontiers on a growing map, and the one to drive to next: explore_lite's method (m-explore,
Hörner 2016, after Yamauchi 1997) on this project's maps.

A frontier cell is a free cell with an unknown cell beside it (4-neighbours); frontier cells
that touch (8-neighbours) make one frontier, and frontiers shorter than ``min_frontier_size``
are noise (the gaps between far beams). The robot drives to a cell it can reach that sees the
frontier: a known free cell at least ``clearance`` from every occupied cell, joined to the
robot's cell by such cells, within ``approach`` of one of the frontier's cells. Each frontier
costs ``potential_scale`` per metre of the path there (the grid's shortest path, 8-connected)
less ``gain_scale`` per metre of frontier (what driving there may reveal); the cheapest one is
the next goal. The parts of frontiers the robot went to see and did not (its goal failed, or
was reached with the frontier still there) go on a blacklist: frontier cells within
``blacklist_radius`` of a blacklisted point are no longer frontier cells.

``find_frontiers`` is a pure function of the map, the robot's position and the blacklist (no
state); the exploring run (``drake_sim.runs.explore``) keeps the goal and the blacklist.
"""

import dataclasses as dc
import math

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap


@dc.dataclass
class FrontierConfig:
    """How frontiers are found and chosen (module docstring); metres and seconds."""

    min_frontier_size: float = 0.3  # m of frontier (its cells times the resolution)
    clearance: float = 0.3  # m from occupied cells, for the goal and the path to it
    approach: float = 0.6  # m: the goal is at most this far from one of its frontier's cells
    potential_scale: float = 1.0  # cost per m of path (explore_lite's potential_scale)
    gain_scale: float = 0.5  # cost per m of frontier (explore_lite's gain_scale)
    blacklist_radius: float = 0.4  # m around a blacklisted point where no frontier counts
    replan_period: float = 1.0  # s between choices of the goal
    progress_timeout: float = 20.0  # s without getting 0.1 m closer: the goal is blacklisted


def check_frontier_config(config: FrontierConfig, where: str = "exploration") -> None:
    """Raises ``ConfigError`` naming ``where`` and the first key out of range."""
    for field in dc.fields(config):
        value = getattr(config, field.name)
        if not (isinstance(value, int | float) and math.isfinite(value)):
            raise ConfigError(f"{where}: '{field.name}' must be a finite number, got {value!r}")
        positive = field.name in ("replan_period", "progress_timeout", "approach")
        if value < 0 or (positive and value == 0):
            rule = "positive" if positive else "at least 0"
            raise ConfigError(f"{where}: '{field.name}' must be {rule}, got {value}")


@dc.dataclass(frozen=True)
class Frontier:
    """One frontier: where to drive to see it, and what it costs."""

    goal: np.ndarray  # [x, y] m: the reachable cell chosen to see it from
    distance_m: float  # length of the grid path from the robot's cell to the goal
    size_m: float  # its cells times the resolution
    cost: float  # potential_scale * distance_m - gain_scale * size_m
    cells: np.ndarray  # (k, 2) x, y of its cells

    def seen_from_goal(self, config: FrontierConfig) -> np.ndarray:
        """Its cells the goal was chosen to see (within ``approach`` of the goal): what to
        blacklist when the goal did not reveal them."""
        return self.cells[np.hypot(*(self.cells - self.goal).T) <= config.approach + 1e-9]


def frontier_mask(occupancy_map: OccupancyMap) -> np.ndarray:
    """Free cells with an open unknown 4-neighbour: an unknown cell (or beyond the map) with no
    occupied cell among its 8 neighbours. The inside of an obstacle is never seen, and where
    its outline steps diagonally (a rotated box, a post) free cells touch it; such unknown cells
    lie beside the outline, and are no frontier."""
    occupied = np.pad(occupancy_map.occupied(), 1, constant_values=False)
    near_wall = ndimage.binary_dilation(occupied, structure=np.ones((3, 3), bool))
    unknown = np.pad(occupancy_map.unknown(), 1, constant_values=True) & ~near_wall
    beside = unknown[:-2, 1:-1] | unknown[2:, 1:-1] | unknown[1:-1, :-2] | unknown[1:-1, 2:]
    return occupancy_map.free() & beside


def find_frontiers(
    occupancy_map: OccupancyMap, robot_xy, config: FrontierConfig, blacklist=()
) -> list[Frontier]:
    """The frontiers the robot can reach from ``robot_xy`` on ``occupancy_map``, cheapest
    first (none: nothing left to explore from here). ``blacklist``: [x, y] points whose
    frontier cells within ``FrontierConfig.blacklist_radius`` do not count."""
    grid = occupancy_map
    resolution = grid.resolution
    frontier = frontier_mask(grid)
    xs, ys = grid.centres()
    blacklist = np.reshape(np.asarray(blacklist, dtype=float), (-1, 2))
    if len(blacklist) and frontier.any():
        gap, _ = cKDTree(blacklist).query(np.column_stack([xs[frontier], ys[frontier]]))
        frontier[frontier] = gap > config.blacklist_radius
    labels, count = ndimage.label(frontier, structure=np.ones((3, 3), bool))
    if count == 0:
        return []
    sizes = np.bincount(labels.ravel(), minlength=count + 1) * resolution
    wall_distance = ndimage.distance_transform_edt(~grid.occupied()) * resolution
    open_cells = grid.free() & (wall_distance >= config.clearance)
    distance = _path_lengths(open_cells, _robot_cell(grid, robot_xy, open_cells), resolution)
    # Each reachable cell within ``approach`` of a frontier sees the nearest one.
    to_frontier, (near_r, near_c) = ndimage.distance_transform_edt(~frontier, return_indices=True)
    sees = np.isfinite(distance) & (to_frontier * resolution <= config.approach)
    seen_label = labels[near_r, near_c]
    found = []
    for label in range(1, count + 1):
        if sizes[label] < config.min_frontier_size:
            continue
        rows, cols = np.nonzero(sees & (seen_label == label))
        if len(rows) == 0:
            continue  # nowhere reachable sees it
        best = np.argmin(distance[rows, cols])
        r, c = rows[best], cols[best]
        path = float(distance[r, c])
        cost = config.potential_scale * path - config.gain_scale * float(sizes[label])
        members = labels == label
        found.append(
            Frontier(
                goal=np.array([xs[r, c], ys[r, c]]),
                distance_m=path,
                size_m=float(sizes[label]),
                cost=cost,
                cells=np.column_stack([xs[members], ys[members]]),
            )
        )
    return sorted(found, key=lambda f: f.cost)


START_REACH = 1.0
"""m: the robot's own cell may be too near a wall to count as open, or not yet free; paths
start from the nearest open cell within this far of it (none further: it might be beyond a
wall)."""


def _robot_cell(grid: OccupancyMap, robot_xy, open_cells: np.ndarray) -> tuple[int, int] | None:
    """The open cell nearest the robot within ``START_REACH``; None when there is none."""
    rows, cols = np.nonzero(open_cells)
    if len(rows) == 0:
        return None
    r, c = (int(v[0]) for v in grid.cell_of(np.asarray(robot_xy, dtype=float)[None, :2]))
    squared = (rows - r) ** 2 + (cols - c) ** 2
    nearest = np.argmin(squared)
    if squared[nearest] * grid.resolution**2 > START_REACH**2:
        return None
    return int(rows[nearest]), int(cols[nearest])


def _path_lengths(open_cells: np.ndarray, start, resolution: float) -> np.ndarray:
    """Shortest 8-connected path lengths (m) from ``start`` over ``open_cells``; inf where
    there is none."""
    lengths = np.full(open_cells.shape, np.inf)
    if start is None:
        return lengths
    index = np.full(open_cells.shape, -1, dtype=np.int64)
    index[open_cells] = np.arange(int(open_cells.sum()))
    heads, tails, weights = [], [], []
    rows, cols = index.shape
    for dr, dc_, w in ((0, 1, 1.0), (1, 0, 1.0), (1, 1, math.sqrt(2)), (1, -1, math.sqrt(2))):
        a = index[: rows - dr, max(0, -dc_) : cols - max(0, dc_)]
        b = index[dr:, max(0, dc_) : cols - max(0, -dc_)]
        both = (a >= 0) & (b >= 0)
        heads.append(a[both])
        tails.append(b[both])
        weights.append(np.full(int(both.sum()), w * resolution))
    n = int(open_cells.sum())
    graph = coo_matrix(
        (np.concatenate(weights), (np.concatenate(heads), np.concatenate(tails))), shape=(n, n)
    ).tocsr()
    found = dijkstra(graph, directed=False, indices=int(index[start]))
    lengths[open_cells] = found
    return lengths
