"""The global planner: shortest paths on a ``Costmap``, like ROS's ``global_planner``/navfn.

A* (or Dijkstra with ``use_astar: false``) over the cells, 8-connected. Entering a cell of cost
c costs ``neutral_cost + cost_factor * c`` per cell length (times sqrt(2) diagonally), so paths
keep away from obstacles as far as the inflation asks. A cell is impassable for the robot's
centre at ``lethal_cost`` (INSCRIBED) and above; unknown cells (NO_INFORMATION) are passable at
cost INSCRIBED - 1 when ``allow_unknown``. A diagonal step may not cut the corner of an
impassable cell. Cells within ``start_escape_radius`` of the start that are not LETHAL are
passable too (at cost INSCRIBED), so a robot standing close to a wall can leave it.

Goal tolerance, as navfn's: when the goal cell is impassable or unreachable, the path ends at
the reachable passable cell nearest the goal within ``tolerance``. The search is compiled with
numba (``cache=True``) and stops when the goal is reached; an unreachable goal costs one sweep
of the start's connected free space (a few ms on a 12 m x 9 m map at 0.05 m).

The cell path is then shortened: from each kept point, the farthest following point that can
be reached in a straight line is kept, where a straight line may only cross passable cells no
costlier than the costliest cell of the stretch of path it replaces (so shortcuts never come
closer to obstacles than the search's path did).
"""

import dataclasses as dc
import heapq
import math
import time

import numpy as np
from numba import njit

from drake_sim.base.errors import ConfigError
from drake_sim.navigation.costmap import INSCRIBED, LETHAL, NO_INFORMATION, Costmap

UNREACHABLE = "unreachable"
GOAL_IN_OBSTACLE = "goal in an obstacle"
START_IN_OBSTACLE = "start in an obstacle"
OUTSIDE_MAP = "outside the map"

_SQRT2 = math.sqrt(2.0)


@dc.dataclass
class GlobalPlannerConfig:
    """Options of the global planner (ROS global_planner / navfn names)."""

    tolerance: float = 0.2  # m, how far from an unreachable goal the path may end.
    use_astar: bool = True  # A* (else Dijkstra; same paths, more cells expanded).
    neutral_cost: float = 50.0  # Cost of crossing one free cell (> 0).
    # Added cost per unit of cell cost (>= 0). ROS global_planner's 3.0 made 3x detours around
    # a 0.7 m gap in the room arena (straight line at most cost 170); 1.0 keeps every path on
    # the shipped arenas within 1.12x a free straight line, with the same clearances.
    cost_factor: float = 1.0
    lethal_cost: int = 253  # Cells at or above this cost are impassable (1..254).
    allow_unknown: bool = True  # Plan through unknown cells (at cost INSCRIBED - 1).
    start_escape_radius: float = 0.15  # m, around the start, non-lethal cells are passable.
    simplify: bool = True  # Shorten the cell path with straight lines (see the module doc).


@dc.dataclass
class GlobalPath:
    """A global plan. On failure ``path`` is empty and ``message`` says why: "unreachable",
    "goal in an obstacle", "start in an obstacle" or "outside the map"."""

    success: bool
    path: np.ndarray  # (n, 2) m, world points from the start to the goal (or the tolerance).
    length_m: float  # m, the polyline's length.
    message: str = ""
    cost: float = math.inf  # The search's path cost (neutral_cost units per cell length).
    expanded: int = 0  # Cells the search expanded.
    planning_time_s: float = 0.0  # s, wall time of the whole call.


def check_global_planner_config(
    config: GlobalPlannerConfig, where: str = "global_planner", prefix: str = ""
) -> None:
    """Raises ``ConfigError`` naming ``where`` and the first out-of-range field of ``config``."""

    def fail(name: str, rule: str) -> None:
        raise ConfigError(
            f"{where}: '{prefix}{name}' must be {rule}, got {getattr(config, name)!r}"
        )

    for field in dc.fields(config):
        value = getattr(config, field.name)
        if field.name in ("use_astar", "allow_unknown", "simplify"):
            if not isinstance(value, bool):
                fail(field.name, "true or false")
        elif isinstance(value, bool) or not isinstance(value, int | float):
            fail(field.name, "a number")
        elif not math.isfinite(value):
            fail(field.name, "finite")
    if config.tolerance < 0:
        fail("tolerance", ">= 0")
    if config.neutral_cost <= 0:
        fail("neutral_cost", "> 0")
    if config.cost_factor < 0:
        fail("cost_factor", ">= 0")
    if not 1 <= config.lethal_cost <= LETHAL:
        fail("lethal_cost", f"in [1, {LETHAL}]")
    if config.start_escape_radius < 0:
        fail("start_escape_radius", ">= 0")


