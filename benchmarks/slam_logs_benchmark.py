"""Offline SLAM on the classic real 2D laser logs, scored as the published systems are:
``python benchmarks/slam_logs_benchmark.py [--data DIR]``.

For each log of Kümmerle et al. 2009's benchmark that is in ``--data`` (default
``$DRAKE_SIM_SLAM_LOGS``, else ``shared/benchmarks/slam_carmen`` beside the checkout: Intel,
Freiburg 079 and ACES as ROS 1 bags with GMapping's beam angles, MIT CSAIL as its CARMEN log;
the data are never copied into the repository), every scan goes through the mapping scenario's
SLAM with its pose graph and loop closures, as ``python -m drake_sim.mapping --log`` runs it
(``--no-loop-closure``: the scan matcher alone), and the laser's trajectory (the datasets'
relations are poses of the laser, not of the odometry's base: ``docs/mapping.md``) is scored on
the log's relations (``drake_sim.tools.slam_relations``: mean and standard deviation of the
translational and rotational errors). Printed per log: scans, the log's duration, the wall time
and the real-time factor, the cost per 100 scans (median and 95th percentile, ms per scan), the
errors, the matches rejected, odometry jumps and loop closures, beside the published
translational errors (``PUBLISHED``). ``--centimetres`` rounds the ranges to 1 cm first (as a
CARMEN log stores them); ``--carmen`` writes each bag as a CARMEN log of ``FLASER`` lines (as
the datasets' ``.clf`` files are: ranges in centimetres, the scanner's maximum for no return,
no laser offset) into a temporary folder and maps that, as a user with the ``.clf`` file
would; ``--noise-runs N`` maps each log N more times with seeded 1 mm noise
on the ranges and gives the least and most error over them (``--jobs N`` maps N of those at a
time, after the plain runs, which run one at a time). ``--limit N`` maps the first N
scans only (relations outside them are counted as missing); ``--json FILE`` writes the figures
for ``python -m benchmarks.report``. Not a test: speeds depend on the machine.
"""

import argparse
import dataclasses as dc
import json
import os
import platform
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from drake_sim.base.carmen_logs import write_flaser
from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.base.laser_logs import read_log
from drake_sim.base.planar import compose
from drake_sim.systems.estimation.log_slam import run_log_slam
from drake_sim.systems.estimation.slam_config import SlamConfig
from drake_sim.tools.slam_relations import load_relations, score

PUBLISHED = {  # m, mean translational error: GMapping, graph mapping (Kümmerle et al. 2009,
    # Table 2), Cartographer (Hess et al. 2016, Table I)
    "intel": (0.070, 0.031, 0.0229),
    "fr079": (0.061, 0.056, 0.0452),
    "aces": (0.060, 0.044, 0.0375),
    "mit-csail": (0.049, 0.004, 0.0319),
}
NOISE = 0.001
"""m: the standard deviation of the seeded noise of ``--noise-runs``."""
LOGS = {  # name: (file, beam angles, relations)
    "intel": ("intel.orig.bag", "gmapping", "intel.relations"),
    "fr079": ("fr079.orig.bag", "gmapping", "fr079.relations"),
    "aces": ("aces.orig.bag", "gmapping", "aces.relations"),
    "mit-csail": ("mit-csail.clf", "log", "mit-csail.relations"),
}


