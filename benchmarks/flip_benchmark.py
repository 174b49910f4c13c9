"""Benchmark of the flipping robot: ``python benchmarks/flip_benchmark.py [--runs 3]``.

Runs the default scenario (config/flip.yaml, config/ddrive.yaml) headless for 20 simulated
seconds, several times, and prints each run's flips, lateral drift, odometry error and
real-time factor, then their medians; ``--json FILE`` also writes them for
``python -m benchmarks.report``. Not a test: speeds depend on the machine.
"""

import argparse
import json
import os
import platform
import statistics

from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.runs.flip import RECIPE

COLUMNS = (
    ("flips", "flips", "{:.0f}"),
    ("drift_m", "max_lateral_deviation_m", "{:.3f}"),
    ("extent_m", "travel_extent_m", "{:.2f}"),
    ("odom_err_m", "odometry_error_m", "{:.3f}"),
    ("naive_err_m", "naive_odometry_error_m", "{:.3f}"),
    ("distance_m", "distance_travelled_m", "{:.1f}"),
    ("wall_s", "wall_time_s", "{:.2f}"),
    ("rtf", "real_time_factor", "{:.1f}"),
)
"""(printed name, report key, format) of each column."""

HEADERS = {
    "flips": ("flips", ""),
    "max_lateral_deviation_m": ("largest drift off the line", "m"),
    "travel_extent_m": ("travel extent", "m"),
    "odometry_error_m": ("odometry error", "m"),
    "naive_odometry_error_m": ("naive odometry error", "m"),
    "distance_travelled_m": ("distance travelled", "m"),
    "wall_time_s": ("wall time", "s"),
    "real_time_factor": ("real-time factor", "x"),
}
"""(header, unit) of each column in the JSON figures."""


def figures(rows: list[dict], duration: float) -> dict:
    """The runs' figures for ``--json``: settings, the medians, and a table of the runs."""
    medians = {key: statistics.median(r[key] for r in rows) for _, key, _ in COLUMNS}
    # "{:.3f}" is the format spec ".3f".
    columns = [["run", "run", "", ""]] + [
        [key, *HEADERS[key], fmt[2:-1]] for _, key, fmt in COLUMNS
    ]
    table_rows = [
        {"run": str(index), **{key: row[key] for _, key, _ in COLUMNS}}
        for index, row in enumerate(rows, 1)
    ]
    return {
        "settings": {"runs": len(rows), "duration_s": duration},
        "figures": medians,
        "tables": [
            {
                "title": f"{len(rows)} runs of {duration:g} simulated s, and their medians",
                "columns": columns,
                "rows": [*table_rows, {"run": "median", **medians}],
            }
        ],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--duration", type=float, default=20.0, help="simulated seconds")
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    print(" ".join(f"{name:>12}" for name, _, _ in COLUMNS))
    rows = []
    for _ in range(args.runs):
        run = RECIPE.start()  # config/flip.yaml, config/ddrive.yaml
        run.run(args.duration, progress=True)  # A bar on a terminal only.
        row = run.report().to_dict()
        rows.append(row)
        print(" ".join(f"{fmt.format(row[key]):>12}" for _, key, fmt in COLUMNS))
    result = figures(rows, args.duration)
    medians = result["figures"]
    print(" ".join(f"{fmt.format(medians[key]):>12}" for _, key, fmt in COLUMNS), "(median)")
    if args.json:
        write_atomic(args.json, json.dumps(result, indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
