"""BARN navigation benchmark with no prior map: ``python benchmarks/barn_benchmark.py``.

BARN (Perille et al., "Benchmarking Metric Ground Navigation", SSRR 2020): 300 obstacle
courses of cylinders, each with a start in a closed pen and a goal 10 m ahead past the field. Its
published move_base + DWA baseline (no prior map, rolling costmaps) succeeds in 88 % of runs
with 4.8 % collisions. The worlds are third-party data, not in the repository: ``--barn DIR``
(default ``$DRAKE_SIM_BARN``, else ``shared/benchmarks/barn`` beside the checkout) holds them as
this project's arenas and goal files (``world_N.yaml``, ``world_N.goals.yaml``).

Each sampled world (``--worlds K``: K evenly spread over 0..299, or ``--world N`` repeated) is
driven by each local planner (``--planners dwa teb``) as ``python -m drake_sim.navigate --arena
world_N.yaml --goals world_N.goals.yaml`` does with no ``--map``: the live SLAM localises, the
costmaps fill from the lidar. A world succeeds when its goal is reached with 0 collisions within
BARN's 100 simulated seconds. Printed per world and in all; ``--json FILE`` writes the figures
for ``python -m benchmarks.report``. Not a test: the speeds depend on the machine.
"""

import argparse
import json
import os
import statistics
import sys
from pathlib import Path

from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.runs.navigate import RECIPE

TIME_LIMIT_S = 100.0
"""BARN's limit on a run, simulated seconds."""

WORLDS = 300


def barn_folder(given: Path | None) -> Path:
    """``given``, else ``$DRAKE_SIM_BARN``, else ``shared/benchmarks/barn`` beside the checkout."""
    if given is not None:
        return given
    if os.environ.get("DRAKE_SIM_BARN"):
        return Path(os.environ["DRAKE_SIM_BARN"])
    return Path(__file__).resolve().parents[2] / "shared" / "benchmarks" / "barn"


def sample(count: int) -> list[int]:
    """``count`` world numbers evenly spread over 0..299."""
    return sorted({round(i * WORLDS / count) for i in range(count)})


def run_world(folder: Path, n: int, seed: int, planner: str = "dwa") -> dict:
    """One world driven with no prior map by the local ``planner`` (dwa, teb); its row."""
    arena = folder / f"world_{n}.yaml"
    run = RECIPE.start(
        overrides=[f"arena={json.dumps(str(arena))}", f"navigator.local_planner={planner}"],
        seed=seed,
        goals=str(folder / f"world_{n}.goals.yaml"),
        no_map=True,
    )
    run.run(run.default_duration())
    report = run.report()
    (goal,) = report.goals or [None]
    reached = bool(goal and goal.reached)
    time_s = goal.time_s if goal else report.sim_time_s
    return {
        "world": n,
        "planner": planner,
        "success": reached and report.collisions == 0 and time_s <= TIME_LIMIT_S,
        "reached": reached,
        "collisions": report.collisions,
        "time_s": time_s,
        "position_error_m": goal.position_error_m if reached else None,
        "min_clearance_m": report.min_clearance_m,
        "real_time_factor": report.real_time_factor,
    }


def summary(rows: list[dict]) -> dict:
    """Success and collision rates, the median time of the successes, the median real-time
    factor."""
    done = [r for r in rows if r["success"]]
    return {
        "worlds": len(rows),
        "success_rate": len(done) / len(rows),
        "collision_rate": sum(r["collisions"] > 0 for r in rows) / len(rows),
        "median_time_s": statistics.median(r["time_s"] for r in done) if done else None,
        "real_time_factor": statistics.median(r["real_time_factor"] for r in rows),
    }


def figures(rows: list[dict], seed: int) -> dict:
    """The summary per planner (``<planner>_<figure>``) and the table for
    ``benchmarks.report``."""
    planners = list(dict.fromkeys(r["planner"] for r in rows))
    columns = [
        ["world", "world", "", "d"],
        ["planner", "local planner", "", ""],
        ["success", "success", "", ""],
        ["collisions", "collisions", "", "d"],
        ["time_s", "time", "s", ".1f"],
        ["position_error_m", "true position error", "m", ".3f"],
        ["min_clearance_m", "closest to a cylinder", "m", ".3f"],
        ["real_time_factor", "real-time factor", "", ".1f"],
    ]
    per = {p: summary([r for r in rows if r["planner"] == p]) for p in planners}
    title = ", ".join(
        f"{p}: {round(per[p]['success_rate'] * per[p]['worlds'])} of {per[p]['worlds']}"
        for p in planners
    )
    return {
        "settings": {"seed": seed, "worlds": sorted({r["world"] for r in rows})},
        "figures": {f"{p}_{k}": v for p in planners for k, v in per[p].items()},
        "tables": [
            {
                "title": f"Goal reached, no collision, within {TIME_LIMIT_S:g} s: {title} "
                f"(seed {seed})",
                "columns": columns,
                "rows": rows,
                "note": "BARN's move_base + DWA baseline: 88 % success, 4.8 % collisions.",
            }
        ],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--barn", type=Path, help="the BARN arenas' folder")
    parser.add_argument("--worlds", type=int, default=10, help="worlds sampled evenly")
    parser.add_argument("--world", type=int, action="append", help="these worlds instead")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--planners", nargs="+", default=["dwa", "teb"], help="local planners (dwa, teb)"
    )
    parser.add_argument("--json", type=output_file("figures"), help="write the figures here")
    args = parser.parse_args()
    folder = barn_folder(args.barn)
    if not (folder / "world_0.yaml").is_file():
        print(f"error: no BARN worlds in {folder} (give --barn DIR)", file=sys.stderr)
        sys.exit(2)
    rows = []
    for n in args.world or sample(args.worlds):
        for planner in args.planners:
            row = run_world(folder, n, args.seed, planner)
            rows.append(row)
            print(
                f"world {n:3d} {planner}: {'success' if row['success'] else 'FAILED '} reached "
                f"{row['reached']}, collisions {row['collisions']}, {row['time_s']:.1f} s, "
                f"{row['real_time_factor']:.1f}x real time",
                flush=True,
            )
    result = figures(rows, args.seed)
    for planner in args.planners:
        got = summary([r for r in rows if r["planner"] == planner])
        print(
            f"{planner}: {got['success_rate']:.0%} of {got['worlds']} worlds succeeded, "
            f"collisions in {got['collision_rate']:.0%}, median real-time factor "
            f"{got['real_time_factor']:.1f}"
        )
    if args.json:
        write_atomic(args.json, json.dumps(result, indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
