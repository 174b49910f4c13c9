"""The OMPL baseline of ``python -m planning.benchmark --compare-ompl`` (needs the bench extra)."""

import importlib.util

import numpy as np
import pytest

import drake_sim.tools.ompl_baseline as mut
from planning import PlanningScene
from planning.collision.checker import CheckerAdapter, first_invalid_segment


def test_availability_matches_the_installed_wheel():
    assert mut.ompl_available() == (importlib.util.find_spec("ompl") is not None)


@pytest.mark.skipif(not mut.ompl_available(), reason="ompl not installed (pip install -e .[bench])")
def test_plans_a_collision_free_path_between_the_requested_ends():
    from pydrake.math import RigidTransform

    scene = PlanningScene()
    scene.add_box("wall", [0.3, 0.04, 0.4], RigidTransform([0.5, 0.0, 0.2]))
    q_start = np.array([-0.6, 0.3, 0.0, -1.8, 0.0, 2.1, 0.785])
    q_goal = np.array([0.6, 0.3, 0.0, -1.8, 0.0, 2.1, 0.785])
    adapter = CheckerAdapter(scene)
    assert adapter.config_free(q_start) and adapter.config_free(q_goal)
    path = mut.ompl_plan(scene, q_start, q_goal, timeout=5.0)
    assert path is not None
    np.testing.assert_allclose(path[0], q_start, atol=1e-9)
    np.testing.assert_allclose(path[-1], q_goal, atol=1e-9)
    # OMPL checks at the checker's edge step: re-check coarser than ours, at that same step.
    assert first_invalid_segment(adapter, path, scene.checker.edge_step_size()) is None
