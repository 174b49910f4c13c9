"""Benchmark of Wall-E on its courses: ``python benchmarks/walle_benchmark.py [--runs 3]``.

With the default robot and scenario (``config/walle.yaml``, ``config/walle_scenario.yaml``),
in ``both`` mode (balancing while following the line, the camera rendering every frame),
headless:

* the real-time factor (simulated s per wall-clock s of ``WalleCourseRun.run``) of one lap of
  the oval course, ``--runs`` times: each run, then the median (the target is >= 2);
* one run per shipped course (``config/courses/*.yaml``): the course fraction, the laps, the
  lap time, the mean and largest distance of the axle's midpoint from the line, the largest
  lean, and how the run ended.

Not a test: speeds depend on the machine.
"""

import argparse
import dataclasses as dc
import os
import platform
import statistics

from diagrams.walle_scenario import default_scenario_file, load_walle_scenario
from drake_sim.robots.walle import default_robot_file
from drake_sim.robots.walle_params import load_walle_params
from drake_sim.walle_run import WalleCourseRun, WalleReport
from drake_sim.worlds.course import load_course, shipped_courses

SPEED_COURSE = "oval"
"""The shipped course whose lap is timed."""

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


def run_course(scenario, robot, path, *, seed: int | None = None) -> WalleReport:
    """One headless run of ``path`` until its default end (one lap, the finish, a fall)."""
    run = WalleCourseRun(scenario, robot, load_course(path), seed=seed)
    run.run(run.default_duration(viewer=False))
    return run.report()


def _cell(fmt: str, value) -> str:
    return "-" if value is None else fmt.format(value)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=3, help="timed laps of the oval")
    args = parser.parse_args()
    scenario = dc.replace(load_walle_scenario(default_scenario_file()), mode="both")
    robot = load_walle_params(default_robot_file())
    courses = {path.stem: path for path in shipped_courses()}
    camera = scenario.camera
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    print(
        f"mode both, controller {scenario.controller}, camera {camera.width}x{camera.height} "
        f"at {camera.rate:g} Hz, cruise {scenario.line_follower.speed:g} m/s, headless"
    )
    print(f"real-time factor, one lap of {SPEED_COURSE}:")
    factors = []
    for index in range(args.runs):
        report = run_course(scenario, robot, courses[SPEED_COURSE])
        factors.append(report.real_time_factor)
        print(
            f"  run {index + 1}: {report.sim_time_s:.1f} s simulated in "
            f"{report.wall_time_s:.2f} s: {report.real_time_factor:.2f}x ({report.end})"
        )
    print(f"  median: {statistics.median(factors):.2f}x (target >= 2)")
    print("per course (one run each):")
    print(f"{'course':>10} " + " ".join(f"{name:>13}" for name, _, _ in COLUMNS))
    for name, path in courses.items():
        row = run_course(scenario, robot, path).to_dict()
        cells = (f"{_cell(fmt, row[key]):>13}" for _, key, fmt in COLUMNS)
        print(f"{name:>10} " + " ".join(cells))


if __name__ == "__main__":
    main()