def run_one(
    data: Path,
    name: str,
    limit: int | None,
    *,
    loop_closure: bool = True,
    noise_seed: int | None = None,
    centimetres: bool = False,
    carmen: bool = False,
) -> dict:
    """One log's row: mapped as ``mapping --log`` maps it (``loop_closure`` on or off), the
    ranges optionally rounded to centimetres (as CARMEN logs store them) and with seeded
    1 mm Gaussian noise added (``noise_seed``); with ``carmen``, a bag is written as a CARMEN
    log first and read back from it."""
    file, angles, relations = LOGS[name]
    log = read_log(data / file, angles=angles)
    if carmen and not file.endswith(".clf"):
        with tempfile.TemporaryDirectory() as folder:
            log = read_log(write_flaser(log, Path(folder) / f"{name}.clf"))
    scans = log.scans[:limit] if limit is not None else log.scans
    if centimetres or noise_seed is not None:
        rng = None if noise_seed is None else np.random.default_rng(noise_seed)
        scans = [dc.replace(s, ranges=_perturbed(s.ranges, rng, centimetres)) for s in scans]
    log = dc.replace(log, scans=scans)
    costs = []
    last = [time.perf_counter()]

    def tick(done, total):
        now = time.perf_counter()
        costs.append((now - last[0]) / 100.0)
        last[0] = now

    config = SlamConfig()
    config = dc.replace(config, loop_closure=dc.replace(config.loop_closure, enabled=loop_closure))
    start = time.perf_counter()
    result = run_log_slam(log, config, progress=tick)
    wall = time.perf_counter() - start
    span = float(np.ptp(result.times))
    sensor = compose(result.poses, result.slam.X_base_sensor)  # the relations' frame
    s = score(result.times, sensor, load_relations(data / relations))
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
        "loop_closures": result.loop_closures,
        **dc.asdict(s),
    }


def _perturbed(ranges, rng, centimetres) -> np.ndarray:
    """The ranges rounded to 1 cm and/or with 1 mm of noise from ``rng`` (None: none); no-return
    readings kept."""
    finite = np.isfinite(ranges)
    out = np.array(ranges, dtype=float)
    if centimetres:
        out[finite] = np.round(out[finite], 2)
    if rng is not None:
        out[finite] += rng.normal(0.0, NOISE, finite.sum())
    return out


