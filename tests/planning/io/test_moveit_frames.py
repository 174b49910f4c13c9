"""planning.io.moveit_frames: a scene's frames on the loaded robot (links from its plant, never
from a list of names), its robot state as plant positions, and MoveIt's defaults."""

import numpy as np
import pytest

from planning import PlanningScene
from planning.io import moveit_frames as mut
from planning.io.moveit_objects import Issues


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


def test_links_and_name_come_from_the_plant(scene):
    links = mut.robot_links(scene)
    assert {"panda_link0", "panda_hand", "panda_attachment"} <= set(links)
    assert mut.robot_name(scene) == "panda"


def test_a_joint_state_sets_what_it_names_and_keeps_the_rest(scene):
    issues = Issues("scene.yaml")
    state = {"name": ["panda_joint2", "elbow_joint"], "position": [0.5, 1.0]}
    q, named = mut.configuration(scene, state, issues)
    default = mut.default_configuration(scene)
    assert named == {"panda_joint2": 0.5} and q[1] == 0.5
    np.testing.assert_array_equal(np.delete(q, 1), np.delete(default, 1))
    np.testing.assert_array_equal(default[7:], scene.other_positions)  # the fingers stay
    assert any("elbow_joint" in w for w in issues.warnings)


def test_frames_resolve_world_links_and_unknowns(scene):
    frames = mut.SceneFrames({}, scene, Issues("scene.yaml"))
    assert frames.X_WF("world").IsExactlyIdentity()
    hand = frames.X_WF("panda_hand")
    expected = scene.plant.EvalBodyPoseInWorld(
        scene.plant_context(frames.q), scene.plant.GetBodyByName("panda_hand")
    )
    np.testing.assert_allclose(hand.GetAsMatrix4(), expected.GetAsMatrix4(), atol=1e-12)
    assert frames.X_WF("no_such_frame") is None
