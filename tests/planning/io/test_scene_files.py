"""Scene files: our pick-and-place YAML (load, save, round trip, held objects), MoveIt's
PlanningScene YAML (primitives, poses, allowed collisions), and malformed input, which raises
INVALID_SCENE naming the file and the key or object and leaves the scene as it was."""

import logging

import numpy as np
import pytest
import yaml
from pydrake.math import RigidTransform, RollPitchYaw

import planning.io.scene_files as mut
from planning import ErrorCode, PlanningError, PlanningScene, SceneObject

OUR_SCENE = """
table: {size: [1.0, 1.0, 0.04], position: [0.3, 0.0, -0.02]}
object: {size: [0.04, 0.04, 0.08], position: [0.5, 0.1, 0.04], mass: 0.1, yaw: 0.3}
obstacle: {size: [0.05, 0.3, 0.2], position: [0.5, -0.1, 0.1]}
place: {position: [0.5, -0.3, 0.04]}
objects:
  - {name: can, shape: cylinder, size: [0.03, 0.12], position: [0.4, 0.3, 0.06],
     orientation: [0, 0, 0.3826834, 0.9238795]}
  - {name: ball, shape: sphere, size: [0.05], position: [0.3, 0.4, 0.05]}
"""

MOVEIT_SCENE = """
world:
  collision_objects:
    - id: crate
      primitives: [{type: box, dimensions: [0.1, 0.2, 0.3]}]
      primitive_poses: [{position: [0.5, 0.0, 0.15], orientation: [0, 0, 0, 1]}]
    - id: pole
      pose: {position: {x: 0.0, y: 0.5, z: 0.0}, orientation: {x: 0, y: 0, z: 0, w: 1}}
      primitives: [{type: 3, dimensions: [0.4, 0.02]}, {type: sphere, dimensions: [0.05]}]
      primitive_poses:
        - {position: [0, 0, 0.2], orientation: [0.7071068, 0, 0, 0.7071068]}
        - {position: {x: 0, y: 0, z: 0.45}}
allowed_collision_matrix:
  entry_names: [panda_link1, panda_link7, crate]
  entry_values:
    - {enabled: [false, true, false]}
    - [true, false, true]
    - [false, true, false]
"""


@pytest.fixture(scope="module")
def base_scene():
    return PlanningScene()


@pytest.fixture
def scene(base_scene):
    """The shared scene, restored to the table alone after each test."""
    yield base_scene
    for name in list(base_scene.attached_objects):
        base_scene.remove_object(name)
    base_scene.clear()
    table = base_scene.config.table
    base_scene.add_box("table", table.size, RigidTransform(table.position))
    base_scene.place_position = None


