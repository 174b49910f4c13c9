"""Benchmark of the lidar robot's navigation: ``python benchmarks/navigation_benchmark.py``.

The whole stack (physics, lidar, wheel odometry, AMCL, costmaps, A*, DWA), headless, with the
default robot and scenario (``config/navigation_scenario.yaml``), on each shipped arena's
ground-truth map (what a perfect mapping run saves; ``--map-dir`` takes saved maps named
``<arena>.yaml`` instead):

* the real-time factor of the room's goals (``config/goals/room.yaml``), ``--runs`` times, and
  the median (target >= 2);
* per arena, ``--goals`` random goals (``random_goals``, seed 7): reached, the
  largest position and heading errors against the truth, collisions, the smallest clearance,
  the worst time over driven length / the robot's top speed (target <= 2.5), the real-time factor;
* AMCL alone: the median cost of one filter update with 2000 particles (target < 5 ms).

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
import tempfile
import time
from pathlib import Path

import numpy as np

from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.base.map_files import load_map, save_map
from drake_sim.runs.navigate import RECIPE
from drake_sim.runs.navigation import NavigationRun
from drake_sim.systems.estimation.particle_filter import ParticleFilter
from drake_sim.worlds.arena import arena_footprints, arena_grid, load_arena, shipped_arenas
from drake_sim.worlds.footprints import cast_rays
from drake_sim.worlds.route import random_goals

AMCL_UPDATES = 100
"""Filter updates timed for AMCL's cost."""


def arena_override(path: Path) -> list[str]:
    """The scenario's override that puts the robot in the arena at ``path``."""
    return [f"arena={json.dumps(str(path))}"]


def run_arena_goals(path: Path, map_file: Path, seed: int):
    """The arena's goals file (``config/goals/<arena>.yaml``) driven on ``map_file``."""
    run = RECIPE.start(overrides=arena_override(path), seed=seed, map=map_file)
    run.run(run.default_duration())
    return run, run.report()


def run_random_goals(path: Path, occupancy_map, goals, seed: int = 0):
    """``goals`` (drawn with a seed of their own, not the run's) driven on ``occupancy_map``:
    the recipe loads the inputs, and the run takes the goals as they are."""
    inputs = RECIPE.load(overrides=arena_override(path), seed=seed)
    arena = load_arena(path)
    run = NavigationRun(
        inputs.scenario, inputs.robot, arena, occupancy_map, start=arena.start_pose(), goals=goals
    )
    run.run(run.default_duration())
    return run, run.report()


def map_files(folder: Path, map_dir: Path | None, robot) -> dict[str, Path]:
    """Each shipped arena's map file: ``map_dir``'s ``<arena>.yaml``, else its ground truth at
    the lidar's height saved in ``folder``."""
    files = {}
    for path in shipped_arenas():
        if map_dir is not None:
            files[path.stem] = map_dir / f"{path.stem}.yaml"
        else:
            truth = arena_grid(load_arena(path), 0.05, height=robot.scan_height)
            files[path.stem] = save_map(truth, folder / path.stem)[1]
    return files


def amcl_cost_ms(scenario, occupancy_map, arena, scan_config) -> float:
    """Median ms of one ``ParticleFilter.update`` with 2000 particles, scans ray-cast from the
    arena's start while the odometry moves on by 0.1 m each time."""
    config = dc.replace(scenario.amcl, min_particles=2000, max_particles=2000)
    pf = ParticleFilter(occupancy_map, config, seed=0)
    start = np.array(arena.start_pose())
    pf.set_pose(start, np.diag([0.01, 0.01, 0.01]))
    angles = -math.pi + 2 * math.pi * np.arange(scan_config.samples) / scan_config.samples
    ranges = cast_rays(arena_footprints(arena), start[None, :2], angles + start[2], 3.5)[0]
    times = []
    for k in range(AMCL_UPDATES + 1):
        odom = start + [0.1 * k, 0.0, 0.0]
        t0 = time.perf_counter()
        pf.update(odom, ranges, angles, range_max=scan_config.range_max)
        if k:  # the first only sets the odometry's reference
            times.append(time.perf_counter() - t0)
    return 1000 * statistics.median(times)


RUN_COLUMNS = [
    ["run", "run", "", ""],
    ["sim_time_s", "simulated", "s", ".1f"],
    ["wall_time_s", "wall time", "s", ".1f"],
    ["real_time_factor", "real-time factor", "x", ".2f"],
    ["reached", "goals reached", "", ""],
]
"""(key, header, unit, format) of the ``--json`` table of the room's runs."""

ARENA_COLUMNS = [
    ["arena", "arena", "", ""],
    ["reached", "reached", "", ""],
    ["max_position_error_m", "largest position error", "m", ".3f"],
    ["max_yaw_error_deg", "largest heading error", "deg", ".2f"],
    ["collisions", "collisions", "", "d"],
    ["min_clearance_m", "smallest clearance", "m", ".3f"],
    ["worst_time_ratio", "worst time / (length / top speed)", "", ".2f"],
    ["real_time_factor", "real-time factor", "x", ".2f"],
]
"""(key, header, unit, format) of the ``--json`` table of the random goals."""


