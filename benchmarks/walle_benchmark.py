"""Benchmark of Wall-E on its courses: ``python benchmarks/walle_benchmark.py [--runs 3]``.

With the default robot and scenario (``config/walle.yaml``, ``config/walle_scenario.yaml``),
in ``both`` mode (balancing while following the line, the camera rendering every frame),
headless:

* the real-time factor (simulated s per wall-clock s of ``WalleCourseRun.run``) of one lap of
  the oval course, ``--runs`` times: each run, then the median (the target is >= 2);
* one run per shipped course (``config/courses/*.yaml``): the course fraction, the laps, the
  lap time, the mean and largest distance of the axle's midpoint from the line, the largest
  lean, and how the run ended.

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
from drake_sim.runs.walle import RECIPE, WalleReport
from drake_sim.worlds.course import shipped_courses

SPEED_COURSE = "oval"
"""The shipped course whose lap is timed."""

MODE = ["mode=both"]
"""The scenario's override: balancing while following the line."""

COLUMNS = (
    ("fraction", "course_fraction", "{:.2f}"),
    ("laps", "laps", "{:d}"),
    ("lap_s", "lap_time_s", "{:.2f}"),
    ("mean_off_m", "mean_line_offset_m", "{:.4f}"),
    ("max_off_m", "max_line_offset_m", "{:.4f}"),
    ("max_pitch_deg", "max_abs_pitch_deg", "{:.2f}"),
    ("sim_s", "sim_time_s", "{:.1f}"),
    ("rtf", "real_time_factor", "{:.2f}"),
    ("end", "end", "{}"),
)


HEADERS = {
    "course_fraction": ("course fraction", ""),
    "laps": ("laps", ""),
    "lap_time_s": ("lap time", "s"),
    "mean_line_offset_m": ("mean line offset", "m"),
    "max_line_offset_m": ("largest line offset", "m"),
    "max_abs_pitch_deg": ("largest lean", "deg"),
    "sim_time_s": ("simulated", "s"),
    "real_time_factor": ("real-time factor", "x"),
    "end": ("end", ""),
}
"""(header, unit) of each column in the ``--json`` figures."""


def figures(settings: dict, laps: list[WalleReport], courses: dict[str, dict]) -> dict:
    """The timed laps and the per-course runs as ``--json`` figures."""
    lap_columns = [
        ["run", "run", "", ""],
        ["sim_time_s", "simulated", "s", ".1f"],
        ["wall_time_s", "wall time", "s", ".2f"],
        ["real_time_factor", "real-time factor", "x", ".2f"],
        ["end", "end", "", ""],
    ]
    lap_rows = [
        {"run": str(index), **{key: getattr(r, key) for key, *_ in lap_columns[1:]}}
        for index, r in enumerate(laps, 1)
    ]
    median = statistics.median(r.real_time_factor for r in laps)
    # "{:.2f}" is the format spec ".2f".
    course_columns = [["course", "course", "", ""]] + [
        [key, *HEADERS[key], fmt[2:-1]] for _, key, fmt in COLUMNS
    ]
    course_rows = [
        {"course": name, **{key: row[key] for _, key, _ in COLUMNS}}
        for name, row in courses.items()
    ]
    return {
        "settings": settings,
        "figures": {"real_time_factor": median},
        "tables": [
            {
                "title": f"Real-time factor, one lap of the {SPEED_COURSE}, {len(laps)} runs",
                "columns": lap_columns,
                "rows": [*lap_rows, {"run": "median", "real_time_factor": median}],
            },
            {"title": "Per course, one run each", "columns": course_columns, "rows": course_rows},
        ],
    }


def run_course(path, *, seed: int | None = None) -> WalleReport:
    """One headless run of ``path`` until its default end (one lap, the finish, a fall)."""
    run = RECIPE.start(overrides=[*MODE, f"course={json.dumps(str(path))}"], seed=seed)
    run.run(run.default_duration(viewer=False))
    return run.report()


def _cell(fmt: str, value) -> str:
    return "-" if value is None else fmt.format(value)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=3, help="timed laps of the oval")
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args()
    scenario = RECIPE.load(overrides=MODE).scenario
    courses = {path.stem: path for path in shipped_courses()}
    camera = scenario.camera
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    print(
        f"mode both, controller {scenario.controller}, camera {camera.width}x{camera.height} "
        f"at {camera.rate:g} Hz, cruise {scenario.line_follower.speed:g} m/s, headless"
    )
    print(f"real-time factor, one lap of {SPEED_COURSE}:")
    factors, laps = [], []
    for index in range(args.runs):
        report = run_course(courses[SPEED_COURSE])
        laps.append(report)
        factors.append(report.real_time_factor)
        print(
            f"  run {index + 1}: {report.sim_time_s:.1f} s simulated in "
            f"{report.wall_time_s:.2f} s: {report.real_time_factor:.2f}x ({report.end})"
        )
    print(f"  median: {statistics.median(factors):.2f}x (target >= 2)")
    print("per course (one run each):")
    print(f"{'course':>10} " + " ".join(f"{name:>13}" for name, _, _ in COLUMNS))
    rows = {}
    for name, path in courses.items():
        row = rows[name] = run_course(path).to_dict()
        cells = (f"{_cell(fmt, row[key]):>13}" for _, key, fmt in COLUMNS)
        print(f"{name:>10} " + " ".join(cells), flush=True)
    if args.json:
        settings = {
            "runs": args.runs,
            "controller": scenario.controller,
            "camera": f"{camera.width}x{camera.height} at {camera.rate:g} Hz",
            "speed_m_per_s": scenario.line_follower.speed,
        }
        result = figures(settings, laps, rows)
        write_atomic(args.json, json.dumps(result, indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
