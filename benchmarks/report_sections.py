"""The sections of ``python -m benchmarks.report``: each benchmark's command at the report's
sizes, what it measures, the README's headline figures, and the summary of the MotionBenchMaker
rows (``python -m planning.benchmark --report`` writes rows, not tables).

The sizes keep the whole report to about 20 minutes on two cores; each section's command, run
on its own, prints the same figures the report collects with ``--json FILE``.
"""

from __future__ import annotations

import statistics
from dataclasses import dataclass

import numpy as np

from benchmarks import report_markdown as md


@dataclass(frozen=True)
class Section:
    """One benchmark of the report.

    Attributes:
        name: the section's name for ``--only``.
        title: its heading in docs/benchmarks.md.
        argv: what follows ``python`` in its command (the report's sizes).
        about: one paragraph: what it measures.
        output: the option that makes the command write its figures to a file.
    """

    name: str
    title: str
    argv: tuple[str, ...]
    about: str
    output: str = "--json"


def _script(name: str, *args: str) -> tuple[str, ...]:
    return (f"benchmarks/{name}_benchmark.py", *args)


SECTIONS = (
    Section(
        "flip",
        "Flipping robot",
        _script("flip", "--runs", "3"),
        "The default robot and scenario (`config/ddrive.yaml`, `config/flip.yaml`) headless "
        "for 20 simulated seconds, three times: flips, drift off the line, odometry error and "
        "real-time factor of each run, and their medians.",
    ),
    Section(
        "sweep",
        "Sweep of flip robot variants",
        _script("sweep", "--limit", "20"),
        "The first 20 rollouts of `config/sweeps/flip_robot_variants.yaml` with one local "
        "worker, then with two: wall times and the speed-up (two free cores would give close "
        "to 2; a busy machine gives less).",
    ),
    Section(
        "walle",
        "Wall-E line following",
        _script("walle", "--runs", "3"),
        "Wall-E in `both` mode (balancing while it follows the line, the camera rendering every "
        "frame), headless: the real-time factor of one lap of the oval, three times, and one "
        "run per shipped course.",
    ),
    Section(
        "walle_balance",
        "Wall-E balance controllers",
        _script("walle_balance"),
        "PID and LQR side by side: the largest push survived (bisection, eight halvings), lean "
        "and drift while balancing with IMU noise (three seeds), a manoeuvre's lean and lag, "
        "and the real-time factor.",
    ),
    Section(
        "pickplace",
        "Pick and place",
        _script("pickplace", "--repeats", "5", "--random", "10"),
        "The whole task (planning, then the motion simulated with contact in `physics` mode or "
        "played back in `kinematic` mode) on the default scene five times and on ten random "
        "scenes (seed 7), per mode.",
    ),
    Section(
        "pick_sequence",
        "Pick-and-place motion planning",
        _script("pick_sequence", "--repeats", "5"),
        "The motions of the pick-and-place task planned by the `MotionPlanner` alone (no "
        "simulation), a fresh planner and scene each time: planning time per step and in total.",
    ),
    Section(
        "mbm",
        "MotionBenchMaker Panda problems",
        ("-m", "planning.benchmark", "--timeout", "5"),
        "Every problem of the seven MotionBenchMaker Panda families (third-party data: "
        "`planning.benchmark` finds or fetches it), planned with `MotionPlanner.plan_path` and "
        "timed from request to validated path; times over the valid problems, failures at the "
        "time they took. Summarised here from its `--report` rows.",
        output="--report",
    ),
    Section(
        "scene_scale",
        "Planning scene size",
        _script("scene_scale"),
        "The cost of adding boxes to a planning scene at 10, 100 and 400 objects, of the first "
        "collision query after them, and of Drake's own `AddCollisionShapeToBody`.",
    ),
    Section(
        "mapping",
        "Mapping",
        _script("mapping", "--runs", "2"),
        "The lidar robot maps every shipped arena along its default route, headless, two seeds "
        "each: map scores, pose error, real-time factor, and the lidar's cost per scan.",
    ),
    Section(
        "explore",
        "Exploration",
        _script("explore", "--runs", "2"),
        "The lidar robot maps every shipped arena by itself (frontier exploration, "
        "`python -m drake_sim.explore`), headless, two seeds each: how the run ended, map "
        "scores, pose error, collisions, and the time against the arena's hand-written mapping "
        "route (its length at the route follower's speed).",
    ),
    Section(
        "slam",
        "Scan-matching SLAM",
        _script("slam"),
        "The SLAM alone, no simulation: scans ray-marched along each arena's route, odometry "
        "drifting; cost per update and pose error against the truth.",
    ),
    Section(
        "lidar",
        "Lidar",
        _script("lidar"),
        "The lidar's geometric ray casting against depth renders on a room with boxes, "
        "cylinders and a 4 096-triangle mesh: cost per scan and error against an exact 2D "
        "reference.",
    ),
    Section(
        "navigation",
        "Navigation",
        _script("navigation", "--runs", "3", "--goals", "4"),
        "The whole navigation stack (physics, lidar, odometry, AMCL, costmaps, A*, DWA), "
        "headless, on each arena's ground-truth map: the room's goals three times, four random "
        "goals per arena, and AMCL's cost per update.",
    ),
    Section(
        "barn",
        "BARN with no prior map",
        _script("barn", "--worlds", "6"),
        "Six of BARN's 300 obstacle courses (Perille et al. 2020), driven as `navigate` does "
        "with no `--map`: the live SLAM localises, the costmaps fill from the lidar. A world "
        "succeeds when the goal 10 m ahead is reached with no collision within 100 simulated "
        "seconds. Needs the BARN arenas (`shared/benchmarks/barn` beside the checkout, or "
        "`$DRAKE_SIM_BARN`).",
    ),
    Section(
        "real_maps",
        "Navigation on real maps",
        _script("real_maps"),
        "The TurtleBot3 world, nav2's depot and its warehouse simulated from their map files "
        "alone, AMCL from the true start (and, on the TurtleBot3 world and the depot, from no "
        "guess), with the DWA and with the TEB local planner; `depot_open` and "
        "`warehouse_open` are goals across open floor, where little is within the lidar's "
        "3.5 m. Needs the maps (`shared/real_ros/maps` beside the checkout, or "
        "`$DRAKE_SIM_REAL_MAPS`).",
    ),
    Section(
        "slam_logs",
        "SLAM on real logs",
        _script("slam_logs", "--noise-runs", "10", "--jobs", "2"),
        "Offline SLAM (the mapping app with `--log FILE`) on the classic real 2D laser logs of "
        "Kümmerle et al. 2009 (Intel, Freiburg 079 and ACES from their ROS 1 bags with "
        "GMapping's beam angles, MIT CSAIL from its CARMEN log), the mapping scenario's SLAM "
        "defaults with the pose graph and loop closures the log mode turns on; errors of the "
        "laser's trajectory (the frame the relations are in: Freiburg 079's laser is 4 cm "
        "ahead of its base, the others' at it) on each log's ground-truth relations, with "
        "GMapping's, graph mapping's and Cartographer's published translational errors "
        "beside; then each log ten times more with seeded 1 mm noise on its ranges (two at a "
        "time): the least and most error over them. Needs the logs "
        "(`shared/benchmarks/slam_carmen` beside the checkout, or `$DRAKE_SIM_SLAM_LOGS`).",
    ),
    Section(
        "slam_carmen",
        "SLAM on real logs, from CARMEN files",
        _script("slam_logs", "--carmen"),
        "The same logs as CARMEN users have them: each bag written as a CARMEN log of FLASER "
        "lines (ranges in centimetres, the scanner's maximum where nothing came back, no laser "
        "offset: the datasets' `.clf` files are not in `shared/`, and this is their format) in "
        "a temporary folder, then mapped from that file as `mapping --log FILE.clf` maps it; "
        "MIT CSAIL from its own CARMEN log. The laser is the base here, so the trajectory "
        "scored is the one `--trajectory` writes.",
    ),
    Section(
        "amcl",
        "AMCL",
        _script("amcl", "--seeds", "3"),
        "AMCL alone, no simulation, on every shipped arena: cost per update, tracking from a "
        "rough guess, and global localisation in the room (three seeds).",
    ),
    Section(
        "costmap",
        "Costmaps and the global planner",
        _script("costmap"),
        "The warehouse's costmap at 0.05 m: building, inflating, scan updates, and A* and "
        "Dijkstra plans (medians of 20 repeats).",
    ),
)
NAMES = tuple(s.name for s in SECTIONS)

