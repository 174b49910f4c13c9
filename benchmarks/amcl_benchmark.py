"""Benchmark of AMCL alone: ``python benchmarks/amcl_benchmark.py [--arena F] [--seeds N]``.

No Drake simulation: on every shipped arena (``config/arenas/*.yaml``) the robot drives its
default route (turning on the spot, then straight at 0.2 m/s; a scan every 0.04 m or 9 degrees,
as at 5 Hz), a 360-beam, 3.5 m lidar with 1 cm noise is ray-cast exactly against the arena's
walls and obstacles, and wheel odometry is 1 % long and drifts 0.5 degrees per metre. The
filter (``config/amcl.yaml``) localises on the arena's ground-truth 0.05 m map. Printed:

* the cost of one ``ParticleFilter.update`` that updates, with the particle count fixed at
  2000 (min_particles = max_particles; 60 of the 360 beams): median and 95th percentile, ms;
  and with the shipped config from a rough guess (8000 particles at first, KLD down to 1000);
* tracking from a guess 0.5 m and 30 degrees off: per seed, the time after which the error
  stays under 5 cm and 3 degrees, and the largest error after 10 s of driving;
* global localisation (particles over all the free space): the time after which the error
  stays under 5 cm and 3 degrees.

The costs include the scan-to-map refinement of the shipped config (``--no-refinement``: the
filter alone).

``--json FILE`` also writes the figures for ``python -m benchmarks.report``. Not a test: speeds
depend on the machine.
"""

import argparse
import dataclasses as dc
import json
import math
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np
from slam_benchmark import route_poses

from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.base.planar import compose, wrap_angle
from drake_sim.base.planar import relative_pose as relative
from drake_sim.systems.estimation.amcl import default_amcl_config_file, load_amcl_config
from drake_sim.systems.estimation.particle_filter import ParticleFilter
from drake_sim.worlds.arena import arena_footprints, arena_grid, load_arena, shipped_arenas
from drake_sim.worlds.footprints import cast_rays
from drake_sim.worlds.route import default_route_file, load_route

RATE = 5.0  # Hz: route_poses spaces the scans as at 0.2 m/s and 0.8 rad/s
BEAMS, RANGE_MIN, RANGE_MAX, SIGMA = 360, 0.12, 3.5, 0.01
SCAN_HEIGHT = 0.17  # m, the TurtleBot3's lidar plane
X_BASE_SENSOR = (-0.064, 0.0, 0.0)
ANGLES = np.linspace(-math.pi, math.pi, BEAMS, endpoint=False)


def odometry_along(truth: np.ndarray, rng) -> np.ndarray:
    """Odometry along ``truth``: 1 % long, 0.5 deg/m of yaw drift, a little noise."""
    odometry = [truth[0]]
    for before, after in zip(truth[:-1], truth[1:], strict=True):
        step = relative(before, after)
        length = math.hypot(step[0], step[1])
        step[:2] *= 1.01
        step[2] += math.radians(0.5) * length + rng.normal(0.0, 0.001)
        odometry.append(compose(odometry[-1], step))
    return np.array(odometry)


class Scenario:
    """An arena's route, its scans and odometry (``duration`` s of driving)."""

    def __init__(self, path: Path, seed: int, duration: float):
        arena = load_arena(path)
        route = load_route(default_route_file(path), arena)
        truth = route_poses(arena.start_pose(), route.waypoints)
        self.truth = truth[: int(duration * RATE) + 1]
        rng = np.random.default_rng(seed)
        self.odometry = odometry_along(self.truth, rng)
        footprints = arena_footprints(arena, height=SCAN_HEIGHT)
        sensors = np.array([compose(pose, X_BASE_SENSOR) for pose in self.truth])
        self.scans = [
            cast_rays(footprints, s[None, :2], ANGLES + s[2], RANGE_MAX)[0]
            + rng.normal(0.0, SIGMA, BEAMS)
            for s in sensors
        ]
        self.grid = arena_grid(arena, 0.05, height=SCAN_HEIGHT)

    def run(self, dut: ParticleFilter):
        """Feeds every scan; returns (update costs s, rows [t, error m, error deg])."""
        costs, rows = [], []
        for k, (pose, odom, ranges) in enumerate(
            zip(self.truth, self.odometry, self.scans, strict=True)
        ):
            begin = time.perf_counter()
            updated = dut.update(
                odom,
                ranges,
                ANGLES,
                range_max=RANGE_MAX,
                range_min=RANGE_MIN,
                X_base_sensor=X_BASE_SENSOR,
            )
            if updated:
                costs.append(time.perf_counter() - begin)
                estimate, _ = dut.estimate()
                rows.append(
                    [
                        k / RATE,
                        math.dist(estimate[:2], pose[:2]),
                        math.degrees(abs(float(wrap_angle(estimate[2] - pose[2])))),
                    ]
                )
        return costs, np.array(rows)


def settled_after(rows: np.ndarray, metres=0.05, degrees=3.0) -> float:
    """s after which every error stays under the bounds (inf: not at the end)."""
    bad = np.nonzero((rows[:, 1] >= metres) | (rows[:, 2] >= degrees))[0]
    if len(bad) == 0:
        return 0.0
    return math.inf if bad[-1] == len(rows) - 1 else float(rows[bad[-1] + 1, 0])


def guess_offset(seed: int) -> np.ndarray:
    rng = np.random.default_rng(1000 + seed)
    direction = rng.uniform(-math.pi, math.pi)
    sign = rng.choice([-1, 1])
    return np.array([0.5 * math.cos(direction), 0.5 * math.sin(direction), sign * math.radians(30)])


