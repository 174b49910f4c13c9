"""Pick-and-place benchmark: the default scene (repeated) and random scenes, in both modes.

    python benchmarks/pickplace_benchmark.py [--repeats 5] [--random 20] [--seed 7]
        [--modes physics kinematic] [--scenario FILE] [--report FILE] [--json FILE]

Prints, per mode: successes, place error (median, max), planning time per task (median; the
sum of every step's planning, the feasibility check included), and the real-time factor
(simulated time over wall time of the whole task, planning included; median). ``--report``
writes every task's report; ``--json`` the summary, for ``python -m benchmarks.report``.
"""

import argparse
import dataclasses as dc
import json
import statistics
import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.runs.pickplace import RECIPE
from planning import planner_kernels
from planning.task.scene_generator import random_scene


def _progress(items, label):
    return tqdm(items, desc=label, leave=False, file=sys.stderr, disable=None)


def run_one(inputs, mode, scene=None):
    """One task through the app's recipe, in ``mode`` (on ``scene`` when given): its report."""
    scenario = dc.replace(inputs.scenario, mode=mode, scene=scene or inputs.scenario.scene)
    run = RECIPE.make_run(dc.replace(inputs, scenario=scenario), {})
    run.run()
    return run.task_report.to_dict()


COLUMNS = [
    ["mode", "mode", "", ""],
    ["scenes", "scenes", "", ""],
    ["success", "done", "", ""],
    ["place_error_median_mm", "place error, median", "mm", ".1f"],
    ["place_error_max_mm", "place error, max", "mm", ".1f"],
    ["planning_time_s", "planning per task, median", "s", ".3f"],
    ["real_time_factor", "real-time factor, median", "x", ".2f"],
]
"""(key, header, unit, format) of the ``--json`` table's columns."""


def summarize(mode, scenes, rows) -> dict:
    """Prints one line on the tasks ``rows`` (and a line per failure); returns it as a row of
    the ``--json`` table (place errors over the tasks done)."""
    ok = [r for r in rows if r["success"]]
    errors = [1000 * r["place_error_m"] for r in ok]
    planning = statistics.median(r["planning_time_s"] for r in rows)
    rtf = [r["real_time_factor"] for r in rows if r["real_time_factor"]]
    summary = {
        "mode": mode,
        "scenes": scenes,
        "success": f"{len(ok)}/{len(rows)}",
        "success_rate": len(ok) / len(rows),
        "place_error_median_mm": float(np.median(errors)) if errors else None,
        "place_error_max_mm": max(errors, default=None),
        "planning_time_s": planning,
        "real_time_factor": statistics.median(rtf) if rtf else None,
        "failures": [f"{r['failed_step']}: {r['reason']}" for r in rows if not r["success"]],
    }
    line = f"{f'{mode}, {scenes}':<28} success {summary['success']}"
    if errors:
        median, worst = summary["place_error_median_mm"], summary["place_error_max_mm"]
        line += f"  place error median {median:.1f} mm max {worst:.1f} mm"
    line += f"  planning median {planning:.3f} s"
    if rtf:
        line += f"  RTF median {summary['real_time_factor']:.2f}"
    print(line, flush=True)
    for failure in summary["failures"]:
        print(f"    failed: {failure}")
    return summary


def figures(summaries: list[dict], settings: dict) -> dict:
    """The summaries as ``--json`` figures; the headline is the default scene's, kinematic
    mode if it ran, else the first mode's."""
    default = [s for s in summaries if s["scenes"].startswith("default")]
    headline = next((s for s in default if s["mode"] == "kinematic"), default[0])
    failures = [f"{s['mode']}, {s['scenes']}: {f}" for s in summaries for f in s["failures"]]
    note = "Failed: " + "; ".join(failures) + "." if failures else "No task failed."
    return {
        "settings": settings,
        "figures": {k: headline[k] for k in ("planning_time_s", "success_rate", "success")},
        "tables": [{"title": "Per mode", "columns": COLUMNS, "rows": summaries, "note": note}],
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--random", type=int, default=20)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--modes", nargs="+", default=["physics", "kinematic"])
    parser.add_argument("--scenario", type=Path, help="pick-and-place scenario YAML")
    parser.add_argument("--report", type=output_file("report"), help="every task's report")
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args(argv)
    # Measure the compiled planner: on a fresh install, wait for its kernels' build.
    planner_kernels.wait_ready(progress=planner_kernels.ProgressLine("benchmark"))
    inputs = RECIPE.load(scenario=args.scenario)
    config = inputs.scenario
    results, summaries = {}, []
    for mode in args.modes:
        rows = [run_one(inputs, mode) for _ in _progress(range(args.repeats), f"{mode} default")]
        summaries.append(summarize(mode, f"default x{args.repeats}", rows))
        rng = np.random.default_rng(args.seed)
        scenes = [random_scene(rng, config.scene) for _ in range(args.random)]
        random_rows = [run_one(inputs, mode, s) for s in _progress(scenes, f"{mode} random")]
        if random_rows:
            summaries.append(summarize(mode, f"{args.random} random", random_rows))
        results[mode] = {"default": rows, "random": random_rows}
    if args.report:
        write_atomic(args.report, json.dumps(results, indent=1) + "\n", "report")
    if args.json:
        settings = {"repeats": args.repeats, "random": args.random, "seed": args.seed}
        result = figures(summaries, settings | {"modes": args.modes})
        write_atomic(args.json, json.dumps(result, indent=1) + "\n", "figures")
    return 0


if __name__ == "__main__":
    sys.exit(main())
