"""Pick-and-place benchmark: the default scene (repeated) and random scenes, in both modes.

    python benchmarks/pickplace_benchmark.py [--repeats 5] [--random 20] [--seed 7]
        [--modes physics kinematic] [--scenario FILE] [--report FILE]

Prints, per mode: successes, place error (median, max), planning time per task (median; the
sum of every step's planning, the feasibility check included), and the real-time factor
(simulated time over wall time of the whole task, planning included; median).
"""

import argparse
import dataclasses as dc
import json
import statistics
import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from diagrams.pickplace_scenario import load_pickplace_scenario
from diagrams.planning_station import make_planning_station
from planning.task.pick_place import PickPlaceTask
from planning.task.scene_generator import random_scene


def _progress(items, label):
    return tqdm(items, desc=label, leave=False, file=sys.stderr, disable=None)


def run_one(config, mode):
    report = PickPlaceTask(make_planning_station(config, mode=mode), config.task).run()
    return report.to_dict()


def summarize(label, rows):
    ok = [r for r in rows if r["success"]]
    errors = [r["place_error_m"] for r in ok]
    planning = [r["planning_time_s"] for r in rows]
    rtf = [r["real_time_factor"] for r in rows if r["real_time_factor"]]
    line = f"{label:<28} success {len(ok)}/{len(rows)}"
    if errors:
        median, worst = 1000 * np.median(errors), 1000 * max(errors)
        line += f"  place error median {median:.1f} mm max {worst:.1f} mm"
    line += f"  planning median {statistics.median(planning):.3f} s"
    line += f"  RTF median {statistics.median(rtf):.2f}"
    print(line, flush=True)
    for r in rows:
        if not r["success"]:
            print(f"    failed: {r['failed_step']}: {r['reason']}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--random", type=int, default=20)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--modes", nargs="+", default=["physics", "kinematic"])
    parser.add_argument("--scenario", type=Path, help="pick-and-place scenario YAML")
    parser.add_argument("--report", type=Path)
    args = parser.parse_args(argv)
    config = load_pickplace_scenario(args.scenario)
    results = {}
    for mode in args.modes:
        rows = [run_one(config, mode) for _ in _progress(range(args.repeats), f"{mode} default")]
        summarize(f"{mode}, default x{args.repeats}", rows)
        rng = np.random.default_rng(args.seed)
        scenes = [random_scene(rng, config.scene) for _ in range(args.random)]
        random_rows = [
            run_one(dc.replace(config, scene=s), mode) for s in _progress(scenes, f"{mode} random")
        ]
        if random_rows:
            summarize(f"{mode}, {args.random} random", random_rows)
        results[mode] = {"default": rows, "random": random_rows}
    if args.report:
        args.report.write_text(json.dumps(results, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
