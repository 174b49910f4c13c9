"""Every MotionBenchMaker Panda scene loads into a PlanningScene and matches its file."""

import collections
from pathlib import Path

import numpy as np
import pytest
import yaml

import planning as mut
from drake_sim.base.resources import cache_dir
from planning.io import mbm


@pytest.fixture(scope="module")
def problems_dir():
    return mbm.unpack(mbm.default_dataset() / "problems.tar.bz2", cache_dir() / "mbm_panda")


@pytest.fixture(scope="module")
def scene():
    return mut.PlanningScene()


def expected_objects(scene_file):
    data = yaml.load(scene_file.read_text(), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    return {o["id"]: o for o in data["world"]["collision_objects"]}


def test_every_scene_loads_and_matches_its_file(problems_dir, scene):
    valid = collections.Counter()
    count = collections.Counter()
    for problem in mbm.iter_problems(problems_dir):
        scene.load_moveit(problem.scene_file)
        objects = scene.world_objects
        expected = expected_objects(problem.scene_file)
        assert sorted(objects) == sorted(expected), problem.scene_file
        for name, entry in expected.items():
            obj = objects[name]
            (primitive,) = entry["primitives"]
            (pose,) = entry["primitive_poses"]
            assert obj.shape == primitive["type"]
            dims = primitive["dimensions"]
            size = dims if obj.shape == "box" else [dims[1], dims[0]]
            np.testing.assert_allclose(obj.size, size)
            np.testing.assert_allclose(obj.X_PO.translation(), pose["position"], atol=1e-12)
            x, y, z, w = pose["orientation"]
            q = obj.X_PO.rotation().ToQuaternion()
            assert abs(np.dot([q.x(), q.y(), q.z(), q.w()], [x, y, z, w])) == pytest.approx(
                np.linalg.norm([x, y, z, w]), abs=1e-9
            )
        request = mbm.load_request(problem.request_file)
        count[problem.family] += 1
        valid[problem.family] += scene.is_collision_free(
            request.q_start
        ) and scene.is_collision_free(request.q_goal)
    assert set(count) == set(mbm.FAMILIES) and all(n == 100 for n in count.values())
    print("valid start and goal per family:", dict(valid))
    assert sum(valid.values()) >= 690


def test_allowed_collision_matrix_becomes_filters(problems_dir, scene):
    problem = next(mbm.iter_problems(problems_dir, families=["box_panda"], limit=1))
    scene.load_moveit(problem.scene_file)
    plant = scene.plant
    body = plant.GetBodyByName
    assert scene.checker.IsCollisionFilteredBetween(body("panda_link5"), body("panda_link7"))
    assert not scene.checker.IsCollisionFilteredBetween(body("panda_link1"), body("panda_link7"))


def test_request_reading(problems_dir):
    problem = next(mbm.iter_problems(problems_dir, families=["cage_panda"], limit=1))
    request = mbm.load_request(problem.request_file)
    assert request.q_start.shape == (9,) and request.q_goal.shape == (9,)
    np.testing.assert_array_equal(request.q_goal[7:], request.q_start[7:])


def test_default_dataset_is_the_repository_copy():
    folder = mbm.default_dataset()
    root = Path(mbm.__file__).resolve().parents[2]
    assert folder == root / "benchmarks" / "data" / "mbm_panda"
    assert (folder / "problems.tar.bz2").is_file() and (folder / "README.md").is_file()


def test_unpack_once_into_a_fresh_folder(tmp_path):
    archive = mbm.default_dataset() / "problems.tar.bz2"
    folder = mbm.unpack(archive, tmp_path)
    assert folder == tmp_path / "problems"
    assert sorted(p.name for p in folder.iterdir()) == sorted(mbm.FAMILIES)
    assert len(list(folder.glob("*/scene*.yaml"))) == 700
    assert [p.name for p in tmp_path.iterdir()] == ["problems"]  # no scratch folder left
    marker = folder / "box_panda" / "marker"
    marker.touch()
    assert mbm.unpack(archive, tmp_path) == folder and marker.is_file()  # not unpacked again


def test_bad_request_names_the_missing_joint(tmp_path):
    path = tmp_path / "request.yaml"
    path.write_text(
        "start_state: {joint_state: {name: [panda_joint1], position: [0]}}\n"
        "goal_constraints: [{joint_constraints: [{joint_name: panda_joint1, position: 0}]}]\n"
    )
    with pytest.raises(ValueError, match="panda_joint2"):
        mbm.load_request(path)
