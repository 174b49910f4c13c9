"""Benchmark of the scan-matching SLAM alone: ``python benchmarks/slam_benchmark.py [--arena F]``.

No Drake simulation: for every shipped arena (``config/arenas/*.yaml``) and its default route,
a robot drives the route (turning on the spot, then straight at 0.2 m/s; a scan every 0.04 m
or 9 degrees, as at 5 Hz), a 360-beam, 3.5 m lidar with 1 cm noise is ray-marched through the
arena's ground-truth grid (1 cm cells, so ranges are good to about 1 cm), and wheel odometry
drifts by 2 % in distance and 0.5 degrees per metre. Printed per arena:

* the cost per ``ScanMatchingSlam.update`` (matching, and the map update when one is due):
  median and 95th percentile, ms; the cost of one ``LogOddsGrid.insert_scan`` (0.05 m grid);
* the pose RMSE and final error of SLAM and of the odometry, m; the map's ``map_iou`` and
  ``known_fraction`` against the arena's grid at 0.05 m.

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
from drake_sim.base.planar import compose
from drake_sim.base.planar import relative_pose as relative
from drake_sim.systems.estimation.occupancy_grid import LogOddsGrid, known_fraction, occupancy_iou
from drake_sim.systems.estimation.scan_matching_slam import ScanMatchingSlam
from drake_sim.worlds.arena import arena_grid, load_arena, shipped_arenas
from drake_sim.worlds.route import default_route_file, load_route

BEAMS, RANGE_MIN, RANGE_MAX, SIGMA = 360, 0.12, 3.5, 0.01
SCAN_HEIGHT = 0.2  # m; the shipped arenas' geometry is taller than this everywhere.
X_BASE_SENSOR = (-0.064, 0.0, 0.0)


def route_poses(start, waypoints, step=0.04, turn=0.16) -> np.ndarray:
    """Poses (k, 3) one scan apart (step m, turn rad) along the route: turn on the spot, then
    drive straight."""
    poses = [np.array(start, dtype=float)]
    for target in waypoints:
        pose = poses[-1]
        heading = math.atan2(target[1] - pose[1], target[0] - pose[0])
        turn_by = (heading - pose[2] + math.pi) % (2 * math.pi) - math.pi
        for k in range(1, int(math.ceil(abs(turn_by) / turn)) + 1):
            fraction = min(1.0, k * turn / abs(turn_by))
            poses.append(np.array([pose[0], pose[1], pose[2] + fraction * turn_by]))
        length = math.hypot(target[0] - pose[0], target[1] - pose[1])
        for k in range(1, int(math.ceil(length / step)) + 1):
            s = min(length, k * step)
            poses.append(
                np.array(
                    [pose[0] + s * math.cos(heading), pose[1] + s * math.sin(heading), heading]
                )
            )
    return np.array(poses)


def drifting(truth: np.ndarray, rng) -> np.ndarray:
    """Odometry along ``truth``: 2 % long, 0.5 deg/m of yaw drift, a little noise."""
    odometry = [truth[0]]
    for before, after in zip(truth[:-1], truth[1:], strict=True):
        step = relative(before, after)
        length = math.hypot(step[0], step[1])
        step[:2] *= 1.02
        step[2] += math.radians(0.5) * length + rng.normal(0.0, 0.001)
        odometry.append(compose(odometry[-1], step))
    return np.array(odometry)


def ray_march(grid, sensor_pose, angles, rng) -> np.ndarray:
    """Noisy ranges from ``sensor_pose`` through the occupied cells of ``grid``."""
    t = np.arange(RANGE_MIN, RANGE_MAX + 0.05, grid.resolution / 2)
    directions = sensor_pose[2] + angles
    xy = np.stack(
        [
            sensor_pose[0] + np.cos(directions)[:, None] * t,
            sensor_pose[1] + np.sin(directions)[:, None] * t,
        ],
        -1,
    )
    hit = grid.value_at(xy, outside=100) >= 100
    first = np.where(hit.any(1), hit.argmax(1), -1)
    ranges = np.where(first >= 0, t[np.maximum(first, 0)], np.inf) + rng.normal(0, SIGMA, BEAMS)
    return np.where(ranges < RANGE_MAX, ranges, np.inf)


def run_arena(path: Path, seed: int) -> dict:
    arena = load_arena(path)
    route = load_route(default_route_file(path), arena)
    start = arena.start_pose()
    truth = route_poses(start, route.waypoints)
    rng = np.random.default_rng(seed)
    odometry = drifting(truth, rng)
    fine_truth = arena_grid(arena, 0.01, height=SCAN_HEIGHT)
    angles = np.linspace(-math.pi, math.pi, BEAMS, endpoint=False)
    scans = [ray_march(fine_truth, compose(pose, X_BASE_SENSOR), angles, rng) for pose in truth]
    slam = ScanMatchingSlam(initial_pose=start, X_base_sensor=X_BASE_SENSOR)
    costs = []
    for scan, odom in zip(scans, odometry, strict=True):
        begin = time.perf_counter()
        slam.update(scan, angles, odom, range_max=RANGE_MAX, range_min=RANGE_MIN)
        costs.append(time.perf_counter() - begin)
    grid = LogOddsGrid(resolution=0.05, size=(30.0, 30.0), origin=(-15.0, -15.0))
    insert = []
    for pose, scan in list(zip(truth, scans, strict=True))[::10]:
        begin = time.perf_counter()
        grid.insert_scan(compose(pose, X_BASE_SENSOR), scan, angles, RANGE_MAX)
        insert.append(time.perf_counter() - begin)
    error = np.hypot(*(slam.trajectory[:, :2] - truth[:, :2]).T)
    odometry_error = np.hypot(*(odometry[:, :2] - truth[:, :2]).T)
    truth_grid = arena_grid(arena, 0.05, height=SCAN_HEIGHT)
    return {
        "scans": len(truth),
        "update_ms": 1e3 * statistics.median(costs),
        "p95_ms": 1e3 * float(np.percentile(costs, 95)),
        "insert_ms": 1e3 * statistics.median(insert),
        "rmse_m": math.sqrt(float(np.mean(error**2))),
        "final_m": float(error[-1]),
        "odom_final_m": float(odometry_error[-1]),
        "map_iou": occupancy_iou(slam.map(), truth_grid),
        "known": known_fraction(slam.map(), truth_grid),
    }


COLUMNS = (
    ("arena", "arena", "", ""),
    ("scans", "scans", "", "d"),
    ("update_ms", "update, median", "ms", ".2f"),
    ("p95_ms", "update, p95", "ms", ".2f"),
    ("insert_ms", "insert_scan, median", "ms", ".3f"),
    ("rmse_m", "pose RMSE", "m", ".4f"),
    ("final_m", "final pose error", "m", ".4f"),
    ("odom_final_m", "odometry's final error", "m", ".3f"),
    ("map_iou", "map IoU", "", ".4f"),
    ("known", "known fraction", "", ".4f"),
)
"""(key, header, unit, format) of the ``--json`` table's columns."""


def figures(rows: list[dict], seed: int) -> dict:
    """The per-arena rows as ``--json`` figures."""
    return {
        "settings": {"seed": seed},
        "figures": {f"{r['arena']}_{k}": r[k] for r in rows for k in ("update_ms", "rmse_m")},
        "tables": [
            {
                "title": f"Per arena, its default route (seed {seed})",
                "columns": [list(c) for c in COLUMNS],
                "rows": rows,
            }
        ],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--arena", type=Path, action="append", help="default: all shipped")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args()
    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"python {platform.python_version()}"
    )
    header = ("arena", "scans", "update_ms", "p95_ms", "insert_ms", "rmse_m", "final_m")
    header += ("odom_final_m", "map_iou", "known")
    print(" ".join(f"{h:>12}" for h in header))
    rows = []
    for path in args.arena or shipped_arenas():
        row = run_arena(path, args.seed)
        rows.append({"arena": path.stem, **row})
        cells = [f"{path.stem:>12}"] + [
            f"{row[h]:>12d}" if isinstance(row[h], int) else f"{row[h]:>12.4f}" for h in header[1:]
        ]
        print(" ".join(cells), flush=True)
    if args.json:
        write_atomic(args.json, json.dumps(figures(rows, args.seed), indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
