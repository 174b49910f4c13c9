"""OMPL RRTConnect plus path simplification on the same Drake collision checker (a baseline).

Used by ``python -m planning.benchmark --compare-ompl`` when the ``ompl`` wheel from PyPI is
installed. States are checked with the scene's ``SceneGraphCollisionChecker`` through a Python
callback; motions with OMPL's discrete motion validator at the same joint-space step as the
checker's edge step. OMPL's returned path is then re-checked at the fine resolution like ours.
"""

from __future__ import annotations

import numpy as np

from planning.collision.checker import CheckerAdapter


def ompl_available() -> bool:
    """True when the ``ompl`` wheel (the ``bench`` extra) is installed."""
    try:
        import ompl  # noqa: F401
    except ImportError:
        return False
    return True


def ompl_plan(scene, q_start, q_goal, timeout: float, simplify: bool = True):
    """Plans with OMPL's RRTConnect (and ``simplifySolution``) on the scene's checker.

    Args:
        scene: the planning scene (fingers already set).
        q_start, q_goal: 7 arm joints each, rad.
        timeout: s for the search (simplification gets the time left, at least 0.1 s).

    Returns:
        (N, n) waypoints, or None when OMPL found no exact solution.
    """
    from ompl import base as ob
    from ompl import geometric as og

    adapter = CheckerAdapter(scene)
    n = scene.num_joints
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for i in range(n):
        bounds.setLow(i, float(adapter.lower[i]))
        bounds.setHigh(i, float(adapter.upper[i]))
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    q = np.empty(n)

    def valid(state) -> bool:
        for i in range(n):
            q[i] = state[i]
        return adapter.config_free(q)

    setup.setStateValidityChecker(valid)
    step = scene.checker.edge_step_size()
    setup.getSpaceInformation().setStateValidityCheckingResolution(step / space.getMaximumExtent())
    start, goal = space.allocState(), space.allocState()
    for i in range(n):
        start[i] = float(q_start[i])
        goal[i] = float(q_goal[i])
    setup.setStartAndGoalStates(start, goal)
    setup.setPlanner(og.RRTConnect(setup.getSpaceInformation()))
    solved = setup.solve(timeout)
    if not solved or not setup.haveExactSolutionPath():
        return None
    if simplify:
        setup.simplifySolution(max(0.1, timeout - setup.getLastPlanComputationTime()))
    path = setup.getSolutionPath()
    return np.array([[path.getState(k)[i] for i in range(n)] for k in range(path.getStateCount())])
