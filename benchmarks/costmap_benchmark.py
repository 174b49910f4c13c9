"""Benchmark of the costmaps and the global planner: ``python benchmarks/costmap_benchmark.py
[--arena F] [--resolution M] [--repeats N]``.

No Drake simulation. The arena's ground-truth grid (``arena_grid``, default the warehouse at
0.05 m) makes the global costmap; 360-beam, 3.5 m scans are cast exactly against its footprints
(plus a box that is not on the map) from poses along its free space. Printed, medians over the
repeats (ms):

* building the costmap from the map (static layer + whole-map inflation), and ``inflate`` alone;
* one ``update_scan`` (ray tracing, marking, re-inflating the window the beams reach);
* ``clear_obstacles`` and ``local_window``;
* ``plan_path`` across the map (A* and Dijkstra), between random free points, and to an
  unreachable goal (a fail costs one sweep of the start's free space).

``--json FILE`` also writes the table for ``python -m benchmarks.report``. Not a test: speeds
depend on the machine.
"""

import argparse
import json
import math
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np

from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.base.resources import config_dir
from drake_sim.navigation.costmap import LETHAL, Costmap, inflate
from drake_sim.navigation.global_planner import GlobalPlannerConfig, plan_path
from drake_sim.worlds.arena import arena_footprints, arena_grid, load_arena
from drake_sim.worlds.footprints import Footprint, cast_rays, clearance

BEAMS, RANGE_MAX = 360, 3.5


def timed(function, repeats: int) -> tuple[float, object]:
    """Median wall time (ms) of ``repeats`` calls, and the last call's result."""
    times, result = [], None
    for _ in range(repeats):
        begin = time.perf_counter()
        result = function()
        times.append(1e3 * (time.perf_counter() - begin))
    return statistics.median(times), result


def row(label: str, ms: float, extra: str = "") -> dict:
    """Prints one aligned line of the table; returns it as a row of the JSON table."""
    print(f"{label:<38}{ms:9.3f} ms" + (f"  ({extra})" if extra else ""), flush=True)
    return {"operation": label, "median_ms": ms, "details": extra or None}


def free_points(arena, rng, count: int, margin: float = 0.3) -> np.ndarray:
    """``count`` random points at least ``margin`` m from every wall and obstacle."""
    footprints = arena_footprints(arena)
    half = 0.5 * np.asarray(arena.size)
    points = []
    while len(points) < count:
        p = rng.uniform(-half, half)
        if clearance(footprints, p) >= margin:
            points.append(p)
    return np.array(points)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--arena", type=Path, default=config_dir() / "arenas" / "warehouse.yaml")
    parser.add_argument("--resolution", type=float, default=0.05, help="m per cell")
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args()
    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"python {platform.python_version()}"
    )
    arena = load_arena(args.arena)
    grid = arena_grid(arena, args.resolution)
    rng = np.random.default_rng(0)
    print(
        f"arena {args.arena.name}: map {grid.shape[1]} x {grid.shape[0]} cells at "
        f"{args.resolution} m"
    )
    plan_path(Costmap.from_map(grid), *free_points(arena, rng, 2))  # numba: load or compile

    ms, costmap = timed(lambda: Costmap.from_map(grid), args.repeats)
    rows = [row("from_map (static + inflation)", ms)]
    lethal = costmap.lethal_mask()
    ms, _ = timed(lambda: inflate(lethal, grid.resolution, costmap.config), args.repeats)
    rows.append(row("inflate, whole map", ms))

    box = Footprint("box", "new", (0.0, -2.0), (0.3, 0.3), 0.0, 0.0, 0.5)
    footprints = [*arena_footprints(arena), box]
    angles = np.linspace(-math.pi, math.pi, BEAMS, endpoint=False)
    poses = free_points(arena, rng, args.repeats)
    scans = cast_rays(footprints, poses, angles, RANGE_MAX)
    times = []
    for pose, ranges in zip(poses, scans, strict=True):
        begin = time.perf_counter()
        costmap.update_scan((*pose, 0.0), ranges, angles, RANGE_MAX)
        times.append(1e3 * (time.perf_counter() - begin))
    rows.append(
        row(
            f"update_scan ({BEAMS} beams, {RANGE_MAX} m)",
            statistics.median(times),
            f"max {max(times):.3f} ms",
        )
    )
    ms, _ = timed(lambda: costmap.local_window(poses[0]), args.repeats)
    rows.append(row(f"local_window ({costmap.config.local_width} m)", ms))
    ms, _ = timed(costmap.clear_obstacles, args.repeats)
    rows.append(row("clear_obstacles", ms))

    costmap = Costmap.from_map(grid)
    half = 0.5 * np.asarray(arena.size) - 0.4
    corners = (-half, half)
    for name, config in (
        ("A*", GlobalPlannerConfig()),
        ("Dijkstra", GlobalPlannerConfig(use_astar=False)),
    ):
        ms, path = timed(lambda config=config: plan_path(costmap, *corners, config), args.repeats)
        rows.append(
            row(
                f"plan_path {name}, corner to corner",
                ms,
                f"{path.length_m:.2f} m, {len(path.path)} points, {path.expanded} cells expanded, "
                f"{path.message or 'ok'}",
            )
        )
    pairs = free_points(arena, rng, 2 * args.repeats).reshape(-1, 2, 2)
    times = [plan_path(costmap, a, b).planning_time_s * 1e3 for a, b in pairs]
    rows.append(
        row("plan_path A*, random pairs", statistics.median(times), f"max {max(times):.3f} ms")
    )
    walled = Costmap.from_map(grid)
    goal = poses[0]
    r, c = walled.cell_of(goal)
    ring = np.zeros(walled.shape, dtype=bool)
    ring[r - 8 : r + 9, c - 8 : c + 9] = True
    ring[r - 7 : r + 8, c - 7 : c + 8] = False
    walled.static_layer[ring] = LETHAL
    walled.clear_obstacles()
    start = next(p for p in poses[1:] if np.linalg.norm(p - goal) > 1.0)
    ms, fail = timed(lambda: plan_path(walled, start, goal), args.repeats)
    rows.append(
        row("plan_path to a walled-in goal", ms, f"{fail.message}, {fail.expanded} cells expanded")
    )
    if args.json:
        size = f"{grid.shape[1]} x {grid.shape[0]} cells at {args.resolution:g} m"
        columns = [
            ["operation", "operation", "", ""],
            ["median_ms", "median", "ms", ".3f"],
            ["details", "details", "", ""],
        ]
        table = {
            "title": f"{args.arena.stem}: map {size}, medians of {args.repeats} repeats",
            "columns": columns,
            "rows": rows,
        }
        result = {
            "settings": {"arena": args.arena.stem, "resolution_m": args.resolution},
            "figures": {r["operation"]: r["median_ms"] for r in rows},
            "tables": [table],
        }
        write_atomic(args.json, json.dumps(result, indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
