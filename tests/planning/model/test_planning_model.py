"""The planning model built from a robot description: the Panda as before (same joints, filters,
named configurations, attachment), other arms by name, and errors naming what is wrong."""

from pathlib import Path

import numpy as np
import pytest

from drake_sim.base.errors import ConfigError
from planning.model import planning_model as mut
from planning.model.model_config import RobotModelConfig


@pytest.fixture(scope="module")
def panda():
    return mut.build_planning_model(RobotModelConfig())


def test_the_panda_has_its_arm_fingers_and_attachment(panda):
    plant = panda.plant
    assert plant.num_positions() == 9 and panda.num_joints == 7
    assert list(panda.group_indices) == list(range(7))
    assert list(panda.finger_indices) == [7, 8] and list(panda.other_indices) == [7, 8]
    np.testing.assert_array_equal(panda.default_other, [0.04, 0.04])
    assert panda.joint_names == [f"panda_joint{i}" for i in range(1, 8)]
    assert panda.attachment_body == "panda_attachment" and panda.ee_frame == "panda_hand_tcp"
    attachment = plant.GetBodyByName("panda_attachment", panda.instance)
    hand = plant.GetBodyByName("panda_hand", panda.instance)
    context = plant.CreateDefaultContext()
    X = plant.EvalBodyPoseInWorld(context, attachment).GetAsMatrix4()
    np.testing.assert_allclose(X, plant.EvalBodyPoseInWorld(context, hand).GetAsMatrix4())


def test_srdf_and_touch_pairs_are_scene_graph_filters(panda):
    """Filters live in the SceneGraph model, so IK distance constraints see them too."""
    plant, inspector = panda.plant, panda.scene_graph.model_inspector()

    def filtered(a, b):
        ids_a = plant.GetCollisionGeometriesForBody(plant.GetBodyByName(a))
        ids_b = plant.GetCollisionGeometriesForBody(plant.GetBodyByName(b))
        return all(inspector.CollisionFiltered(i, j) for i in ids_a for j in ids_b)

    assert filtered("panda_hand", "panda_link5")  # "Default" in the SRDF: not adjacent
    assert filtered("panda_link3", "panda_rightfinger")
    assert not filtered("panda_link1", "panda_link7")
    assert not filtered("panda_link2", "panda_hand")
    assert ("panda_attachment", "panda_leftfinger") in panda.disabled_pairs
    assert ("panda_attachment", "panda_rightfinger") in panda.disabled_pairs


def test_named_configurations_come_from_the_description_then_the_config(panda):
    named = panda.named_configurations
    assert {"ready", "extended", "transport"} <= set(named)
    np.testing.assert_allclose(
        named["ready"], [0, -np.pi / 4, 0, -3 * np.pi / 4, 0, np.pi / 2, np.pi / 4]
    )
    np.testing.assert_array_equal(panda.home, named["ready"])
    for name, q in named.items():
        assert q.shape == (7,), name
        assert np.all(q >= panda.robot.lower) and np.all(q <= panda.robot.upper), name
    config = RobotModelConfig(named_configurations={"up": [0, 0, 0, -1, 0, 1, 0], "ready": [0] * 7})
    named = mut.named_configurations(config)
    assert named["up"][3] == -1 and not named["ready"].any() and "transport" in named


@pytest.mark.parametrize(
    "robot, joints, others", [("ur5", 6, 0), ("fetch", 8, None), ("baxter", 14, None)]
)
def test_shipped_arms_build_with_their_groups(robot, joints, others):
    try:
        model = mut.build_planning_model(RobotModelConfig(description=robot))
    except ConfigError as e:  # the vamp sdist cannot be had (no network, no cache)
        pytest.skip(str(e))
    assert model.num_joints == joints and len(model.robot.joint_names) == joints
    assert model.plant.num_positions() == joints + len(model.other_indices)
    if others is not None:
        assert len(model.other_indices) == others
    assert model.plant.HasBodyNamed(model.attachment_body, model.instance)


@pytest.mark.parametrize(
    "config, match",
    [
        (RobotModelConfig(description="nope"), "no shipped robot 'nope'"),
        (RobotModelConfig(description="missing/robot.yaml"), "robot.yaml"),
        (RobotModelConfig(ee_frame="no_such_frame"), "no frame 'no_such_frame'"),
        (RobotModelConfig(group="nogroup"), "nogroup"),
        (RobotModelConfig(named_configurations={"x": [0, 1]}), "has 2 values"),
        (RobotModelConfig(finger_position=0.5), "finger_position"),
        (RobotModelConfig(collision_geometry="voxels"), "collision_geometry"),
        (RobotModelConfig(description="ur5", collision_geometry="primitives"), "Panda only"),
    ],
)
def test_bad_configurations_name_the_problem(config, match):
    with pytest.raises(ConfigError, match=match):
        mut.build_planning_model(config)


def test_a_description_yaml_sets_frames_states_and_other_joints(tmp_path):
    shipped = mut.description_file("panda")
    text = shipped.read_text().replace(
        "joint_limits: panda/joint_limits.yaml",
        f"joint_limits: {shipped.parent}/panda/joint_limits.yaml",
    )
    path = tmp_path / "mine.yaml"
    path.write_text(
        text.replace("ee_frame: panda_hand_tcp", "ee_frame: panda_link8").replace(
            "default_positions: {panda_finger_joint1: 0.04, panda_finger_joint2: 0.04}",
            "default_positions: {panda_finger_joint1: 0.01}",
        )
    )
    model = mut.build_planning_model(RobotModelConfig(description=str(path)))
    assert model.ee_frame == "panda_link8"
    np.testing.assert_allclose(model.default_other, [0.01, 0.0])
    path.write_text(text.replace("attach_link: panda_hand", "attach_link: panda_link99"))
    with pytest.raises(ConfigError, match="attach_link: the URDF has no link 'panda_link99'"):
        mut.build_planning_model(RobotModelConfig(description=str(path)))


def test_a_description_is_a_shipped_name_first_then_a_path(tmp_path, monkeypatch):
    assert mut.description_file("ur5").name == "ur5.yaml"
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my_moveit_config").mkdir()
    (tmp_path / "panda").mkdir()  # a folder of that name does not hide the shipped robot
    assert mut.description_file("my_moveit_config") == Path("my_moveit_config")
    assert mut.description_file("panda").parent.name == "robots"
    assert mut.description_file("arms/mine.yaml") == Path("arms/mine.yaml")
    with pytest.raises(ConfigError, match="no shipped robot 'nope'"):
        mut.description_file("nope")