def traversal_costs(costmap: Costmap, config: GlobalPlannerConfig, start_xy=None) -> np.ndarray:
    """Returns the cost the search sees per cell (int32, the costmap's shape): -1 impassable,
    else the cell cost (unknown: INSCRIBED - 1; the start's escape cells: INSCRIBED)."""
    costs = costmap.costs
    eff = costs.astype(np.int32)
    unknown = costs == NO_INFORMATION
    eff[costs >= config.lethal_cost] = -1
    eff[unknown] = INSCRIBED - 1 if config.allow_unknown else -1
    if start_xy is not None:
        grid = costmap.to_grid(np.asarray(start_xy, dtype=float))
        span = int(math.ceil(config.start_escape_radius / costmap.resolution)) + 1
        row, col = int(math.floor(grid[1])), int(math.floor(grid[0]))
        r0, r1 = max(row - span, 0), min(row + span + 1, costs.shape[0])
        c0, c1 = max(col - span, 0), min(col + span + 1, costs.shape[1])
        if r0 >= r1 or c0 >= c1:  # a start off the costmap (a lost estimate): no escape
            return eff
        rr, cc = np.mgrid[r0:r1, c0:c1]
        near = np.hypot(cc + 0.5 - grid[0], rr + 0.5 - grid[1]) * costmap.resolution
        near_start = (near <= config.start_escape_radius) | ((rr == row) & (cc == col))
        escape = near_start & (costs[r0:r1, c0:c1] != LETHAL)
        window = eff[r0:r1, c0:c1]
        window[escape & (window < 0)] = INSCRIBED
    return eff


