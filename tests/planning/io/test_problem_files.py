"""problem_files: a scene and a request written as MoveIt messages load back with planning.io's
readers (the same objects, the same start and goal), in an MBM set's layout, atomically."""

import numpy as np
import pytest
import yaml
from pydrake.math import RigidTransform, RollPitchYaw

import planning.io.problem_files as mut
from drake_sim.base.errors import ConfigError
from planning import PlanningScene, SceneObject
from planning.io import mbm
from tests.planning.io.conftest import assert_same_objects

ARM = [f"panda_joint{i}" for i in range(1, 8)]
FINGERS = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.03}
CRATE_POSE = RigidTransform(RollPitchYaw(0.3, -0.2, 1.0), [0.5, 0.1, 0.2])
CAN_POSE = RigidTransform(RollPitchYaw(1.2, 0.0, 0.0), [0.1, -0.6, 0.4])
OBJECTS = [
    SceneObject("crate", "box", (0.2, 0.1, 0.3), CRATE_POSE),
    SceneObject("can", "cylinder", (0.04, 0.25), CAN_POSE),
    SceneObject("ball", "sphere", (0.07,), RigidTransform([-0.4, 0.3, 0.9])),
]


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


def write(folder, number=1):
    start = dict(zip(ARM, np.linspace(-1.0, 1.0, 7), strict=True)) | FINGERS
    goal = dict(zip(ARM, np.linspace(0.5, -0.5, 7), strict=True))
    return mut.write_problem(
        folder,
        "random",
        number,
        mut.scene_message(OBJECTS, "saved"),
        mut.request_message("panda_arm", start, goal),
    )


def test_files_load_back(tmp_path, scene):
    scene_file, request_file = write(tmp_path, 12)
    assert (scene_file, request_file) == mut.problem_paths(tmp_path, "random", 12)
    assert scene_file == tmp_path / "random" / "scene0012.yaml"
    scene.load_moveit(scene_file)
    assert_same_objects(scene.world_objects, {o.name: o for o in OBJECTS})
    request = mbm.load_request(request_file)
    np.testing.assert_array_equal(request.q_start[:7], np.linspace(-1.0, 1.0, 7))
    np.testing.assert_array_equal(request.q_start[7:], [0.02, 0.03])
    np.testing.assert_array_equal(request.q_goal[:7], np.linspace(0.5, -0.5, 7))
    data = yaml.safe_load(request_file.read_text())
    assert data["group_name"] == "panda_arm" and len(data["goal_constraints"]) == 1
    assert data["start_state"]["joint_state"]["name"] == [*ARM, *FINGERS]


def test_saved_folder_is_an_mbm_set(tmp_path):
    for number in (1, 2):
        write(tmp_path, number)
    assert mbm.problems_folder(tmp_path) == tmp_path
    problems = list(mbm.iter_problems(tmp_path, ["random"]))
    assert [(p.family, p.number, p.request_file.name) for p in problems] == [
        ("random", 1, "request0001.yaml"),
        ("random", 2, "request0002.yaml"),
    ]


def test_numpy_values_are_written_as_plain_numbers(tmp_path):
    message = mut.request_message("g", {"a": np.float64(0.5)}, {"a": np.float32(0.25)})
    _, request_file = mut.write_problem(tmp_path, "f", 1, mut.scene_message([]), message)
    assert "!!" not in request_file.read_text()


def test_a_folder_that_cannot_be_written_is_one_config_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.raises(ConfigError, match="cannot be written") as e:
        write(blocker)
    assert "\n" not in str(e.value)
    assert not (tmp_path / "random").exists()
