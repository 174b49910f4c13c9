"""drake_sim.tools.plan_benchmark_profile: exclusive phase times, check counts, the breakdown
tables."""

import numpy as np
import pytest

import drake_sim.tools.plan_benchmark_profile as mut
from planning import PlanningScene
from planning.motion_planner import MotionPlanner


@pytest.fixture(scope="module")
def planner():
    return MotionPlanner(PlanningScene())


def test_rows_sum_to_the_request_and_wrappers_are_removed(planner):
    original = MotionPlanner.__dict__["plan_path"]
    q_start = planner.state.q
    q_goal = q_start + 0.3
    with mut.PhaseProfiler() as dut:
        assert MotionPlanner.__dict__["plan_path"] is not original
        planner.scene.is_collision_free(q_start)  # outside a request: not profiled
        assert dut.take()["calls"] == {}
        start = mut.time.perf_counter()
        path, how = planner.plan_path(q_start, q_goal)
        total = mut.time.perf_counter() - start
        record = dut.take(total, "free space")
    assert MotionPlanner.__dict__["plan_path"] is original
    assert how == "straight" and path.shape == (2, 7)
    times = record["times"]
    assert times["total"] == total
    assert sum(t for row, t in times.items() if row != "total") == pytest.approx(total)
    assert all(t >= 0 for t in times.values())
    # In free space the spheres prove the start and the goal free, and the compiled search
    # finds and checks the straight line: Drake is not asked.
    assert "start/goal check: spheres" in times and "request: python" in times
    assert "compiled: search on spheres" in times and "compiled: fine check on spheres" in times
    assert record["calls"]["SphereCollisionModel.classify"] >= 2  # start, goal
    assert "CollisionChecker.CheckConfigCollisionFree" not in record["calls"]
    assert record["name"] == "free space"


def test_breakdown_tables():
    def record(name, total, spheres, drake_calls):
        times = {"rrt-connect: spheres": spheres, mut.OTHER: total - spheres, "total": total}
        times["retime: python"] = 0.5
        return {"name": name, "times": times, "calls": {"drake": drake_calls}}

    records = [record(f"p{k}", 0.01 * k, 0.005 * k, k) for k in range(1, 21)]
    text = mut.breakdown(records)
    assert "profile over 20 requests" in text
    assert "tail only (1 requests: p20 200 ms)" in text
    spheres = next(line for line in text.splitlines() if line.startswith("rrt-connect: spheres"))
    assert spheres.split()[-2:] == ["50.0%", "50.0%"]  # half of each group's time
    assert "not in total" in text and "retime: python" in text
    counts = next(line for line in text.splitlines() if line.startswith("drake"))
    assert counts.split()[1:] == ["10", "19", "20"]  # median, p95, tail median
    assert np.isclose(float(text.split("total")[1].split()[0]), 105.0)  # median ms
    assert mut.breakdown([]) == "profile: no timed request"