def data_folder(given: Path | None) -> Path:
    """``given``, else ``$DRAKE_SIM_SLAM_LOGS``, else ``shared/benchmarks/slam_carmen`` beside
    the checkout."""
    if given is not None:
        return given
    if os.environ.get("DRAKE_SIM_SLAM_LOGS"):
        return Path(os.environ["DRAKE_SIM_SLAM_LOGS"])
    return Path(__file__).resolve().parents[2] / "shared" / "benchmarks" / "slam_carmen"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--data", type=Path, help="the logs' folder")
    p.add_argument("--logs", nargs="+", choices=sorted(LOGS), default=list(LOGS))
    p.add_argument("--limit", type=int, help="the first N scans of each log only")
    p.add_argument(
        "--no-loop-closure", action="store_true", help="the scan matcher alone (as --log can)"
    )
    p.add_argument(
        "--centimetres", action="store_true", help="ranges rounded to 1 cm, as in CARMEN logs"
    )
    p.add_argument(
        "--carmen",
        action="store_true",
        help="each bag written as a CARMEN log (FLASER lines, ranges in cm) and mapped from it",
    )
    p.add_argument(
        "--noise-runs",
        type=int,
        default=0,
        help="also map each log this many times with seeded 1 mm noise on the ranges (seeds "
        "0..N-1) and give the worst of them",
    )
    p.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="noise runs mapped this many at a time (after the plain runs, one at a time)",
    )
    p.add_argument("--json", type=output_file("json"), help="write the table here")
    args = p.parse_args()
    data = data_folder(args.data)
    if args.jobs < 1 or args.noise_runs < 0:
        print("error: --jobs must be at least 1 and --noise-runs not negative", file=sys.stderr)
        raise SystemExit(2)
    present = [n for n in args.logs if (data / LOGS[n][0]).exists()]
    if not present:
        print(f"error: no logs in {data} (give --data DIR)", file=sys.stderr)
        raise SystemExit(2)
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    options = {
        "loop_closure": not args.no_loop_closure,
        "centimetres": args.centimetres,
        "carmen": args.carmen,
    }
    rows = []
    for name in present:  # one at a time: their speeds are the table's
        row = run_one(data, name, args.limit, **options)
        row.update(zip(("gmapping_m", "graph_m", "cartographer_m"), PUBLISHED[name], strict=True))
        _print(row)
        rows.append(row)
    tasks = [(name, seed) for name in present for seed in range(args.noise_runs)]
    runs = {}
    if tasks:  # no worker processes without noise runs
        with ProcessPoolExecutor(max_workers=args.jobs) as pool:
            futures = [
                pool.submit(run_one, data, name, args.limit, noise_seed=seed, **options)
                for name, seed in tasks
            ]
            for (name, seed), future in zip(tasks, futures, strict=True):
                runs.setdefault(name, []).append(future.result())
                _print(runs[name][-1], f"  noise seed {seed}")
    for row in rows:
        noisy = runs.get(row["log"], [])
        if noisy:
            row["noise_runs"] = len(noisy)
            row["noise_trans_min_m"] = min(r["trans_mean_m"] for r in noisy)
            row["noise_trans_max_m"] = max(r["trans_mean_m"] for r in noisy)
            row["noise_rot_max_deg"] = max(r["rot_mean_deg"] for r in noisy)
            row["noise_rtf_min"] = min(r["real_time_factor"] for r in noisy)
    columns = [
        ["log", "log", "", ""],
        ["scans", "scans", "", "d"],
        ["real_time_factor", "real-time factor", "", ".1f"],
        ["ms_per_scan_median", "per scan, median", "ms", ".1f"],
        ["ms_per_scan_p95", "per scan, p95", "ms", ".1f"],
        ["trans_mean_m", "translational error", "m", ".3f"],
        ["trans_std_m", "its std", "m", ".3f"],
        ["rot_mean_deg", "rotational error", "deg", ".2f"],
        ["rot_std_deg", "its std", "deg", ".2f"],
        ["loop_closures", "loop closures", "", "d"],
        ["gmapping_m", "GMapping", "m", ".3f"],
        ["graph_m", "graph mapping", "m", ".3f"],
        ["cartographer_m", "Cartographer", "m", ".4f"],
    ]
    if args.noise_runs:
        columns[-3:-3] = [
            ["noise_runs", "1 mm noise runs", "", "d"],
            ["noise_trans_min_m", "their error, least", "m", ".3f"],
            ["noise_trans_max_m", "their error, most", "m", ".3f"],
            ["noise_rot_max_deg", "their rotational error, most", "deg", ".2f"],
            ["noise_rtf_min", f"their real-time factor, least ({args.jobs} at a time)", "", ".1f"],
        ]
    result = {
        "figures": {
            f"{r['log']}_{k}": r[k] for r in rows for k in ("trans_mean_m", "real_time_factor")
        },
        "tables": [
            {
                "title": "Offline SLAM on the Kümmerle logs"
                + (" (the bags written as CARMEN logs)" if args.carmen else "")
                + ", published errors beside",
                "columns": columns,
                "rows": rows,
            }
        ],
    }
    if args.json:
        write_atomic(args.json, json.dumps(result, indent=1) + "\n", "figures")


def _print(row: dict, prefix: str = "") -> None:
    print(
        f"{prefix or row['log']:10s} {row['scans']:6d} scans, {row['log_duration_s']:7.1f} s of "
        f"log in {row['wall_time_s']:6.1f} s ({row['real_time_factor']:5.2f}x real time; "
        f"{row['ms_per_scan_median']:.1f} / {row['ms_per_scan_p95']:.1f} ms per scan), "
        f"{row['relations']} relations ({row['missing']} missing): "
        f"{row['trans_mean_m']:.3f} +- {row['trans_std_m']:.3f} m, "
        f"{row['rot_mean_deg']:.2f} +- {row['rot_std_deg']:.2f} deg; "
        f"{row['rejected_matches']} rejected, {row['odometry_jumps']} jumps, "
        f"{row['loop_closures']} loop closures",
        flush=True,
    )


if __name__ == "__main__":
    main()