def write(tmp_path, text, name="scene.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def assert_same_objects(actual: dict, expected: dict):
    assert sorted(actual) == sorted(expected)
    for name, obj in expected.items():
        again = actual[name]
        assert again.shape == obj.shape and again.size == pytest.approx(obj.size)
        assert again.X_PO.IsNearlyEqualTo(obj.X_PO, 1e-9), name


# ------------------------------------------------------------------------------ our YAML ----
def test_our_yaml_loads_every_key(scene, tmp_path):
    scene.add_box("old", [0.1, 0.1, 0.1], RigidTransform([0.0, 0.5, 0.5]))
    mut.load_scene_yaml(scene, write(tmp_path, OUR_SCENE))
    objects = scene.world_objects
    assert sorted(objects) == ["ball", "can", "object", "obstacle", "table"]  # "old" replaced
    assert objects["table"].size == (1.0, 1.0, 0.04)
    assert objects["object"].X_PO.rotation().ToRollPitchYaw().yaw_angle() == pytest.approx(0.3)
    np.testing.assert_allclose(objects["object"].X_PO.translation(), [0.5, 0.1, 0.04])
    assert objects["can"].shape == "cylinder" and objects["can"].size == (0.03, 0.12)
    yaw = objects["can"].X_PO.rotation().ToRollPitchYaw().yaw_angle()
    assert yaw == pytest.approx(np.pi / 4, abs=1e-6)
    assert objects["ball"].shape == "sphere" and objects["ball"].size == (0.05,)
    np.testing.assert_allclose(scene.place_position, [0.5, -0.3, 0.04])


def test_our_yaml_round_trips(scene, tmp_path):
    mut.load_scene_yaml(scene, write(tmp_path, OUR_SCENE))
    objects = scene.world_objects
    out = tmp_path / "saved.yaml"
    mut.save_scene_yaml(scene, out)
    data = yaml.safe_load(out.read_text())
    # Yaw-only boxes keep their own keys; everything else is under "objects".
    assert data["object"]["yaw"] == pytest.approx(0.3) and "yaw" not in data["obstacle"]
    assert sorted(o["name"] for o in data["objects"]) == ["ball", "can"]
    assert "attached" not in data
    scene.clear()
    scene.place_position = None
    mut.load_scene_yaml(scene, out)
    assert_same_objects(scene.world_objects, objects)
    np.testing.assert_allclose(scene.place_position, [0.5, -0.3, 0.04])


def test_tilted_boxes_and_held_objects_round_trip(scene, tmp_path):
    scene.clear()
    tilted = RigidTransform(RollPitchYaw(0.2, 0.0, 0.1), [0.5, 0.0, 0.3])
    scene.add_box("object", [0.05, 0.05, 0.1], tilted)  # not yaw-only: saved under objects
    scene.attach_new(SceneObject("held", "cylinder", (0.02, 0.1), RigidTransform([0, 0, 0.1])))
    world, held = scene.world_objects, scene.attached_objects
    out = tmp_path / "saved.yaml"
    mut.save_scene_yaml(scene, out)
    data = yaml.safe_load(out.read_text())
    assert "object" not in data and [o["name"] for o in data["objects"]] == ["object"]
    assert [o["name"] for o in data["attached"]] == ["held"]
    assert "place" not in data
    scene.remove_object("held")
    mut.load_scene_yaml(scene, out)
    assert_same_objects(scene.world_objects, world)
    assert_same_objects(scene.attached_objects, held)  # held again, in the hand's frame
    assert scene.place_position is None


def test_apply_scene_file_takes_a_parsed_spec(scene):
    spec = mut.SceneFile(
        table=mut.BoxSpec(size=[1.0, 1.0, 0.02], position=[0.3, 0.0, -0.01]),
        object=mut.BoxSpec(size=[0.04, 0.04, 0.04], position=[0.5, 0.0, 0.02], yaw=0.5),
        place=mut.PlaceSpec(position=[0.4, 0.2, 0.02]),
    )
    mut.apply_scene_file(scene, spec)
    assert sorted(scene.world_objects) == ["object", "table"]
    np.testing.assert_allclose(scene.place_position, [0.4, 0.2, 0.02])
    bad = mut.SceneFile(object=mut.BoxSpec(size=[0.04, 0.04], position=[0.5, 0.0, 0.02]))
    with pytest.raises(PlanningError) as info:
        mut.apply_scene_file(scene, bad, where="my scene")
    assert info.value.code == ErrorCode.INVALID_SCENE
    assert "my scene" in info.value.message and "object" in info.value.message
    assert sorted(scene.world_objects) == ["object", "table"]  # unchanged


DUPLICATES = (
    "objects: [{name: a, shape: sphere, size: [0.1], position: [0, 0, 1]},"
    " {name: a, shape: sphere, size: [0.1], position: [0, 0, 2]}]"
)


@pytest.mark.parametrize(
    "text, needles",
    [
        ("table: {size: [1, 1, 1], position: [0, 0]}", ["table position", "3 values"]),
        ("table: {size: [1, 1], position: [0, 0, 0]}", ["'table'", "3 size values"]),
        ("obstacle: {size: [1, 1, 1], position: [0, .nan, 0]}", ["obstacle", "finite"]),
        ("objects: [{name: x, shape: blob, size: [1], position: [0, 0, 0]}]", ["'x'", "blob"]),
        ("tabel: {size: [1, 1, 1]}", ["unknown", "tabel"]),
        ("object: {size: [1, 1, 1], position: [0, 0, 0], colour: red}", ["object.colour"]),
        ("object: {size: [1, 1, 1], position: [0, 0, 0], mass: heavy}", ["object.mass"]),
        ("table: {size: [1, 1, 1]", []),
        (DUPLICATES, ["duplicate", "'a'"]),
    ],
)
def test_malformed_yaml_raises_naming_the_file_and_key(scene, tmp_path, text, needles):
    path = write(tmp_path, text)
    with pytest.raises(PlanningError) as info:
        mut.load_scene_yaml(scene, path)
    assert info.value.code == ErrorCode.INVALID_SCENE
    for needle in [str(path), *needles]:
        assert needle in info.value.message
    assert list(scene.world_objects) == ["table"]  # a bad file leaves the scene as it was


def test_duplicate_names_are_an_invalid_scene(scene, tmp_path):
    with pytest.raises(PlanningError) as info:
        mut.load_scene_yaml(scene, write(tmp_path, DUPLICATES))
    assert info.value.code == ErrorCode.INVALID_SCENE
    assert "duplicate" in info.value.message and "'a'" in info.value.message
    assert list(scene.world_objects) == ["table"]


def test_missing_file_is_an_invalid_scene(scene, tmp_path):
    for load in (mut.load_scene_yaml, mut.load_moveit_scene):
        with pytest.raises(PlanningError) as info:
            load(scene, tmp_path / "nowhere.yaml")
        assert info.value.code == ErrorCode.INVALID_SCENE
        assert "nowhere.yaml" in info.value.message


def test_planning_scene_reads_and_writes_through_this_module(scene, tmp_path):
    scene.load_yaml(write(tmp_path, OUR_SCENE))
    objects = scene.world_objects
    scene.save_yaml(tmp_path / "saved.yaml")
    scene.load_moveit(write(tmp_path, MOVEIT_SCENE, "moveit.yaml"))
    assert sorted(scene.world_objects) == ["crate", "pole", "pole#1"]
    scene.load_yaml(tmp_path / "saved.yaml")
    assert_same_objects(scene.world_objects, objects)


# ------------------------------------------------------------------------ MoveIt's YAML ----
def test_moveit_scene_loads_primitives_poses_and_allowed_collisions(scene, tmp_path):
    scene.place_position = np.array([0.5, 0.0, 0.0])
    mut.load_moveit_scene(scene, write(tmp_path, MOVEIT_SCENE))
    objects = scene.world_objects
    assert sorted(objects) == ["crate", "pole", "pole#1"]  # the table is replaced
    assert scene.place_position is None
    crate, pole, ball = objects["crate"], objects["pole"], objects["pole#1"]
    assert crate.shape == "box" and crate.size == (0.1, 0.2, 0.3)
    np.testing.assert_allclose(crate.X_PO.translation(), [0.5, 0.0, 0.15])
    # A cylinder's [height, radius] becomes (radius, length); poses compose with the object's.
    assert pole.shape == "cylinder" and pole.size == (0.02, 0.4)
    np.testing.assert_allclose(pole.X_PO.translation(), [0.0, 0.5, 0.2])
    np.testing.assert_allclose(pole.X_PO.rotation().col(2), [0, -1, 0], atol=1e-6)  # along y
    assert ball.shape == "sphere" and ball.size == (0.05,)
    np.testing.assert_allclose(ball.X_PO.translation(), [0.0, 0.5, 0.45])
    # The allowed pair of links is filtered; the pair with an object is not a link pair.
    body = scene.plant.GetBodyByName
    assert scene.checker.IsCollisionFilteredBetween(body("panda_link1"), body("panda_link7"))
    assert not scene.checker.IsCollisionFilteredBetween(body("panda_link1"), body("panda_link6"))


def test_allowed_collision_matrix_parsing(caplog, scene, tmp_path):
    data = yaml.safe_load(MOVEIT_SCENE)
    pairs = mut.parse_allowed_collisions(data)
    assert pairs == [("panda_link1", "panda_link7"), ("panda_link7", "crate")]
    assert mut.parse_allowed_collisions({}) == []
    text = MOVEIT_SCENE.replace("panda_link1, panda_link7", "panda_link1, gripper_cam")
    with caplog.at_level(logging.WARNING, logger=mut.__name__):
        mut.load_moveit_scene(scene, write(tmp_path, text))
    assert "gripper_cam" in caplog.text and "not applied" in caplog.text
    for bad, needle in [
        ({"entry_names": ["a", "b"], "entry_values": [[False, True]]}, "2 names, 1 rows"),
        ({"entry_names": ["a", "b"], "entry_values": [[False], [True]]}, "row 0"),
    ]:
        with pytest.raises(ValueError, match=needle):
            mut.parse_allowed_collisions({"allowed_collision_matrix": bad})


def moveit_object(**entry):
    return yaml.safe_dump({"world": {"collision_objects": [entry]}})


BOX = {"type": "box", "dimensions": [0.1, 0.1, 0.1]}
AT_ORIGIN = {"position": [0, 0, 0]}


@pytest.mark.parametrize(
    "text, needle",
    [
        (
            moveit_object(
                id="c",
                primitives=[{"type": "cone", "dimensions": [1, 1]}],
                primitive_poses=[AT_ORIGIN],
            ),
            "cone",
        ),
        (moveit_object(id="c", primitives=[BOX], primitive_poses=[]), "1 primitives, 0 poses"),
        (moveit_object(id="m", meshes=[{"vertices": []}]), "'m'"),
        (moveit_object(primitives=[BOX], primitive_poses=[AT_ORIGIN]), "without an id"),
        (
            moveit_object(
                id="p", primitives=[BOX], primitive_poses=[{"orientation": [0, 0, 0, 1]}]
            ),
            "position",
        ),
        (
            moveit_object(
                id="cyl",
                primitives=[{"type": "cylinder", "dimensions": [1]}],
                primitive_poses=[AT_ORIGIN],
            ),
            "cylinder",
        ),
        (
            moveit_object(
                id="q",
                primitives=[BOX],
                primitive_poses=[{"position": [0, 0, 0], "orientation": [0, 0, 0, 0]}],
            ),
            "'q'",
        ),
        ("- just\n- a list\n", "mapping"),
        ("world: {collision_objects: [", "moveit.yaml"),
    ],
)
def test_malformed_moveit_scene_raises_naming_the_object(scene, tmp_path, text, needle):
    path = write(tmp_path, text, "moveit.yaml")
    with pytest.raises(PlanningError) as info:
        mut.load_moveit_scene(scene, path)
    assert info.value.code == ErrorCode.INVALID_SCENE
    assert needle in info.value.message and "moveit.yaml" in info.value.message
    assert list(scene.world_objects) == ["table"]
