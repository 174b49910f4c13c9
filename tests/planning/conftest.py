"""Fixtures the planning tests share."""

import pytest
from pydrake.math import RigidTransform

from planning import PlanningScene


@pytest.fixture(scope="module")
def wall_scene():
    """The table and a wall around the hand at "ready"; turning joint 1 by 0.8 rad either way
    clears it."""
    scene = PlanningScene()
    ready = scene.model.named_configurations["ready"]
    scene.add_box(
        "wall", [0.1, 0.1, 0.3], RigidTransform(scene.attachment_pose(ready).translation())
    )
    return scene
