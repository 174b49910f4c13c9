"""A seed gives the same path on any machine: MBM requests planned with the default options
return, to the bit, the paths recorded in ``data/mbm_paths.json``.

The search counts checks instead of reading the clock, draws from its own seeded generator and
compiles without fast-math (no reassociation or fused multiply-adds), so its floating-point
results do not depend on the CPU it runs on. The recorded requests are the first of each MBM
family that the straight line does not solve, so the random search, the shortcuts and the fine
check all take part.

A change to the planner that changes its paths on purpose records them again, and says so:

    python -m tests.planning.search.test_mbm_paths
"""

import json
from pathlib import Path

import numpy as np
import pytest

from drake_sim.tools.plan_benchmark import _load
from planning import MotionPlanner, PlanningScene
from planning.io import mbm
from tests.mbm_helpers import find_mbm_problems

RECORDED = Path(__file__).parent / "data" / "mbm_paths.json"


def _plan(planner, q_start, q_goal):
    planner.prepare()
    return planner.plan_path(q_start, q_goal, timeout=60.0)


def _problems(folder):
    return {(p.family, p.number): p for p in mbm.iter_problems(folder, list(mbm.FAMILIES), None)}


@pytest.fixture(scope="module")
def planner_and_scene():
    scene = PlanningScene()
    return MotionPlanner(scene), scene


def test_the_recorded_requests_cover_every_family_with_searched_paths():
    recorded = json.loads(RECORDED.read_text())
    assert sorted({r["family"] for r in recorded}) == sorted(mbm.FAMILIES)
    assert all(r["how"] != "straight" and len(r["path"]) > 2 for r in recorded)


def test_each_recorded_request_gives_the_recorded_path_to_the_bit(planner_and_scene, mbm_folder):
    planner, scene = planner_and_scene
    problems = _problems(mbm_folder)
    for row in json.loads(RECORDED.read_text()):
        path, how = _plan(planner, *_load(scene, problems[row["family"], row["problem"]]))
        expected = np.array(row["path"])
        name = f"{row['family']} {row['problem']}"
        assert how == row["how"], name
        assert path.shape == expected.shape, name
        # JSON keeps a float's shortest repr, which reads back as the same double.
        assert np.array_equal(path, expected), f"{name}: max diff {np.abs(path - expected).max()}"


def record() -> None:
    """Plans the first request of each family that the straight line does not solve and
    writes the paths to ``RECORDED``."""
    scene = PlanningScene()
    planner = MotionPlanner(scene)
    rows, done = [], set()
    for problem in _problems(find_mbm_problems()).values():
        if problem.family in done:
            continue
        q_start, q_goal = _load(scene, problem)
        ends = (q_start, q_goal)
        if not all(scene.in_joint_limits(q, 1e-6) and scene.is_collision_free(q) for q in ends):
            continue
        path, how = _plan(planner, q_start, q_goal)
        if how == "straight":
            continue
        done.add(problem.family)
        rows.append(
            {"family": problem.family, "problem": problem.number, "how": how, "path": path.tolist()}
        )
    RECORDED.parent.mkdir(exist_ok=True)
    RECORDED.write_text(json.dumps(rows, indent=1) + "\n")
    print(f"recorded {len(rows)} paths in {RECORDED}")


if __name__ == "__main__":
    record()
