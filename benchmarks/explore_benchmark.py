"""Benchmark of frontier exploration: ``python benchmarks/explore_benchmark.py [--runs 2]``.

With the default robot and explore scenario (``config/turtlebot3.yaml``,
``config/explore_scenario.yaml``), headless, on every shipped arena, ``--runs`` runs each
(seeds 0, 1, ...): how the run ended, the map's known fraction and IoU, the SLAM's pose RMSE,
collisions, the simulated time against the time the arena's hand-written mapping route takes
(its length at the route follower's speed: the turns not counted, so a little less than a
mapping run takes), the distance driven, frontiers visited and the real-time factor; each run
against the acceptance (explored, known and IoU >= 0.95, no collision, RMSE <= 0.05 m, within
600 s and 1.5 times the route's time, at least 3x real time).

``--json FILE`` also writes the figures for ``python -m benchmarks.report``. Not a test: speeds
depend on the machine.
"""

import argparse
import json
import os
import platform
import statistics

from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.runs import mapping
from drake_sim.runs.explore import RECIPE, ExploreReport
from drake_sim.worlds.arena import load_arena, shipped_arenas
from drake_sim.worlds.route import default_route_file, load_route

COLUMNS = [
    ["arena", "arena", "", ""],
    ["seed", "seed", "", "d"],
    ["end", "end", "", ""],
    ["known_fraction", "known", "", ".3f"],
    ["map_iou", "map IoU", "", ".3f"],
    ["pose_rmse_m", "pose RMSE", "m", ".3f"],
    ["collisions", "collisions", "", "d"],
    ["sim_time_s", "simulated", "s", ".1f"],
    ["route_time_s", "its route's time", "s", ".1f"],
    ["time_ratio", "time / route's", "", ".2f"],
    ["distance_m", "driven", "m", ".1f"],
    ["frontiers_visited", "frontiers", "", "d"],
    ["real_time_factor", "real-time factor", "x", ".2f"],
    ["accepted", "accepted", "", ""],
]
"""(key, header, unit, format) of the ``--json`` per-run table."""


def route_time(arena_file) -> float:
    """s the arena's default mapping route takes at the route follower's speed."""
    scenario = mapping.RECIPE.load().scenario
    arena = load_arena(arena_file)
    route = load_route(default_route_file(arena_file), arena)
    length = mapping.route_length(arena.start_pose(), route.waypoints)
    return length / scenario.route_follower.speed


def meets_acceptance(report: ExploreReport, route_s: float) -> bool:
    """The issue's acceptance for one run on a shipped arena."""
    return (
        report.end == "explored"
        and report.known_fraction >= 0.95
        and report.map_iou >= 0.95
        and report.collisions == 0
        and report.pose_rmse_m <= 0.05
        and report.sim_time_s <= min(600.0, 1.5 * route_s)
        and report.real_time_factor >= 3.0
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=2, help="runs per arena (seeds 0, 1, ...)")
    parser.add_argument("--arenas", nargs="*", help="arena names (default: every shipped one)")
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args()
    arenas = [p for p in shipped_arenas() if not args.arenas or p.stem in args.arenas]
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    print("arena      seed  end        known   iou  rmse_m  col   sim_s route_s ratio  rtf  ok")
    rows = []
    for path in arenas:
        route_s = route_time(path)
        for seed in range(args.runs):
            # The map is not saved (``run``, not ``finish``).
            run = RECIPE.start(overrides=[f"arena={json.dumps(str(path))}"], seed=seed)
            run.run(run.default_duration())
            r = run.report()
            ok = meets_acceptance(r, route_s)
            row = {key: getattr(r, key) for key, *_ in COLUMNS if hasattr(r, key)}
            row.update(arena=path.stem, seed=seed, route_time_s=route_s, accepted=ok)
            row["time_ratio"] = r.sim_time_s / route_s
            rows.append(row)
            print(
                f"{path.stem:<10} {seed:>4}  {r.end:<10} {r.known_fraction:5.3f} "
                f"{r.map_iou:5.3f} {r.pose_rmse_m:7.3f} {r.collisions:4d} {r.sim_time_s:7.1f} "
                f"{route_s:7.1f} {row['time_ratio']:5.2f} {r.real_time_factor:4.2f}  "
                f"{'yes' if ok else 'NO'}",
                flush=True,
            )
    if args.json:
        figures = {
            "settings": {"runs": args.runs},
            "figures": {
                "real_time_factor": statistics.median(r["real_time_factor"] for r in rows),
                "max_time_ratio": max(r["time_ratio"] for r in rows),
                "accepted": sum(r["accepted"] for r in rows),
                "runs": len(rows),
            },
            "tables": [
                {
                    "title": f"Per run ({args.runs} seeds per arena)",
                    "columns": COLUMNS,
                    "rows": rows,
                    "note": "Accepted: explored, known and map IoU >= 0.95, no collision, pose "
                    "RMSE <= 0.05 m, within 600 s and 1.5 times the route's time, at least 3x "
                    "real time.",
                }
            ],
        }
        write_atomic(args.json, json.dumps(figures, indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