HEADLINES = (
    md.Headline(
        "flip",
        "{real_time_factor:.1f}x real time ({duration_s:g} simulated s, median of {runs} runs)",
    ),
    md.Headline(
        "walle", "{real_time_factor:.1f}x real time (one lap of the oval, median of {runs} runs)"
    ),
    md.Headline(
        "pickplace",
        "{success_rate:.0%} done, planning {planning_time_s:.3f} s per task (default scene, "
        "kinematic mode, median of {repeats})",
    ),
    md.Headline(
        "pick_sequence", "{total_ms:.0f} ms to plan the task's motions (median of {repeats})"
    ),
    md.Headline(
        "mbm",
        "median {median_ms:.2f} ms, p95 {p95_ms:.1f} ms per problem, {solved} of the {valid} "
        "valid problems solved",
    ),
    md.Headline(
        "mapping",
        "{real_time_factor:.1f}x real time (median of every run), map IoU {min_map_iou:.3f} "
        "or better",
    ),
    md.Headline(
        "navigation",
        "{real_time_factor:.1f}x real time (the room's goals, median of {runs} runs)",
    ),
)
"""The README's headline figures, in order."""


def mbm_figures(report, *, limit: str = "all") -> dict:
    """The MotionBenchMaker section's figures from ``planning.benchmark``'s report rows (a
    list, or an object with ``rows``): per family and in all, problems, valid, solved, time
    over the valid problems (median, p95, max; ms), median path length, paths valid when
    re-checked at 0.01 rad.

    Raises:
        ValueError: the report has no rows (KeyError: a row lacks a key).
    """
    rows = report.get("rows") if isinstance(report, dict) else report
    if not isinstance(rows, list):
        raise ValueError("the MBM report has no rows")
    families = list(dict.fromkeys(r["family"] for r in rows))
    table, overall = [], {}
    for family in [*families, "all"]:
        group = [r for r in rows if family in ("all", r["family"])]
        valid = [r for r in group if r.get("valid")]
        solved = [r for r in valid if r.get("success")]
        times = [1e3 * r["time_s"] for r in valid if r.get("time_s") is not None]
        lengths = [r["path_length"] for r in solved if r.get("path_length") is not None]
        overall = {
            "family": family,
            "problems": len(group),
            "valid": len(valid),
            "solved": len(solved),
            "median_ms": statistics.median(times) if times else None,
            "p95_ms": float(np.percentile(times, 95)) if times else None,
            "max_ms": max(times, default=None),
            "median_length": statistics.median(lengths) if lengths else None,
            "fine_ok": sum(bool(r.get("path_valid_fine")) for r in solved),
        }
        table.append(overall)
    columns = [
        ["family", "family", "", ""],
        ["problems", "problems", "", "d"],
        ["valid", "valid", "", "d"],
        ["solved", "solved", "", "d"],
        ["median_ms", "median time", "ms", ".2f"],
        ["p95_ms", "p95 time", "ms", ".2f"],
        ["max_ms", "max time", "ms", ".1f"],
        ["median_length", "median path length", "rad", ".2f"],
        ["fine_ok", "paths valid at 0.01 rad", "", "d"],
    ]
    return {
        "settings": {"limit": limit},
        "figures": {k: overall[k] for k in ("median_ms", "p95_ms", "valid", "solved", "problems")},
        "tables": [{"title": "Per family", "columns": columns, "rows": table}],
    }
