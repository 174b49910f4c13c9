"""publish_scene in a headless Meshcat: the robot at q, world objects grey (the table brown),
held objects orange at the hand, removed objects deleted; nothing without a Meshcat. What
Meshcat holds is read back from its ``StaticHtml`` (msgpack commands)."""

import base64
import dataclasses
import re
from types import SimpleNamespace

import numpy as np
import pytest
from pydrake.geometry import Meshcat
from pydrake.math import RigidTransform

import planning.scene_display as mut
from planning import PlanningScene, SceneObject

msgpack = pytest.importorskip("msgpack")

_BLOB = re.compile(r'"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"')


def meshcat_commands(meshcat) -> dict:
    """{(command type, path below /drake/): command} for the scene Meshcat holds now."""
    commands = {}
    for blob in _BLOB.findall(meshcat.StaticHtml()):
        try:
            command = msgpack.unpackb(base64.b64decode(blob), raw=False, strict_map_key=False)
        except (ValueError, msgpack.UnpackException):
            continue  # mesh data, not a command
        if isinstance(command, dict) and "path" in command:
            commands[command["type"], command["path"].removeprefix("/drake/")] = command
    return commands


def pose(commands, path) -> RigidTransform:
    matrix = np.reshape(commands["set_transform", path]["matrix"], (4, 4)).T  # column-major
    return RigidTransform(matrix)


def material(commands, path) -> tuple[int, float]:
    """(colour as 0xRRGGBB, opacity) of the object at path."""
    (first, *_) = commands["set_object", path]["object"]["materials"]
    return first["color"], first["opacity"]


@pytest.fixture(scope="module")
def meshcat():
    return Meshcat()


@pytest.fixture(scope="module")
def scene(meshcat):
    return PlanningScene(meshcat=meshcat)


@pytest.fixture(scope="module")
def q(scene):
    return scene.model.named_configurations["extended"]


BALL = RigidTransform([0.5, 0.3, 0.2])
HELD = SceneObject("held", "box", (0.04, 0.04, 0.04), RigidTransform([0.0, 0.0, 0.11]))


@pytest.fixture(scope="module")
def published(scene, meshcat, q):
    """The scene with a ball and a held box, published at q; the commands Meshcat then holds."""
    scene.add_sphere("ball", 0.05, BALL)
    scene.add_box("crate", [0.1, 0.1, 0.1], RigidTransform([0.6, -0.3, 0.05]))
    scene.attach_new(HELD)
    mut.publish_scene(scene, q)
    return meshcat_commands(meshcat)


def test_world_objects_are_drawn_where_they_are(scene, meshcat, published):
    for name, obj in scene.world_objects.items():
        path = f"{mut.PREFIX}/world/{name}"
        assert meshcat.HasPath(path)
        assert pose(published, path).IsNearlyEqualTo(obj.X_PO, 1e-12)
    ball = published["set_object", f"{mut.PREFIX}/world/ball"]["object"]["geometries"][0]
    assert ball["type"] == "SphereGeometry" and ball["radius"] == pytest.approx(0.05)


def test_held_objects_are_drawn_at_the_hand(scene, meshcat, published, q):
    path = f"{mut.PREFIX}/attached/held"
    assert meshcat.HasPath(path) and not meshcat.HasPath(f"{mut.PREFIX}/world/held")
    assert pose(published, path).IsNearlyEqualTo(scene.object_pose("held", q), 1e-12)


def test_colours_tell_the_table_world_and_held_objects_apart(published):
    table = material(published, f"{mut.PREFIX}/world/table")
    ball = material(published, f"{mut.PREFIX}/world/ball")
    crate = material(published, f"{mut.PREFIX}/world/crate")
    held = material(published, f"{mut.PREFIX}/attached/held")
    assert ball == crate  # every world object alike ...
    assert len({table, ball, held}) == 3  # ... but the table and held objects differ
    assert table[1] == mut.TABLE_COLOR.a() and ball[1] == pytest.approx(mut.WORLD_COLOR.a())
    assert held[1] == pytest.approx(mut.ATTACHED_COLOR.a())


def test_objects_with_a_colour_of_their_own_are_drawn_in_it(scene, meshcat, q):
    corners = [(x, y, z) for x in (0.0, 0.1) for y in (0.0, 0.1) for z in (0.0, 0.1)]
    hull = SceneObject("hull", "convex", (), RigidTransform([0.3, -0.4, 0.0]), vertices=corners)
    scene.add_object(dataclasses.replace(hull, color=(1.0, 0.0, 0.0, 0.5)))
    scene.attach_new(SceneObject("blue", "sphere", (0.01,), RigidTransform(), color=(0, 0, 1, 1)))
    try:
        mut.publish_scene(scene, q)
        commands = meshcat_commands(meshcat)
        assert material(commands, f"{mut.PREFIX}/world/hull") == (0xFF0000, 0.5)
        assert material(commands, f"{mut.PREFIX}/attached/blue") == (0x0000FF, 1.0)
        assert pose(commands, f"{mut.PREFIX}/world/hull").IsNearlyEqualTo(hull.X_PO, 1e-12)
    finally:
        scene.remove_object("hull")
        scene.remove_object("blue")


def test_robot_is_drawn_at_q(scene, published, q):
    plant = scene.plant
    X_WH = plant.EvalBodyPoseInWorld(scene.plant_context(q), plant.GetBodyByName("panda_hand"))
    assert pose(published, "planning/robot/panda/panda_hand").IsNearlyEqualTo(X_WH, 1e-9)


def test_removed_objects_disappear_at_the_next_publish(scene, meshcat, published, q):
    scene.add_box("gone", [0.1, 0.1, 0.1], RigidTransform([0.0, -0.5, 0.05]))
    scene.attach_new(SceneObject("gone_held", "sphere", (0.02,), RigidTransform([0, 0, 0.2])))
    mut.publish_scene(scene, q)
    assert meshcat.HasPath(f"{mut.PREFIX}/world/gone")
    assert meshcat.HasPath(f"{mut.PREFIX}/attached/gone_held")
    scene.remove_object("gone")
    scene.remove_object("gone_held")
    mut.publish_scene(scene, q)
    assert not meshcat.HasPath(f"{mut.PREFIX}/world/gone")
    assert not meshcat.HasPath(f"{mut.PREFIX}/attached/gone_held")
    for path in ("world/ball", "world/crate", "world/table", "attached/held"):
        assert meshcat.HasPath(f"{mut.PREFIX}/{path}")  # the others stay


def test_without_meshcat_nothing_is_drawn():
    # Only ``meshcat`` is there: touching anything else (the model, the objects) would fail.
    assert mut.publish_scene(SimpleNamespace(meshcat=None), np.zeros(7)) is None
