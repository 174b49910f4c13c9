"""Cost of adding objects to a planning scene as it grows.

Run from the checkout: ``python benchmarks/scene_scale_benchmark.py [--sizes 10 100 400]``.
For each size N, on a fresh scene (the table alone), prints:

- ``add``: the median time of ``add_box`` over the 10 adds that bring the scene to N objects,
  with no query in between (the objects wait in the checker's queue);
- ``first query``: the first ``is_collision_free`` after those adds, which registers every
  queued object in each checker context;
- ``add + query``: the median of 10 rounds of adding one more object and querying once at N
  objects, the cost when adds and queries alternate;
- ``Drake add``: for comparison, the median of 5 adds through Drake's own
  ``AddCollisionShapeToBody`` at N objects (what ``add_box`` used to do for each object; it
  re-applies every collision filter, so its cost grows with the square of N).

The acceptance is the ``add`` median at 400 objects within 2x of the one at 10. ``--json FILE``
also writes the figures for ``python -m benchmarks.report``.
"""

import argparse
import json
import statistics
import time

from pydrake.geometry import Box
from pydrake.math import RigidTransform
from pydrake.planning import SceneGraphCollisionChecker

import planning
from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic

_WINDOW = 10  # adds measured per size


def box_pose(i: int) -> RigidTransform:
    """Small boxes on a grid well away from the robot (nothing collides)."""
    return RigidTransform([2.0 + 0.05 * (i % 20), 0.05 * (i // 20 % 20), 0.05 * (i // 400)])


def timed(function) -> float:
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def measure(size: int) -> dict[str, float]:
    scene = planning.PlanningScene()
    ready = scene.model.named_configurations["ready"]
    scene.is_collision_free(ready)
    adds = []
    for i in range(size):
        seconds = timed(lambda i=i: scene.add_box(f"box{i}", [0.02] * 3, box_pose(i)))
        if i >= size - _WINDOW:
            adds.append(seconds)
    first_query = timed(lambda: scene.is_collision_free(ready))
    rounds = []
    for i in range(size, size + _WINDOW):
        scene.remove_object(f"box{i - size}")  # stay at N objects
        rounds.append(
            timed(
                lambda i=i: (
                    scene.add_box(f"box{i}", [0.02] * 3, box_pose(i)),
                    scene.is_collision_free(ready),
                )
            )
        )
    checker, world = scene.checker, scene.plant.world_body()
    drake = [
        timed(
            lambda k=k: SceneGraphCollisionChecker.AddCollisionShapeToBody(
                checker, f"drake{k}", world, Box(0.02, 0.02, 0.02), box_pose(size + 100 + k)
            )
        )
        for k in range(5)
    ]
    return {
        "add": statistics.median(adds),
        "first query": first_query,
        "add + query": statistics.median(rounds),
        "Drake add": statistics.median(drake),
    }


def figures(results: dict[int, dict[str, float]]) -> dict:
    """The measurements (s) as ``--json`` figures: a table in ms by scene size, and the ratio of
    the ``add`` median at the largest size over the smallest."""
    keys = {"add": "add_ms", "first query": "first_query_ms", "add + query": "add_query_ms"}
    keys["Drake add"] = "drake_add_ms"
    rows = [
        {"objects": size, **{keys[k]: 1e3 * v for k, v in r.items()}} for size, r in results.items()
    ]
    smallest, largest = min(results), max(results)
    ratio = results[largest]["add"] / results[smallest]["add"]
    columns = [
        ["objects", "objects", "", "d"],
        ["add_ms", f"add, median of {_WINDOW}", "ms", ".3f"],
        ["first_query_ms", "first query after the adds", "ms", ".1f"],
        ["add_query_ms", f"add + query, median of {_WINDOW}", "ms", ".2f"],
        ["drake_add_ms", "Drake's AddCollisionShapeToBody, median of 5", "ms", ".2f"],
    ]
    note = (
        f"The add median at {largest} objects is {ratio:.2f}x the one at {smallest} "
        "(acceptance: within 2x)."
    )
    return {
        "settings": {"sizes": list(results)},
        "figures": {"add_ratio": ratio},
        "tables": [{"title": "By scene size", "columns": columns, "rows": rows, "note": note}],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 400])
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args()
    sizes = args.sizes
    results = {}
    print(f"{'objects':>8} {'add':>10} {'first query':>12} {'add + query':>12} {'Drake add':>10}")
    for size in sizes:
        r = results[size] = measure(size)
        print(
            f"{size:>8} {r['add'] * 1e3:>8.3f}ms {r['first query'] * 1e3:>10.1f}ms"
            f" {r['add + query'] * 1e3:>10.2f}ms {r['Drake add'] * 1e3:>8.2f}ms"
        )
    smallest, largest = min(sizes), max(sizes)
    ratio = results[largest]["add"] / results[smallest]["add"]
    print(f"add at {largest} objects / add at {smallest}: {ratio:.2f}x (acceptance: within 2x)")
    if args.json:
        write_atomic(args.json, json.dumps(figures(results), indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