def figures(rows: list[dict], global_row: dict, seeds: int) -> dict:
    """The per-arena rows and the global localisation's as ``--json`` figures (times that never
    settled as null)."""
    columns = [
        ["arena", "arena", "", ""],
        ["fixed_ms", "update, 2000 particles, median", "ms", ".2f"],
        ["fixed_p95_ms", "p95", "ms", ".2f"],
        ["shipped_ms", "update, shipped config, median", "ms", ".2f"],
        ["settled_s", "settled after, per seed", "s", ".1f"],
        ["max_error_m", "largest error after 10 s", "m", ".3f"],
        ["max_error_deg", "largest heading error after 10 s", "deg", ".2f"],
    ]
    global_columns = [
        ["arena", "arena", "", ""],
        ["particles", "particles", "", "d"],
        ["settled_s", "settled after, per seed", "s", ".1f"],
        ["first_update_ms", "first update, last seed", "ms", ".1f"],
    ]
    settled = "settled: the error stays under 5 cm and 3 degrees from then on (- never)"
    return {
        "settings": {"seeds": seeds},
        "figures": {f"{r['arena']}_fixed_ms": r["fixed_ms"] for r in rows},
        "tables": [
            {
                "title": f"Tracking from a guess 0.5 m and 30 degrees off, seeds 1 to {seeds}",
                "columns": columns,
                "rows": rows,
                "note": f"Costs over every update of every seed; {settled}.",
            },
            {
                "title": "Global localisation (particles over all the free space)",
                "columns": global_columns,
                "rows": [global_row],
            },
        ],
    }


def _finite(seconds: float) -> float | None:
    return seconds if math.isfinite(seconds) else None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--arena", type=Path, action="append", help="default: all shipped")
    parser.add_argument("--seeds", type=int, default=5, help="seeds 1..N per arena")
    parser.add_argument(
        "--no-refinement", action="store_true", help="without the scan-to-map refinement"
    )
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args()
    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"python {platform.python_version()}, numpy {np.__version__}"
    )
    config = load_amcl_config(default_amcl_config_file())
    if args.no_refinement:
        config = dc.replace(config, scan_match_refinement=False)
    fixed = dc.replace(config, min_particles=2000, max_particles=2000)
    covariance = np.diag([0.25, 0.25, math.radians(30) ** 2])
    warm = Scenario(shipped_arenas()[0], 0, 1.0)  # loads the compiled kernel before timing
    warm.run(ParticleFilter(warm.grid, fixed, 0))
    print(
        f"{'arena':>10} {'2000 p: ms':>11} {'p95 ms':>7} {'shipped ms':>11}"
        f" {'settled s (per seed)':>28} {'max err >10 s: m, deg':>22}"
    )
    arena_rows = []
    for path in args.arena or shipped_arenas():
        fixed_costs, shipped_costs, settled, worst = [], [], [], [0.0, 0.0]
        for seed in range(1, args.seeds + 1):
            scenario = Scenario(path, seed, 20.0)
            start = scenario.truth[0] + guess_offset(seed)
            dut = ParticleFilter(scenario.grid, fixed, seed)
            dut.set_pose(start, covariance)
            fixed_costs += scenario.run(dut)[0]
            dut = ParticleFilter(scenario.grid, config, seed)
            dut.set_pose(start, covariance)
            costs, rows = scenario.run(dut)
            shipped_costs += costs
            settled.append(settled_after(rows))
            late = rows[rows[:, 0] >= 10.0]
            worst = [max(worst[0], late[:, 1].max()), max(worst[1], late[:, 2].max())]
        print(
            f"{path.stem:>10} {1e3 * statistics.median(fixed_costs):>11.2f}"
            f" {1e3 * float(np.percentile(fixed_costs, 95)):>7.2f}"
            f" {1e3 * statistics.median(shipped_costs):>11.2f}"
            f" {' '.join(f'{s:.1f}' for s in settled):>28}"
            f" {worst[0]:>15.3f}, {worst[1]:.2f}"
        )
        arena_rows.append(
            {
                "arena": path.stem,
                "fixed_ms": 1e3 * statistics.median(fixed_costs),
                "fixed_p95_ms": 1e3 * float(np.percentile(fixed_costs, 95)),
                "shipped_ms": 1e3 * statistics.median(shipped_costs),
                "settled_s": [_finite(s) for s in settled],
                "max_error_m": float(worst[0]),
                "max_error_deg": float(worst[1]),
            }
        )
    room = next(p for p in shipped_arenas() if p.stem == "room")
    times = []
    for seed in range(1, args.seeds + 1):
        scenario = Scenario(room, seed, 70.0)
        dut = ParticleFilter(scenario.grid, config, seed)
        dut.global_localization()
        costs, rows = scenario.run(dut)
        times.append(settled_after(rows))
    print(
        f"global localisation, room, {config.max_particles} particles: settled after "
        f"{', '.join(f'{t:.1f}' for t in times)} s of driving (first update "
        f"{1e3 * costs[0]:.1f} ms)"
    )
    if args.json:
        global_row = {
            "arena": room.stem,
            "particles": config.max_particles,
            "settled_s": [_finite(t) for t in times],
            "first_update_ms": 1e3 * costs[0],
        }
        result = figures(arena_rows, global_row, args.seeds)
        write_atomic(args.json, json.dumps(result, indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