def plan_path(costmap: Costmap, start_xy, goal_xy, config: GlobalPlannerConfig | None = None):
    """Plans a path on ``costmap`` from ``start_xy`` to ``goal_xy`` (m, world).

    Returns:
        A ``GlobalPath``; on failure ``success`` is False and ``message`` says why.

    Raises:
        ConfigError: ``config`` is out of range.
    """
    begin = time.perf_counter()
    config = config if config is not None else GlobalPlannerConfig()
    check_global_planner_config(config, "plan_path")
    start = np.asarray(start_xy, dtype=float)[:2]
    goal = np.asarray(goal_xy, dtype=float)[:2]

    def failure(message: str, expanded: int = 0) -> GlobalPath:
        elapsed = time.perf_counter() - begin
        return GlobalPath(False, np.zeros((0, 2)), 0.0, message, math.inf, expanded, elapsed)

    if not (np.all(np.isfinite(start)) and np.all(np.isfinite(goal))):
        return failure(OUTSIDE_MAP)
    rows, cols = costmap.shape
    g_start, g_goal = costmap.to_grid(start), costmap.to_grid(goal)
    s_rc, t_rc = _cell(g_start), _cell(g_goal)
    if not (costmap.inside(*s_rc) and costmap.inside(*t_rc)):
        return failure(OUTSIDE_MAP)
    if costmap.costs[s_rc] == LETHAL:
        return failure(START_IN_OBSTACLE)
    eff = traversal_costs(costmap, config, start)
    if eff[s_rc] < 0:
        return failure(START_IN_OBSTACLE)
    candidates = _goal_candidates(eff, g_goal, t_rc, config.tolerance / costmap.resolution)
    if len(candidates) == 0:
        return failure(GOAL_IN_OBSTACLE)
    target = candidates[0]
    tolerance_cells = config.tolerance / costmap.resolution if eff[t_rc] < 0 else 0.0
    g, parent, expanded = _search(
        eff,
        s_rc[0] * cols + s_rc[1],
        int(target),
        float(g_goal[1]),
        float(g_goal[0]),
        tolerance_cells,
        float(config.neutral_cost),
        float(config.cost_factor),
        bool(config.use_astar),
    )
    reached = [int(c) for c in candidates if math.isfinite(g[c])]
    if not reached:
        return failure(UNREACHABLE, expanded)
    end = reached[0]
    cells = [end]
    while cells[-1] != s_rc[0] * cols + s_rc[1]:
        cells.append(int(parent[cells[-1]]))
    cells = np.array(cells[::-1])
    points = np.stack([cells % cols + 0.5, cells // cols + 0.5], -1)
    points[0] = g_start
    last = g_goal if end == t_rc[0] * cols + t_rc[1] else points[-1]
    if len(points) == 1:
        points = np.vstack([points, last])
    points[-1] = last
    if config.simplify and len(points) > 2:
        keep = _shortcut(eff, points, cell_costs=eff.ravel()[cells])
        points = points[keep]
    path = costmap.to_world(points)
    length = float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
    return GlobalPath(True, path, length, "", float(g[end]), expanded, time.perf_counter() - begin)


def path_blocked(
    costmap: Costmap, path, config: GlobalPlannerConfig | None = None, start_xy=None
) -> bool:
    """True if a point of the polyline ``path`` (n, 2) m, sampled every half cell, lies in a
    cell the planner may not cross (the start's escape cells around ``start_xy`` excepted)."""
    config = config if config is not None else GlobalPlannerConfig()
    path = np.asarray(path, dtype=float).reshape(-1, 2)
    if len(path) == 0:
        return False
    eff = traversal_costs(costmap, config, start_xy)
    grid = costmap.to_grid(path)
    samples = [grid[:1]]
    for a, b in zip(grid[:-1], grid[1:], strict=True):
        n = max(1, int(math.ceil(2.0 * float(np.linalg.norm(b - a)))))
        samples.append(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
    points = np.concatenate(samples)
    rows, cols = np.floor(points[:, 1]).astype(int), np.floor(points[:, 0]).astype(int)
    ok = costmap.inside(rows, cols)
    return bool(np.any(~ok) or np.any(eff[rows[ok], cols[ok]] < 0))


def _cell(grid) -> tuple[int, int]:
    """(row, col) of a (finite) point in grid units."""
    return int(math.floor(grid[1])), int(math.floor(grid[0]))


def _goal_candidates(eff, g_goal, t_rc, tolerance_cells: float) -> np.ndarray:
    """Flat indices of the goal cell (if passable) then of the passable cells within the
    tolerance, nearest the goal first."""
    rows, cols = eff.shape
    span = int(math.ceil(tolerance_cells)) + 1
    r0, r1 = max(t_rc[0] - span, 0), min(t_rc[0] + span + 1, rows)
    c0, c1 = max(t_rc[1] - span, 0), min(t_rc[1] + span + 1, cols)
    rr, cc = np.mgrid[r0:r1, c0:c1]
    d = np.hypot(cc + 0.5 - g_goal[0], rr + 0.5 - g_goal[1])
    is_goal = (rr == t_rc[0]) & (cc == t_rc[1])
    ok = (eff[r0:r1, c0:c1] >= 0) & ((d <= tolerance_cells + 1e-9) | is_goal)
    d = np.where(is_goal, -1.0, d)  # The goal cell itself first.
    order = np.argsort(d[ok], kind="stable")
    return (rr[ok] * cols + cc[ok])[order]


@njit(cache=True)
def _search(eff, start, target, goal_r, goal_c, tol, neutral, factor, astar):
    """A* (Dijkstra without ``astar``) from flat cell ``start`` to ``target``; returns the
    cost-to-come of every closed cell (inf elsewhere), parents and the cells expanded."""
    rows, cols = eff.shape
    flat = eff.ravel()
    n = rows * cols
    g = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int64)
    closed = np.zeros(n, dtype=np.bool_)
    dr = np.array([-1, 1, 0, 0, -1, -1, 1, 1])
    dc = np.array([0, 0, -1, 1, -1, 1, -1, 1])
    g[start] = 0.0
    heap = [(0.0, start)]
    expanded = 0
    while len(heap) > 0:
        _, cell = heapq.heappop(heap)
        if closed[cell]:
            continue
        closed[cell] = True
        expanded += 1
        if cell == target:
            break
        r, c = cell // cols, cell % cols
        for k in range(8):
            nr, nc = r + dr[k], c + dc[k]
            if nr < 0 or nr >= rows or nc < 0 or nc >= cols:
                continue
            nxt = nr * cols + nc
            if closed[nxt] or flat[nxt] < 0:
                continue
            step = 1.0
            if k >= 4:
                if flat[r * cols + nc] < 0 or flat[nr * cols + c] < 0:
                    continue
                step = 1.4142135623730951
            cost = g[cell] + (neutral + factor * flat[nxt]) * step
            if cost < g[nxt]:
                g[nxt] = cost
                parent[nxt] = cell
                h = 0.0
                if astar:
                    h = neutral * max(0.0, math.hypot(nr + 0.5 - goal_r, nc + 0.5 - goal_c) - tol)
                heapq.heappush(heap, (cost + h, nxt))
    for i in range(n):
        if not closed[i]:
            g[i] = np.inf
    return g, parent, expanded


def _shortcut(eff, points, cell_costs) -> np.ndarray:
    """Indices of ``points`` (grid units) to keep (see the module docstring)."""
    return _shortcut_kernel(eff, np.ascontiguousarray(points), cell_costs.astype(np.int64))


@njit(cache=True)
def _shortcut_kernel(eff, points, cell_costs):
    n = points.shape[0]
    keep = [0]
    i = 0
    while i < n - 1:
        best = i + 1
        worst = max(cell_costs[i], cell_costs[i + 1])
        for j in range(i + 2, n):
            worst = max(worst, cell_costs[j])
            if not _line_ok(eff, points[i], points[j], worst):
                break
            best = j
        keep.append(best)
        i = best
    return np.array(keep)


@njit(cache=True)
def _line_ok(eff, a, b, worst):
    """True if every cell the segment a-b (grid units) crosses, sampled every 1/4 cell, is
    passable and costs at most ``worst``."""
    length = math.hypot(b[0] - a[0], b[1] - a[1])
    n = max(1, int(math.ceil(4.0 * length)))
    for k in range(n + 1):
        s = k / n
        c = int(math.floor(a[0] + s * (b[0] - a[0])))
        r = int(math.floor(a[1] + s * (b[1] - a[1])))
        value = eff[r, c]
        if value < 0 or value > worst:
            return False
    return True
