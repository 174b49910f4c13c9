"""Navigation on real map_server maps: ``python benchmarks/real_maps_benchmark.py``.

The TurtleBot3 world (``turtlebot3_navigation2``'s map), nav2's 30 x 15 m depot and its
30 x 50 m warehouse, each simulated from its map file alone (``navigate --map M --start X Y
YAW``: the occupied cells are the walls), localised by AMCL from the true start as its pose
estimate, and on the TurtleBot3 world and the depot also by global localisation (no first
guess: the robot turns and drives short legs until AMCL has settled); each with the DWA and
with the TEB local planner (``--planners``). The maps are third-party files, not in the
repository: ``--maps DIR`` (default ``$DRAKE_SIM_REAL_MAPS``, else ``shared/real_ros/maps``
beside the checkout).

Per run: goals reached, the largest true position and heading errors at arrival, collisions,
AMCL's mean error, and the real-time factor. ``--json FILE`` writes the figures for ``python -m
benchmarks.report``. Not a test: the speeds depend on the machine.
"""

import argparse
import json
import os
import sys
from pathlib import Path

from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.runs.navigate import RECIPE

CASES = (
    # name, map file (under the maps folder), start [x, y, yaw_deg], goals [[x, y, yaw_deg]]
    ("turtlebot3_world", "turtlebot3_main/map.yaml", [-2.0, -0.5, 0.0],
     [[0.5, -1.8, 0.0], [1.8, 0.5, 90.0], [-0.5, 1.8, 180.0]]),
    ("depot", "nav2_main/depot.yaml", [0.0, 0.0, 0.0], [[10.0, 5.0, 90.0]]),
    ("warehouse", "nav2_main/warehouse.yaml", [0.2, 1.8, 0.0], [[11.0, -10.8, 0.0]]),
    # Goals in open floor, few things within the lidar's 3.5 m on the way (#39: AMCL's
    # estimate is then 6 to 18 cm off at arrival).
    ("depot_open", "nav2_main/depot.yaml", [0.0, 0.0, 0.0], [[1.83, 1.45, 148.0]]),
    ("warehouse_open", "nav2_main/warehouse.yaml", [0.2, 1.8, 0.0], [[-7.5, 5.02, -161.0]]),
)  # fmt: skip
"""The runs: each map's start and goals."""
GLOBAL_LOCALIZATION = ("turtlebot3_world", "depot")
"""The maps also run from no first guess (the warehouse's repeated shelves can fool it: see
``docs/navigation.md``)."""


def maps_folder(given: Path | None) -> Path:
    """``given``, else ``$DRAKE_SIM_REAL_MAPS``, else ``shared/real_ros/maps`` beside the
    checkout."""
    if given is not None:
        return given
    if os.environ.get("DRAKE_SIM_REAL_MAPS"):
        return Path(os.environ["DRAKE_SIM_REAL_MAPS"])
    return Path(__file__).resolve().parents[2] / "shared" / "real_ros" / "maps"


def run_case(map_file: Path, start, goals, planner: str, global_localization: bool) -> dict:
    """One map driven from its start to its goals; the run's row."""
    run = RECIPE.start(
        overrides=[f"world={json.dumps(str(map_file))}", f"start={json.dumps(start)}",
                   f"navigator.local_planner={planner}"],
        map=str(map_file),
        goals=[[x, y, yaw * 3.141592653589793 / 180.0] for x, y, yaw in goals],
        global_localization=global_localization,
    )  # fmt: skip
    run.run(run.default_duration() + (30.0 if global_localization else 0.0))
    report = run.report()
    reached = [g for g in report.goals if g.reached]
    return {
        "planner": planner,
        "localisation": "global" if global_localization else "pose estimate",
        "reached": f"{len(reached)} of {len(goals)}",
        "all_reached": len(reached) == len(goals),
        "max_position_error_m": max((g.position_error_m for g in reached), default=None),
        "max_yaw_error_deg": max((g.yaw_error_deg for g in reached), default=None),
        "collisions": report.collisions,
        "localization_error_mean_m": report.localization_error_mean_m,
        "real_time_factor": report.real_time_factor,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--maps", type=Path, help="the real maps' folder")
    parser.add_argument("--planners", nargs="+", default=["dwa", "teb"])
    parser.add_argument("--json", type=output_file("figures"), help="write the figures here")
    args = parser.parse_args()
    folder = maps_folder(args.maps)
    rows = []
    for name, relative, start, goals in CASES:
        map_file = folder / relative
        if not map_file.is_file():
            print(f"error: no {map_file} (give --maps DIR)", file=sys.stderr)
            sys.exit(2)
        modes = (False, True) if name in GLOBAL_LOCALIZATION else (False,)
        for planner in args.planners:
            for global_localization in modes:
                row = {"map": name, **run_case(map_file, start, goals, planner,
                                                global_localization)}  # fmt: skip
                rows.append(row)
                print(
                    f"{name} {planner} {row['localisation']}: {row['reached']} reached, "
                    f"max error {row['max_position_error_m']} m / {row['max_yaw_error_deg']} "
                    f"deg, collisions {row['collisions']}, {row['real_time_factor']:.1f}x",
                    flush=True,
                )
    columns = [
        ["map", "map", "", ""],
        ["planner", "local planner", "", ""],
        ["localisation", "AMCL from", "", ""],
        ["reached", "goals reached", "", ""],
        ["max_position_error_m", "largest true position error", "m", ".3f"],
        ["max_yaw_error_deg", "largest heading error", "deg", ".2f"],
        ["collisions", "collisions", "", "d"],
        ["localization_error_mean_m", "AMCL mean error", "m", ".3f"],
        ["real_time_factor", "real-time factor", "", ".1f"],
    ]
    result = {
        "figures": {
            f"{r['map']}_{r['planner']}_{'global' if r['localisation'] == 'global' else 'pose'}"
            f"_rtf": r["real_time_factor"]
            for r in rows
        },
        "tables": [
            {"title": "Real maps, simulated from the map files", "columns": columns, "rows": rows}
        ],  # fmt: skip
    }
    if args.json:
        write_atomic(args.json, json.dumps(result, indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
