"""Speed of the planning scene: collision checks, IK, object add/remove, and MBM validity.

Run from the checkout: ``python benchmarks/planning_scene_benchmark.py [--dataset PATH]``.
Prints collision checks per second (empty scene with the table, and an MBM bookshelf scene),
edge checks per second, IK solve times and success rates (full pose, position only, orientation
only), add and remove times at several scene sizes, and per MBM family how many problems have a
collision-free start and goal under our model with the fingers at the request's own positions
(and, for comparison, clamped to the URDF's 0.04 m limit). The MBM problems come from
``--dataset`` (a ``problems`` folder, a folder holding ``problems.tar.bz2`` or the archive itself),
else as ``python -m planning.benchmark`` finds them (``planning.io.mbm.find_problems``:
``$DRAKE_SIM_MBM``, the cache, or a download with pip into the cache); the MBM part is skipped,
saying why, when they cannot be had.
"""

import argparse
import collections
import time
from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform
from tqdm import tqdm

import planning
from planning.io import mbm


def random_configurations(scene, count: int, rng) -> np.ndarray:
    idx = scene.model.arm_indices
    lower = scene.plant.GetPositionLowerLimits()[idx]
    upper = scene.plant.GetPositionUpperLimits()[idx]
    return rng.uniform(lower, upper, size=(count, 7))


def bench_checks(scene, samples: int, rng, label: str) -> None:
    qs = [scene.full_q(q) for q in random_configurations(scene, samples, rng)]
    checker = scene.checker
    start = time.perf_counter()
    free = sum(checker.CheckConfigCollisionFree(q) for q in qs)
    elapsed = time.perf_counter() - start
    print(f"collision checks ({label}): {samples / elapsed:,.0f} per s, {free / samples:.0%} free")
    edges = min(samples // 10, 500)
    start = time.perf_counter()
    for a, b in zip(qs[:edges], qs[1 : edges + 1], strict=True):
        checker.CheckEdgeCollisionFree(a, b)
    elapsed = time.perf_counter() - start
    step = checker.edge_step_size()
    print(f"edge checks ({label}, random pairs, step {step} rad): {edges / elapsed:,.0f} per s")


def bench_ik(scene, poses: int, rng) -> None:
    state = planning.RobotState(scene)
    targets = []
    for q in random_configurations(scene, poses * 3, rng):
        if scene.is_collision_free(q):
            targets.append(state.fk(q))
        if len(targets) == poses:
            break
    if not targets:
        print("IK: no collision-free random configuration found; skipped")
        return
    for mode in ("pose", "position", "orientation"):
        times, solved = [], 0
        for X_WE in tqdm(targets, desc=f"IK {mode}", leave=False, disable=None):
            kwargs = {
                "pose": {"X_WE": X_WE},
                "position": {"p_WE": X_WE.translation()},
                "orientation": {"R_WE": X_WE.rotation()},
            }[mode]
            start = time.perf_counter()
            try:
                state.ik(**kwargs)
                solved += 1
            except planning.PlanningError:
                pass
            times.append(time.perf_counter() - start)
        print(
            f"IK {mode:11s}: {solved}/{len(targets)} solved,"
            f" median {np.median(times) * 1e3:.1f} ms, p95 {np.percentile(times, 95) * 1e3:.1f} ms"
        )
    start = time.perf_counter()
    try:
        state.ik(RigidTransform([1.5, 0.0, 0.3]))
    except planning.PlanningError as e:
        print(f"IK unreachable: {e.code.name} in {(time.perf_counter() - start) * 1e3:.2f} ms")


def bench_add_remove(scene) -> None:
    for existing in (0, 20, 100):
        names = [f"filler{i}" for i in range(existing)]
        for i, name in enumerate(names):
            scene.add_box(name, [0.01] * 3, RigidTransform([2.0 + 0.02 * i, 0.0, 0.0]))
        adds, removes = [], []
        for i in range(20):
            start = time.perf_counter()
            scene.add_box("probe", [0.1, 0.1, 0.1], RigidTransform([0.5, 0.1 * i, 0.3]))
            adds.append(time.perf_counter() - start)
            start = time.perf_counter()
            scene.remove_object("probe")
            removes.append(time.perf_counter() - start)
        print(
            f"add/remove with {existing + 1} objects present: add {np.median(adds) * 1e3:.2f} ms,"
            f" remove {np.median(removes) * 1e3:.2f} ms (median of 20)"
        )
        for name in names:
            scene.remove_object(name)


def bench_mbm(scene, folder: Path) -> None:
    rows = collections.defaultdict(lambda: collections.Counter())
    load_times = []
    problems = list(mbm.iter_problems(folder))
    for problem in tqdm(problems, desc="MBM problems", leave=False, disable=None):
        start = time.perf_counter()
        scene.load_moveit(problem.scene_file)
        load_times.append(time.perf_counter() - start)
        request = mbm.load_request(problem.request_file)
        row = rows[problem.family]
        row["problems"] += 1
        for key, clamp in (("valid", False), ("valid_clamped", True)):
            qs = [request.q_start.copy(), request.q_goal.copy()]
            if clamp:
                for q in qs:
                    q[7:] = np.minimum(q[7:], 0.04)
            start_ok = scene.is_collision_free(qs[0])
            goal_ok = scene.is_collision_free(qs[1])
            row[key] += start_ok and goal_ok
            if not clamp:
                row["start_valid"] += start_ok
                row["goal_valid"] += goal_ok
    print(f"MBM scene load: median {np.median(load_times) * 1e3:.1f} ms")
    print(f"{'family':24s} problems start goal valid valid(fingers<=0.04)")
    for family, row in rows.items():
        print(
            f"{family:24s} {row['problems']:8d} {row['start_valid']:5d} {row['goal_valid']:4d}"
            f" {row['valid']:5d} {row['valid_clamped']:5d}"
        )
    total = sum(r["valid"] for r in rows.values())
    print(f"all families: {total}/{sum(r['problems'] for r in rows.values())} valid")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--dataset",
        type=Path,
        default=None,
        help="MBM problems folder or problems.tar.bz2 (default: as planning.benchmark finds it)",
    )
    parser.add_argument("--samples", type=int, default=20000, help="collision checks to time")
    parser.add_argument("--ik-poses", type=int, default=100)
    parser.add_argument("--collision-geometry", default=None, help="convex_mesh or primitives")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    config = planning.PlanningConfig()
    if args.collision_geometry:
        config.model.collision_geometry = args.collision_geometry
    start = time.perf_counter()
    scene = planning.PlanningScene(config)
    print(f"collision geometry: {config.model.collision_geometry}")
    print(f"scene construction: {(time.perf_counter() - start) * 1e3:.0f} ms")
    rng = np.random.default_rng(args.seed)
    bench_checks(scene, args.samples, rng, "table only")
    bench_ik(scene, args.ik_poses, rng)
    bench_add_remove(scene)
    try:
        folder = mbm.find_problems(args.dataset)
    except mbm.MbmDataError as e:
        print(f"MBM problems skipped: {e}")
    else:
        problem = next(mbm.iter_problems(folder, families=["bookshelf_thin_panda"], limit=1))
        scene.load_moveit(problem.scene_file)
        bench_checks(scene, args.samples, rng, "MBM bookshelf_thin scene 1")
        bench_mbm(scene, folder)


if __name__ == "__main__":
    main()
