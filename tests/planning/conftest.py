"""Fixtures the planning tests share."""

import pytest
from pydrake.math import RigidTransform

from planning import PlanningScene
from tests.mbm_helpers import mbm_problems


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


@pytest.fixture(scope="session")
def mbm_folder():
    """The unpacked MotionBenchMaker Panda problems folder (``tests/mbm_helpers.py``: the copy
    in ``shared/`` when present, else the library's finder); the test skips, saying why, when
    they cannot be had."""
    return mbm_problems()
