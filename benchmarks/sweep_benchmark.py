"""Benchmark of the sweep's local backend: ``python benchmarks/sweep_benchmark.py [--limit N]``.

Runs the first ``--limit`` rollouts (default all 60) of ``config/sweeps/flip_robot_variants.yaml``
with ``--workers 1`` and then ``--workers 2`` (each into a fresh temporary folder), and prints
both wall times and the speed-up. Each rollout is independent and builds its own diagram, so on
an idle machine with two free cores the speed-up should approach 2 (target: at least 1.7); the
fixed cost of spawning workers (each imports Drake once) is included, as a user would see it.

``--json FILE`` also writes the figures for ``python -m benchmarks.report``. Not a test: times
depend on the machine and on what else runs on it.
"""

import argparse
import csv
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic

SWEEP = Path(__file__).resolve().parent.parent / "config" / "sweeps" / "flip_robot_variants.yaml"
TARGET_SPEEDUP = 1.7


def timed_sweep(workers: int, limit: int | None) -> tuple[float, float]:
    """Wall time (s) of the sweep with ``workers`` local workers, in a fresh output folder, and
    the sum of its rollouts' own wall times (s; what the workers spent inside rollouts)."""
    with tempfile.TemporaryDirectory() as out:
        argv = [sys.executable, "-m", "drake_sim.sweep", str(SWEEP), "--workers", str(workers)]
        argv += ["--out", out] + (["--limit", str(limit)] if limit else [])
        start = time.perf_counter()
        subprocess.run(argv, check=True, stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - start
        with (Path(out) / "results.csv").open(newline="") as f:
            inside = sum(float(row["wall_time_s"]) for row in csv.DictReader(f))
        return wall, inside


def figures(walls: dict[int, tuple[float, float]], limit: int | None) -> dict:
    """The wall times (s) by worker count, (whole sweep, inside rollouts), as ``--json``
    figures."""
    rows = [
        {"workers": n, "wall_time_s": wall, "rollouts_s": inside}
        | ({"overhead_s": wall - inside} if n == 1 else {})  # one worker: the rest is overhead
        for n, (wall, inside) in walls.items()
    ]
    speedup = walls[1][0] / walls[2][0]
    columns = [
        ["workers", "workers", "", "d"],
        ["wall_time_s", "wall time", "s", ".1f"],
        ["rollouts_s", "inside rollouts, summed over workers", "s", ".1f"],
        ["overhead_s", "start-up etc., one worker", "s", ".1f"],
    ]
    note = (
        f"Speed-up with two workers: {speedup:.2f}x (target {TARGET_SPEEDUP}x on two free cores)."
    )
    return {
        "settings": {"limit": limit or "all", "sweep": SWEEP.name},
        "figures": {"speedup": speedup},
        "tables": [
            {
                "title": f"{SWEEP.name}, {limit or 'all'} rollouts",
                "columns": columns,
                "rows": rows,
                "note": note,
            }
        ],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--limit", type=int, help="only the first N rollouts (default: all)")
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"machine: {platform.node()}, {platform.processor() or platform.machine()}, "
        f"{os.cpu_count()} CPUs, Python {platform.python_version()}, load average {load:.2f}"
    )
    print(f"sweep: {SWEEP.name}, {args.limit or 'all'} rollouts")
    walls = {1: timed_sweep(1, args.limit)}
    one, inside = walls[1]
    print(
        f"--workers 1: {one:6.1f} s (rollouts {inside:.1f} s, start-up etc. {one - inside:.1f} s)"
    )
    walls[2] = timed_sweep(2, args.limit)
    two, inside = walls[2]
    print(f"--workers 2: {two:6.1f} s (rollouts {inside:.1f} s summed over both workers)")
    speedup = one / two
    verdict = "meets" if speedup >= TARGET_SPEEDUP else "below"
    print(f"speed-up: {speedup:.2f}x ({verdict} the {TARGET_SPEEDUP}x target)")
    if args.json:
        write_atomic(args.json, json.dumps(figures(walls, args.limit), indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
