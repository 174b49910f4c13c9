"""The scene the search tests share: the table and a box around the hand at "ready", between
two ends 1.6 rad apart on the first joint."""

import numpy as np
import pytest

E = np.eye(7)


@pytest.fixture(scope="module")
def scene(wall_scene):
    """The wall scene (``tests/planning/conftest.py``), between the start and the goal."""
    return wall_scene


@pytest.fixture(scope="module")
def ends(scene):
    """Either side of the wall: "ready" turned 0.8 rad back and forth on the first joint."""
    ready = scene.model.named_configurations["ready"]
    return ready - 0.8 * E[0], ready + 0.8 * E[0]
