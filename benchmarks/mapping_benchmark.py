"""Benchmark of the lidar robot's mapping: ``python benchmarks/mapping_benchmark.py [--runs 3]``.

With the default robot and scenario (``config/turtlebot3.yaml``, ``config/mapping_scenario.yaml``:
the LDS-01's 360 beams at 5 Hz), headless, on every shipped arena with its default route,
``--runs`` runs each (seeds 0, 1, ...):

* per run: the map's IoU and known fraction, the SLAM's pose RMSE, the raw odometry's final
  error and their ratio, and the real-time factor; per arena the median real-time factor and
  whether every run met the acceptance (IoU >= 0.9, known >= 0.95, RMSE <= 0.05 m and at least
  3 times smaller than the odometry's final error);
* the lidar alone: the median cost of one 360-beam scan in each arena, from the robot's start.

Not a test: speeds depend on the machine.
"""

import argparse
import os
import platform
import statistics
import time

import numpy as np
from pydrake.systems.analysis import Simulator

from diagrams.mapping import make_mapping_diagram
from diagrams.mapping_scenario import default_scenario_file, load_mapping_scenario
from drake_sim.mapping_run import MappingReport, MappingRun
from drake_sim.robots.turtlebot3 import default_turtlebot3_file
from drake_sim.robots.turtlebot3_params import load_turtlebot3_params
from drake_sim.worlds.arena import load_arena, shipped_arenas
from drake_sim.worlds.route import default_route_file, load_route

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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=3, help="runs per arena (seeds 0, 1, ...)")
    parser.add_argument("--arenas", nargs="*", help="arena names (default: every shipped one)")
    args = parser.parse_args()
    scenario = load_mapping_scenario(default_scenario_file())
    robot = load_turtlebot3_params(default_turtlebot3_file())
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
    summary = []
    for path in arenas:
        arena = load_arena(path)
        waypoints = load_route(default_route_file(path), arena).waypoints
        factors, passed = [], True
        for seed in range(args.runs):
            run = MappingRun(scenario, robot, arena, waypoints, seed=seed)
            run.run(run.default_duration())
            r = run.report()
            ok = r.end == "route_done" and meets_acceptance(r)
            passed &= ok
            factors.append(r.real_time_factor)
            ratio = r.odometry_final_error_m / r.pose_rmse_m if r.pose_rmse_m > 0 else np.inf
            print(
                f"{path.stem:<10} {seed:>4} {r.map_iou:5.3f} {r.known_fraction:6.3f} "
                f"{r.pose_rmse_m:7.3f} {r.odometry_final_error_m:7.3f} {ratio:6.1f} "
                f"{r.sim_time_s:7.1f} {r.real_time_factor:6.2f}  {'yes' if ok else 'NO'}",
                flush=True,
            )
        summary.append(
            (path.stem, statistics.median(factors), passed, lidar_cost_ms(scenario, robot, arena))
        )
    print("per arena: median real-time factor (target >= 3), acceptance, lidar ms per scan (< 2)")
    for name, factor, passed, cost in summary:
        print(
            f"  {name:<10} {factor:5.2f}x  {'all runs pass' if passed else 'FAILED'}  {cost:.3f} ms"
        )


if __name__ == "__main__":
    main()
