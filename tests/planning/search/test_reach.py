"""planning.search.reach: the reach bound is conservative on random configurations and, for the
Panda, the classic shoulder-elbow-wrist chain."""

import numpy as np
import pytest

from planning import PlanningScene
from planning.search.reach import reach_bound


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


def test_the_panda_bound_is_its_joint_centre_chain_and_holds_everywhere(scene):
    plant, model = scene.plant, scene.model
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, scene.full_q(np.zeros(7)))
    frame = plant.GetFrameByName(model.ee_frame, model.instance)
    p_WA, reach = reach_bound(plant, context, frame)
    np.testing.assert_allclose(p_WA, [0, 0, 0.333], atol=1e-9)
    tool = 0.107 + 0.1034  # flange to the hand's TCP along the last axis
    expected = np.hypot(0.0825, 0.316) + np.hypot(0.0825, 0.384) + 0.088 + tool
    assert reach == pytest.approx(expected, abs=1e-6)
    rng = np.random.default_rng(0)
    farthest = 0.0
    for q in rng.uniform(scene.lower, scene.upper, (500, 7)):
        plant.SetPositions(context, scene.full_q(q))
        farthest = max(
            farthest, np.linalg.norm(frame.CalcPoseInWorld(context).translation() - p_WA)
        )
    assert reach - 0.1 < farthest <= reach + 1e-9
