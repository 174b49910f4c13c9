"""Benchmark of the lidar robot's mapping: ``python benchmarks/mapping_benchmark.py [--runs 3]``.

With the default robot and scenario (``config/turtlebot3.yaml``, ``config/mapping_scenario.yaml``:
the LDS-01's 360 beams at 5 Hz), headless, on every shipped arena with its default route,
``--runs`` runs each (seeds 0, 1, ...):

* per run: the map's IoU and known fraction, the SLAM's pose RMSE, the raw odometry's final
  error and their ratio, and the real-time factor; per arena the median real-time factor and
  whether every run met the acceptance (IoU >= 0.9, known >= 0.95, RMSE <= 0.05 m and at least
  3 times smaller than the odometry's final error);
* the lidar alone: the median cost of one 360-beam scan in each arena, from the robot's start.

``--json FILE`` also writes the figures for ``python -m benchmarks.report``. Not a test: speeds
depend on the machine.
"""

import argparse
import json
import os
import platform
import statistics
import time

import numpy as np
from pydrake.systems.analysis import Simulator

from diagrams.mapping import make_mapping_diagram
from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.runs.mapping import RECIPE, MappingReport
from drake_sim.worlds.arena import load_arena, shipped_arenas

LIDAR_SCANS = 200
"""Scans timed per arena for the lidar's cost."""


def meets_acceptance(report: MappingReport) -> bool:
    """The issue's acceptance for one run on a shipped arena."""
    return (
        report.map_iou >= 0.9
        and report.known_fraction >= 0.95
        and report.pose_rmse_m <= 0.05
        and 3 * report.pose_rmse_m <= report.odometry_final_error_m
    )


def lidar_cost_ms(scenario, robot, arena) -> float:
    """Median wall time (ms) of one scan of the diagram's lidar at the arena's start."""
    diagram = make_mapping_diagram(scenario, robot, arena, [])
    simulator = Simulator(diagram)
    simulator.AdvanceTo(0.01)
    lidar = diagram.GetSubsystemByName("lidar")
    context = lidar.GetMyContextFromRoot(simulator.get_context())
    lidar.scan_now(context)  # loads the compiled kernel and caches the static scene
    times = []
    for _ in range(LIDAR_SCANS):
        start = time.perf_counter()
        lidar.scan_now(context)
        times.append(time.perf_counter() - start)
    return 1000 * statistics.median(times)


RUN_COLUMNS = [
    ["arena", "arena", "", ""],
    ["seed", "seed", "", "d"],
    ["map_iou", "map IoU", "", ".3f"],
    ["known_fraction", "known", "", ".3f"],
    ["pose_rmse_m", "pose RMSE", "m", ".3f"],
    ["odometry_final_error_m", "odometry's final error", "m", ".3f"],
    ["ratio", "odometry error / RMSE", "", ".1f"],
    ["sim_time_s", "simulated", "s", ".1f"],
    ["real_time_factor", "real-time factor", "x", ".2f"],
    ["accepted", "accepted", "", ""],
]
"""(key, header, unit, format) of the ``--json`` per-run table."""

ARENA_COLUMNS = [
    ["arena", "arena", "", ""],
    ["real_time_factor", "median real-time factor", "x", ".2f"],
    ["all_accepted", "every run accepted", "", ""],
    ["lidar_ms", "lidar, median per scan", "ms", ".3f"],
]
"""(key, header, unit, format) of the ``--json`` per-arena table."""


def figures(runs: list[dict], arenas: list[dict], settings: dict) -> dict:
    """The runs and the per-arena summaries as ``--json`` figures."""
    accept = (
        "Accepted: the route done, IoU >= 0.9, known >= 0.95, RMSE <= 0.05 m and at least 3 "
        "times smaller than the odometry's final error."
    )
    return {
        "settings": settings,
        "figures": {
            "real_time_factor": statistics.median(r["real_time_factor"] for r in runs),
            "min_map_iou": min(r["map_iou"] for r in runs),
            "max_pose_rmse_m": max(r["pose_rmse_m"] for r in runs),
        },
        "tables": [
            {
                "title": f"Per run ({settings['runs']} seeds per arena, its default route)",
                "columns": RUN_COLUMNS,
                "rows": runs,
                "note": accept,
            },
            {
                "title": f"Per arena (the lidar: median of {LIDAR_SCANS} scans from the start)",
                "columns": ARENA_COLUMNS,
                "rows": arenas,
            },
        ],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=3, help="runs per arena (seeds 0, 1, ...)")
    parser.add_argument("--arenas", nargs="*", help="arena names (default: every shipped one)")
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args()
    inputs = RECIPE.load()  # config/mapping_scenario.yaml, config/turtlebot3.yaml
    scenario, robot = inputs.scenario, inputs.robot
    arenas = [p for p in shipped_arenas() if not args.arenas or p.stem in args.arenas]
    lidar = scenario.lidar
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    print(
        f"lidar {lidar.samples} beams at {lidar.rate:g} Hz, range {lidar.range_max:g} m, "
        f"sigma {lidar.noise_sigma:g} m; SLAM at {scenario.slam.resolution:g} m, "
        f"{scenario.slam.levels} levels; route speed {scenario.route_follower.speed:g} m/s"
    )
    header = "arena      seed   iou  known  rmse_m  odom_m  ratio   sim_s    rtf  ok"
    print(header)
    summary, runs = [], []
    for path in arenas:
        factors, passed = [], True
        for seed in range(args.runs):
            # The arena's default route; the map is not saved (``run``, not ``finish``).
            run = RECIPE.start(overrides=[f"arena={json.dumps(str(path))}"], seed=seed)
            run.run(run.default_duration())
            r = run.report()
            ok = r.end == "route_done" and meets_acceptance(r)
            passed &= ok
            factors.append(r.real_time_factor)
            ratio = r.odometry_final_error_m / r.pose_rmse_m if r.pose_rmse_m > 0 else np.inf
            scores = {key: getattr(r, key) for key, *_ in RUN_COLUMNS if hasattr(r, key)}
            runs.append({"arena": path.stem, "ratio": float(ratio), "accepted": ok, **scores})
            print(
                f"{path.stem:<10} {seed:>4} {r.map_iou:5.3f} {r.known_fraction:6.3f} "
                f"{r.pose_rmse_m:7.3f} {r.odometry_final_error_m:7.3f} {ratio:6.1f} "
                f"{r.sim_time_s:7.1f} {r.real_time_factor:6.2f}  {'yes' if ok else 'NO'}",
                flush=True,
            )
        cost = lidar_cost_ms(scenario, robot, load_arena(path))
        summary.append((path.stem, statistics.median(factors), passed, cost))
    print("per arena: median real-time factor (target >= 3), acceptance, lidar ms per scan (< 2)")
    for name, factor, passed, cost in summary:
        print(
            f"  {name:<10} {factor:5.2f}x  {'all runs pass' if passed else 'FAILED'}  {cost:.3f} ms"
        )
    if args.json:
        keys = [key for key, *_ in ARENA_COLUMNS]
        arena_rows = [dict(zip(keys, row, strict=True)) for row in summary]
        settings = {"runs": args.runs, "lidar_beams": lidar.samples, "lidar_rate_hz": lidar.rate}
        result = figures(runs, arena_rows, settings)
        write_atomic(args.json, json.dumps(result, indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
