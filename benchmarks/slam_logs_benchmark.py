"""Offline SLAM on the classic real 2D laser logs, scored as the published systems are:
``python benchmarks/slam_logs_benchmark.py --data ../shared/benchmarks/slam_carmen``.

For each log of Kümmerle et al. 2009's benchmark that is in ``--data`` (Intel, Freiburg 079 and
ACES as ROS 1 bags with GMapping's beam angles, MIT CSAIL as its CARMEN log; the data are never
copied into the repository), every scan goes through ``ScanMatchingSlam`` with the mapping
scenario's defaults, as ``python -m drake_sim.mapping --log`` runs it, and the trajectory is
scored on the log's relations (``drake_sim.tools.slam_relations``: mean and standard deviation
of the translational and rotational errors). Printed per log: scans, the log's duration, the
wall time and the real-time factor, the cost per scan (median and 95th percentile, ms), the
errors, the matches rejected and odometry jumps. ``--limit N`` maps the first N scans only
(relations outside them are counted as missing); ``--json FILE`` writes the table. Not a test:
speeds depend on the machine.
"""

import argparse
import dataclasses as dc
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.base.laser_logs import read_log
from drake_sim.systems.estimation.log_slam import run_log_slam
from drake_sim.systems.estimation.scan_matching_slam import SlamConfig
from drake_sim.tools.slam_relations import load_relations, score

LOGS = {  # name: (file, beam angles, relations)
    "intel": ("intel.orig.bag", "gmapping", "intel.relations"),
    "fr079": ("fr079.orig.bag", "gmapping", "fr079.relations"),
    "aces": ("aces.orig.bag", "gmapping", "aces.relations"),
    "mit-csail": ("mit-csail.clf", "log", "mit-csail.relations"),
}


def run_one(data: Path, name: str, limit: int | None) -> dict:
    """One log's row."""
    file, angles, relations = LOGS[name]
    log = read_log(data / file, angles=angles)
    if limit is not None:
        log = dc.replace(log, scans=log.scans[:limit])
    costs = []
    last = [time.perf_counter()]

    def tick(done, total):
        now = time.perf_counter()
        costs.append((now - last[0]) / 100.0)
        last[0] = now

    start = time.perf_counter()
    result = run_log_slam(log, SlamConfig(), progress=tick)
    wall = time.perf_counter() - start
    span = float(np.ptp(result.times))
    s = score(result.times, result.poses, load_relations(data / relations))
    return {
        "log": name,
        "scans": result.scans,
        "log_duration_s": span,
        "wall_time_s": wall,
        "real_time_factor": span / wall,
        "ms_per_scan_median": 1000.0 * float(np.median(costs)) if costs else None,
        "ms_per_scan_p95": 1000.0 * float(np.percentile(costs, 95)) if costs else None,
        "map_size_m": result.slam.config.map_size,
        "rejected_matches": result.slam.rejected,
        "odometry_jumps": result.odometry_jumps,
        **dc.asdict(s),
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--data", type=Path, default=Path("../shared/benchmarks/slam_carmen"))
    p.add_argument("--logs", nargs="+", choices=sorted(LOGS), default=list(LOGS))
    p.add_argument("--limit", type=int, help="the first N scans of each log only")
    p.add_argument("--json", type=output_file("json"), help="write the table here")
    args = p.parse_args()
    present = [n for n in args.logs if (args.data / LOGS[n][0]).exists()]
    if not present:
        raise SystemExit(f"no logs in {args.data} (the shared SLAM datasets)")
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    rows = []
    for name in present:
        row = run_one(args.data, name, args.limit)
        rows.append(row)
        print(
            f"{name:10s} {row['scans']:6d} scans, {row['log_duration_s']:7.1f} s of log in "
            f"{row['wall_time_s']:6.1f} s ({row['real_time_factor']:5.2f}x real time; "
            f"{row['ms_per_scan_median']:.1f} / {row['ms_per_scan_p95']:.1f} ms per scan), "
            f"{row['relations']} relations ({row['missing']} missing): "
            f"{row['trans_mean_m']:.3f} +- {row['trans_std_m']:.3f} m, "
            f"{row['rot_mean_deg']:.2f} +- {row['rot_std_deg']:.2f} deg; "
            f"{row['rejected_matches']} rejected, {row['odometry_jumps']} jumps",
            flush=True,
        )
    if args.json:
        write_atomic(args.json, json.dumps({"rows": rows}, indent=2) + "\n", "json")


if __name__ == "__main__":
    main()
