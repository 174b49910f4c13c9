"""Planning time of the pick-and-place motion sequence (the MotionPlanner alone, no simulation).

    python benchmarks/pick_sequence_benchmark.py [--scene config/pickplace.yaml] [--repeats 5]

The motions of ``PickPlaceTask``'s steps, under the same names, on the pick-and-place scene:
ready -> ``move_above_object`` (pose goal 12 cm above the grasp, hand down) -> ``approach``
(Cartesian down, fingers ``PickPlaceOptions.grasp_depth`` below the object's top) -> the object
attached -> ``lift`` (Cartesian, 15 cm up) -> ``move_to_place`` in two motions: ``above`` (pose
goal 15 cm above the place, over the obstacle) and ``down`` (Cartesian, the object 5 mm above
its target). Each
repeat uses a fresh ``MotionPlanner`` on a freshly loaded scene. Prints each step's planning
time (median over the repeats) and the median total; exit code 1 when a step fails.
``--json FILE`` also writes them for ``python -m benchmarks.report``.
"""

import argparse
import json
import statistics
import sys
import time

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix

from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.base.resources import config_dir
from planning import MotionPlanner, PickPlaceOptions, PlanningScene, planner_kernels

R_DOWN = RotationMatrix.MakeXRotation(np.pi)  # the hand's z axis along -z_W
STEPS = ("move_above_object", "approach", "lift", "move_to_place above", "move_to_place down")


def plan_sequence(scene: PlanningScene) -> dict[str, float]:
    """Plans the sequence once; returns each step's planning time, s."""
    planner = MotionPlanner(scene)
    p_WO = scene.object_pose("object").translation()
    height = scene.world_objects["object"].size[2]
    # The hand's TCP holds the object grasp_depth below its top: p_WG = p_WO + [0, 0, offset].
    offset = 0.5 * height - min(PickPlaceOptions().grasp_depth, 0.5 * height)
    p_place = np.asarray(scene.place_position, dtype=float)
    q = planner.state.named("ready")
    times = {}

    def run(name, request, *args):
        nonlocal q
        start = time.perf_counter()
        result = request(*args, q_start=q)
        times[name] = time.perf_counter() - start
        if not result.success:
            raise RuntimeError(f"{name}: {result.message}")
        q = result.plan.waypoints[-1]

    def above(p, height):
        return RigidTransform(R_DOWN, p + [0.0, 0.0, height])

    run("move_above_object", planner.plan_to_pose, above(p_WO, offset + 0.12))
    run("approach", planner.plan_cartesian, above(p_WO, offset))
    scene.attach("object", q)
    run("lift", planner.plan_cartesian, above(p_WO, offset + 0.15))
    run("move_to_place above", planner.plan_to_pose, above(p_place, offset + 0.15))
    run("move_to_place down", planner.plan_cartesian, above(p_place, offset + 0.005))
    return times


def figures(rows: list[dict[str, float]]) -> dict:
    """The repeats' step times (s) as ``--json`` figures: per step and in total, the median,
    min and max in ms."""

    def stats(label, seconds):
        ms = [1e3 * s for s in seconds]
        median = statistics.median(ms)
        return {"step": label, "median_ms": median, "min_ms": min(ms), "max_ms": max(ms)}

    table = [stats(name, [r[name] for r in rows]) for name in STEPS]
    table.append(stats("total", [sum(r.values()) for r in rows]))
    columns = [
        ["step", "step", "", ""],
        ["median_ms", "median", "ms", ".1f"],
        ["min_ms", "min", "ms", ".1f"],
        ["max_ms", "max", "ms", ".1f"],
    ]
    return {
        "settings": {"repeats": len(rows)},
        "figures": {"total_ms": table[-1]["median_ms"]},
        "tables": [
            {
                "title": f"Planning time per step, {len(rows)} repeats (the first in the process "
                "included)",
                "columns": columns,
                "rows": table,
            }
        ],
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default=str(config_dir() / "pickplace.yaml"))
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args(argv)
    # Measure the compiled planner: on a fresh install, wait for its kernels' build.
    planner_kernels.wait_ready(progress=planner_kernels.ProgressLine("benchmark"))
    rows = []
    for _ in range(args.repeats):
        scene = PlanningScene()
        scene.load_yaml(args.scene)
        try:
            rows.append(plan_sequence(scene))
        except RuntimeError as e:
            print(f"failed: {e}", file=sys.stderr)
            return 1
    for name in STEPS:
        print(f"{name:20s} {statistics.median(r[name] for r in rows) * 1e3:7.1f} ms")
    totals = [sum(r.values()) for r in rows]
    print(
        f"{'total':20s} {statistics.median(totals) * 1e3:7.1f} ms median of {len(rows)} "
        f"(min {min(totals) * 1e3:.1f}, max {max(totals) * 1e3:.1f})"
    )
    if args.json:
        write_atomic(args.json, json.dumps(figures(rows), indent=1) + "\n", "figures")
    return 0


if __name__ == "__main__":
    sys.exit(main())
