"""Our scene YAML: load, save, round trip, held objects; loading replaces the whole scene;
malformed input raises INVALID_SCENE naming the file and the key or object and leaves the scene
as it was (property tests: generated scenes round-trip, corruptions are INVALID_SCENE). MoveIt's
files are tested in test_moveit_scene.py and test_moveit_text.py."""

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from pydrake.math import RigidTransform, RollPitchYaw

import planning.io.scene_files as mut
from planning import ErrorCode, PlanningError, SceneObject
from planning.io import moveit_scene
from tests.planning.io.conftest import assert_same_objects, load_corrupted, restore
from tests.planning.io.scene_strategies import corruptions, our_scenes

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


@pytest.fixture
def scene(table_scene):
    return table_scene


# ------------------------------------------------------------------------------ our YAML ----
def test_our_yaml_loads_every_key(scene, write, tmp_path):
    scene.add_box("old", [0.1, 0.1, 0.1], RigidTransform([0.0, 0.5, 0.5]))
    mut.load_scene_yaml(scene, write(OUR_SCENE))
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


def test_our_yaml_round_trips(scene, write, tmp_path):
    mut.load_scene_yaml(scene, write(OUR_SCENE))
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


def test_tilted_boxes_and_held_objects_round_trip(scene, write, tmp_path):
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


def test_convex_objects_and_colours_round_trip(scene, tmp_path):
    scene.clear()
    corners = [(x, y, z) for x in (0.0, 0.1) for y in (0.0, 0.2) for z in (0.0, 0.3)]
    X = RigidTransform(RollPitchYaw(0.2, 0.0, 0.1), [0.5, 0.0, 0.3])
    scene.add_object(SceneObject("hull", "convex", (), X, vertices=corners, color=(1, 0, 0, 1)))
    scene.add_object(SceneObject("red", "sphere", (0.1,), X, color=(1, 0, 0, 0.5)))
    world = scene.world_objects
    out = tmp_path / "saved.yaml"
    mut.save_scene_yaml(scene, out)
    data = yaml.safe_load(out.read_text())
    hull = data["objects"][0]
    assert hull["shape"] == "convex" and "size" not in hull and len(hull["vertices"]) == 8
    assert hull["color"] == [1.0, 0.0, 0.0, 1.0] and data["objects"][1]["color"][3] == 0.5
    scene.clear()
    mut.load_scene_yaml(scene, out)
    assert_same_objects(scene.world_objects, world)
    assert scene.world_objects["hull"].vertices == world["hull"].vertices
    assert [o.color for o in scene.world_objects.values()] == [o.color for o in world.values()]


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
        (
            "objects: [{name: h, shape: convex, vertices: [[0, 0, 0]], position: [0, 0, 0]}]",
            ["'h'", "at least 4 vertices"],
        ),
        (
            "objects: [{name: c, shape: sphere, size: [1], position: [0, 0, 0], color: [1]}]",
            ["'c'", "color must be"],
        ),
        ("tabel: {size: [1, 1, 1]}", ["unknown", "tabel"]),
        ("object: {size: [1, 1, 1], position: [0, 0, 0], colour: red}", ["object.colour"]),
        ("object: {size: [1, 1, 1], position: [0, 0, 0], mass: heavy}", ["object.mass"]),
        ("table: {size: [1, 1, 1]", []),
        (DUPLICATES, ["duplicate", "'a'"]),
    ],
)
def test_malformed_yaml_raises_naming_the_file_and_key(scene, write, text, needles):
    path = write(text)
    with pytest.raises(PlanningError) as info:
        mut.load_scene_yaml(scene, path)
    assert info.value.code == ErrorCode.INVALID_SCENE
    for needle in [str(path), *needles]:
        assert needle in info.value.message
    assert list(scene.world_objects) == ["table"]  # a bad file leaves the scene as it was


def test_duplicate_names_are_an_invalid_scene(scene, write):
    with pytest.raises(PlanningError) as info:
        mut.load_scene_yaml(scene, write(DUPLICATES))
    assert info.value.code == ErrorCode.INVALID_SCENE
    assert "duplicate" in info.value.message and "'a'" in info.value.message
    assert list(scene.world_objects) == ["table"]


def test_missing_and_non_utf8_files_are_an_invalid_scene(scene, write, tmp_path):
    for path, needle in [(tmp_path / "nowhere.yaml", "nowhere.yaml"), (write(b"a: \xff"), "UTF-8")]:
        for load in (mut.load_scene_yaml, mut.load_moveit_scene):
            with pytest.raises(PlanningError) as info:
                load(scene, path)
            assert info.value.code == ErrorCode.INVALID_SCENE
            assert needle in info.value.message and str(path) in info.value.message