def figures(runs: list[dict], arenas: list[dict], amcl_ms: float, settings: dict) -> dict:
    """The room's runs, the random goals per arena and AMCL's cost as ``--json`` figures."""
    median = statistics.median(r["real_time_factor"] for r in runs)
    return {
        "settings": settings,
        "figures": {"real_time_factor": median, "amcl_update_ms": amcl_ms},
        "tables": [
            {
                "title": f"The room's goals, {len(runs)} runs (seeds 0, 1, ...)",
                "columns": RUN_COLUMNS,
                "rows": [*runs, {"run": "median", "real_time_factor": median}],
            },
            {
                "title": f"{settings['goals']} random goals per arena (seed 7)",
                "columns": ARENA_COLUMNS,
                "rows": arenas,
                "note": (
                    f"Errors over the goals reached, against the truth. AMCL alone: "
                    f"{amcl_ms:.2f} ms per update with 2000 particles (median of "
                    f"{AMCL_UPDATES})."
                ),
            },
        ],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=3, help="timed runs of the room's goals")
    parser.add_argument("--goals", type=int, default=10, help="random goals per arena")
    parser.add_argument("--map-dir", type=Path, help="saved maps <arena>.yaml (default: truth)")
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args()
    inputs = RECIPE.load()  # config/navigation_scenario.yaml, config/turtlebot3.yaml
    with tempfile.TemporaryDirectory() as tmp:
        files = map_files(Path(tmp), args.map_dir, inputs.robot)
        measure(args, inputs.scenario, inputs.robot, files)


def measure(args, scenario, robot, files: dict[str, Path]) -> None:
    """Runs and prints what the module docstring says, on the maps in ``files``."""
    top = robot.limits.max_linear_velocity
    maps = {name: load_map(path) for name, path in files.items()}
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    print(
        f"maps: {'saved, ' + str(args.map_dir) if args.map_dir else 'ground truth'}; "
        f"top speed {top:g} m/s; AMCL {scenario.amcl.min_particles}-"
        f"{scenario.amcl.max_particles} particles"
    )
    room_file = next(p for p in shipped_arenas() if p.stem == "room")
    room = load_arena(room_file)
    factors, runs, arena_rows = [], [], []
    for index in range(args.runs):
        run, report = run_arena_goals(room_file, files["room"], seed=index)
        room_goals = run.goals
        factors.append(report.real_time_factor)
        reached = f"{sum(g.reached for g in report.goals)}/{len(room_goals)}"
        times = {key: getattr(report, key) for key, *_ in RUN_COLUMNS[1:4]}
        runs.append({"run": str(index + 1), "reached": reached, **times})
        print(
            f"  room goals run {index + 1}: {report.sim_time_s:.1f} s simulated in "
            f"{report.wall_time_s:.1f} s: {report.real_time_factor:.2f}x, reached "
            f"{sum(g.reached for g in report.goals)}/{len(room_goals)}",
            flush=True,
        )
    print(f"  median real-time factor: {statistics.median(factors):.2f}x (target >= 2)")
    print(f"{args.goals} random goals per arena (seed 7):")
    print(
        "arena      reached  max_err_m  max_yaw_deg  collisions  min_clear_m  worst_t/(L/v)   rtf"
    )
    for path in shipped_arenas():
        arena = load_arena(path)
        goals = random_goals(arena, args.goals, seed=7)
        _, r = run_random_goals(path, maps[path.stem], goals)
        reached = [g for g in r.goals if g.reached]
        worst = max(
            (g.time_s / (g.path_length_m / top) for g in reached if g.path_length_m > 0),
            default=math.nan,
        )
        print(
            f"{path.stem:<10} {len(reached):>3}/{len(goals):<3} "
            f"{max((g.position_error_m for g in reached), default=math.nan):10.3f} "
            f"{max((g.yaw_error_deg for g in reached), default=math.nan):12.2f} "
            f"{r.collisions:>11} {r.min_clearance_m:12.3f} {worst:14.2f} "
            f"{r.real_time_factor:6.2f}",
            flush=True,
        )
        arena_rows.append(
            {
                "arena": path.stem,
                "reached": f"{len(reached)}/{len(goals)}",
                "max_position_error_m": max((g.position_error_m for g in reached), default=None),
                "max_yaw_error_deg": max((g.yaw_error_deg for g in reached), default=None),
                "collisions": r.collisions,
                "min_clearance_m": r.min_clearance_m,
                "worst_time_ratio": worst,
                "real_time_factor": r.real_time_factor,
            }
        )
    cost = amcl_cost_ms(scenario, maps["room"], room, scenario.lidar)
    print(f"AMCL update with 2000 particles: {cost:.2f} ms median (target < 5)")
    if args.json:
        maps_used = f"saved, {args.map_dir}" if args.map_dir else "ground truth"
        settings = {"runs": args.runs, "goals": args.goals, "maps": maps_used}
        result = figures(runs, arena_rows, cost, settings)
        write_atomic(args.json, json.dumps(result, indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
