"""Fixtures of the scene file tests: one planning scene for the whole folder, restored to the
table alone (and no allowed collisions beyond the robot's own) after each test."""

import pytest
import yaml
from hypothesis import event
from pydrake.math import RigidTransform

from planning import ErrorCode, PlanningError, PlanningScene, SceneObject


def assert_same_objects(actual: dict, expected: dict) -> None:
    """Two dicts of SceneObjects by name hold the same shapes, sizes and poses."""
    assert sorted(actual) == sorted(expected)
    for name, obj in expected.items():
        again = actual[name]
        assert again.shape == obj.shape and again.size == pytest.approx(obj.size), name
        assert again.X_PO.IsNearlyEqualTo(obj.X_PO, 1e-9), name


@pytest.fixture(scope="session")
def shared_scene():
    return PlanningScene()


def restore(scene) -> None:
    """Back to a new scene's contents: the table alone, the robot's own allowed collisions."""
    table = scene.config.table
    scene.replace([SceneObject("table", "box", tuple(table.size), RigidTransform(table.position))])


@pytest.fixture
def table_scene(shared_scene):
    """The shared scene, restored after the test."""
    restore(shared_scene)
    yield shared_scene
    restore(shared_scene)


@pytest.fixture
def write(tmp_path):
    """``write(text, name="scene.yaml")`` writes a file in the test's folder and returns its path
    (``text`` may be bytes)."""

    def write_file(text, name: str = "scene.yaml"):
        path = tmp_path / name
        if isinstance(text, bytes):
            path.write_bytes(text)
        else:
            path.write_text(text)
        return path

    return write_file


def load_corrupted(load, scene, tmp_path_factory, content, must_fail: bool) -> None:
    """Writes ``content`` (a parsed scene, or bytes) to a file in a new folder and loads it with
    ``load``: either INVALID_SCENE naming the file, the scene left as it was, or a valid scene
    (never when ``must_fail``); no other exception gets out. Restores the scene after."""
    path = tmp_path_factory.mktemp("corrupt") / "scene.yaml"
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(yaml.safe_dump(content))
    restore(scene)
    before = scene.world_objects
    try:
        load(scene, path)
        assert not must_fail, path.read_text()
        event("loaded")
    except PlanningError as e:
        assert e.code == ErrorCode.INVALID_SCENE and str(path) in e.message
        assert scene.world_objects == before
        event("INVALID_SCENE")
    finally:
        restore(scene)
