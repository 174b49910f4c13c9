"""Shared fixtures: a per-session cache folder so tests never touch ~/.cache, and the motion
planner's compiled kernels built once, in the background, while the first tests run.

Tests plan the same way every time: ``DRAKE_SIM_KERNELS=wait`` (``planning.planner_kernels``)
makes every planner, in this process and in the CLIs the tests start, use the compiled search,
waiting for the build when it is not finished. The build starts with the session, in a process
of its own, so that on a fresh clone its two to three minutes overlap the tests that do not plan:
those run first (``pytest_collection_modifyitems``), the arm's tests after them.
"""

import pytest

# Tests that plan for the arm (and so may wait for the kernels' build): run after the others.
_PLANS = (
    "tests/planning/",
    "tests/benchmarks/",
    "panda",
    "pick",
    "planning_station",
    "notebooks",
    "signals",
    "sweep/",
    "tools/test_plan_benchmark",
)


def _plans(item) -> bool:
    path = item.path.as_posix()
    return "tests/drake_sim/navigation/" not in path and any(p in path for p in _PLANS)


def pytest_collection_modifyitems(config, items):
    """Runs the tests that do not plan for the arm first, in their order, then the others."""
    items.sort(key=_plans)  # a stable sort keeps each group's order


@pytest.fixture(autouse=True, scope="session")
def _session_cache(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("DRAKE_SIM_CACHE", str(tmp_path_factory.mktemp("drake_sim_cache")))
    mp.setenv("DRAKE_SIM_KERNELS", "wait")
    from planning import planner_kernels

    planner_kernels.start_background()  # once for all workers: it holds a lock
    yield
    mp.undo()