@pytest.mark.parametrize("text", ["", " \n\n", "# a comment\n"])
def test_an_empty_file_is_an_invalid_scene(scene, write, text):
    path = write(text)
    with pytest.raises(PlanningError) as info:
        mut.load_scene_yaml(scene, path)
    assert info.value.code == ErrorCode.INVALID_SCENE
    assert info.value.message.startswith(f"{path}: empty scene file")
    assert list(scene.world_objects) == ["table"]


def test_an_explicitly_empty_scene_loads(scene, write):
    mut.load_scene_yaml(scene, write("{}\n"))
    assert scene.world_objects == {} and scene.place_position is None


def test_loading_replaces_the_whole_scene(scene, write):
    """Held objects and allowed collisions of the scene before are gone too."""
    scene.attach_new(SceneObject("held", "sphere", (0.02,), RigidTransform([0, 0, 0.1])))
    scene.allow_collision("panda_link2", "panda_link5")
    body = scene.plant.GetBodyByName
    assert scene.checker.IsCollisionFilteredBetween(body("panda_link2"), body("panda_link5"))
    mut.load_scene_yaml(scene, write(OUR_SCENE))
    assert scene.attached_objects == {}
    assert not scene.checker.IsCollisionFilteredBetween(body("panda_link2"), body("panda_link5"))
    assert scene.checker.IsCollisionFilteredBetween(body("panda_link0"), body("panda_link1"))


def test_moveit_names_stay_importable_from_here():
    assert mut.load_moveit_scene is moveit_scene.load_moveit_scene
    assert mut.parse_moveit_objects is moveit_scene.parse_moveit_objects
    assert mut.parse_allowed_collisions is moveit_scene.parse_allowed_collisions


def test_planning_scene_reads_and_writes_through_this_module(scene, write, tmp_path):
    scene.load_yaml(write(OUR_SCENE))
    objects = scene.world_objects
    scene.save_yaml(tmp_path / "saved.yaml")
    scene.clear()
    scene.load_yaml(tmp_path / "saved.yaml")
    assert_same_objects(scene.world_objects, objects)


# ------------------------------------------------------------------------ property tests ----
def expected_objects(data: dict) -> tuple[dict, dict]:
    """The world and held objects a generated scene of our YAML describes."""
    world = {}
    for key in ("table", "object", "obstacle"):
        if key in data:
            box = data[key]
            X = RigidTransform(RollPitchYaw(0, 0, box["yaw"]), box["position"])
            world[key] = SceneObject(key, "box", tuple(box["size"]), X)

    def objects(entries):
        return {
            o["name"]: SceneObject(
                o["name"],
                o["shape"],
                tuple(o["size"]),
                mut.make_pose(o["position"], o.get("orientation")),
            )
            for o in entries
        }

    return world | objects(data.get("objects", [])), objects(data.get("attached", []))


@settings(max_examples=60, derandomize=True, deadline=None)
@given(data=our_scenes())
def test_generated_scenes_load_and_round_trip(shared_scene, tmp_path_factory, data):
    folder = tmp_path_factory.mktemp("round_trip")
    (folder / "in.yaml").write_text(yaml.safe_dump(data))
    try:
        mut.load_scene_yaml(shared_scene, folder / "in.yaml")
        world, held = expected_objects(data)
        assert_same_objects(shared_scene.world_objects, world)
        assert_same_objects(shared_scene.attached_objects, held)
        mut.save_scene_yaml(shared_scene, folder / "out.yaml")
        restore(shared_scene)
        mut.load_scene_yaml(shared_scene, folder / "out.yaml")
        assert_same_objects(shared_scene.world_objects, world)
        assert_same_objects(shared_scene.attached_objects, held)
        place = data.get("place", {}).get("position")
        if place is None:
            assert shared_scene.place_position is None
        else:
            np.testing.assert_allclose(shared_scene.place_position, place)
    finally:
        restore(shared_scene)


@settings(max_examples=250, derandomize=True, deadline=None)
@given(corruption=corruptions(our_scenes()))
def test_corruptions_are_an_invalid_scene(shared_scene, tmp_path_factory, corruption):
    load_corrupted(mut.load_scene_yaml, shared_scene, tmp_path_factory, *corruption)
