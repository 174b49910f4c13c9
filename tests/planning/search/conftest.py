"""The scene the search tests share: the table and a box around the hand at "ready", between
two ends 1.6 rad apart on the first joint."""

import numpy as np
import pytest
from pydrake.math import RigidTransform

from planning import PlanningScene

E = np.eye(7)


@pytest.fixture(scope="module")
def scene():
    """The table and a wall around the hand at "ready", between the start and the goal."""
    scene = PlanningScene()
    ready = scene.model.named_configurations["ready"]
    scene.add_box(
        "wall", [0.1, 0.1, 0.3], RigidTransform(scene.attachment_pose(ready).translation())
    )
    return scene


@pytest.fixture(scope="module")
def ends(scene):
    """Either side of the wall: "ready" turned 0.8 rad back and forth on the first joint."""
    ready = scene.model.named_configurations["ready"]
    return ready - 0.8 * E[0], ready + 0.8 * E[0]
