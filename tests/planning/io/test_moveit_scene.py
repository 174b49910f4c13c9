"""MoveIt's PlanningScene YAML: primitives and poses, header frames (world names, fixed frames,
robot links at the scene's joint state), held objects, operations, allowed collisions (replaced
by the next scene), INVALID_SCENE naming the file and key path for anything malformed, and one
warning (INVALID_SCENE when strict) for what cannot be represented; the reader is picked by the
file's extension. Property tests: generated scenes load as described, corruptions are
INVALID_SCENE. Meshes, planes, colours, subframes and start states: test_moveit_features.py;
the real files: test_moveit_real_files.py."""

import logging
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from pydrake.math import RigidTransform

import planning.io.moveit_scene as mut
from planning import ErrorCode, PlanningError, SceneObject, make_pose
from planning.model.panda import ARM_JOINTS
from tests.planning.io.conftest import assert_same_objects, load_corrupted, restore
from tests.planning.io.scene_strategies import corruptions, moveit_scenes

SCENE = """
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
# A configuration where only panda_link2 and panda_link5 collide.
SELF_COLLIDING = [2.561, -1.368, 1.56, -3.011, -1.528, 3.264, -0.869]


@pytest.fixture
def scene(table_scene):
    return table_scene


def box(name="b", frame=None, position=(0.5, 0.0, 0.1), **extra) -> dict:
    entry = {
        "id": name,
        "primitives": [{"type": "box", "dimensions": [0.1, 0.1, 0.1]}],
        "primitive_poses": [{"position": list(position)}],
        **extra,
    }
    if frame is not None:
        entry["header"] = {"frame_id": frame}
    return entry


def scene_text(*objects, **keys) -> str:
    return yaml.safe_dump({"world": {"collision_objects": list(objects)}, **keys})


def load_error(scene, path, **options) -> str:
    before = scene.world_objects
    with pytest.raises(PlanningError) as info:
        mut.load_moveit_scene(scene, path, **options)
    assert info.value.code == ErrorCode.INVALID_SCENE
    assert str(path) in info.value.message
    assert scene.world_objects == before  # a bad file leaves the scene as it was
    return info.value.message


def test_primitives_poses_and_allowed_collisions(scene, write):
    scene.place_position = np.array([0.5, 0.0, 0.0])
    mut.load_moveit_scene(scene, write(SCENE))
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
    body = scene.plant.GetBodyByName
    assert scene.checker.IsCollisionFilteredBetween(body("panda_link1"), body("panda_link7"))
    assert not scene.checker.IsCollisionFilteredBetween(body("panda_link1"), body("panda_link6"))


def test_allowed_collision_matrix_parsing(caplog, scene, write):
    pairs = mut.parse_allowed_collisions(yaml.safe_load(SCENE))
    assert pairs == [("panda_link1", "panda_link7"), ("panda_link7", "crate")]
    assert mut.parse_allowed_collisions({}) == []
    half = {"entry_names": ["a", "b"], "entry_values": [[False, True], [False, False]]}
    assert mut.parse_allowed_collisions({"allowed_collision_matrix": half}) == [("a", "b")]
    with caplog.at_level(logging.WARNING, logger=mut.__name__):
        mut.load_moveit_scene(
            scene, write(SCENE.replace("panda_link1, panda", "gripper_cam, panda"))
        )
    assert "gripper_cam" in caplog.text and "not applied" in caplog.text
    for bad, needle in [
        ({"entry_names": ["a", "b"], "entry_values": [[False, True]]}, "2 entry_names, 1"),
        ({"entry_names": ["a", "b"], "entry_values": [[False], [True]]}, "entry_values[0] must"),
        ({"entry_names": ["a"], "entry_values": [[1]]}, "entry_values[0][0] must be true"),
        ({"entry_names": ["a"], "entry_values": [{"on": [True]}]}, "unknown key 'on'"),
    ]:
        with pytest.raises(ValueError) as info:
            mut.parse_allowed_collisions({"allowed_collision_matrix": bad})
        assert needle in str(info.value)


def test_allowed_collisions_do_not_outlive_their_scene(scene, write):
    """A scene allowing link 2 and link 5 to touch, then one that does not."""
    assert scene.colliding_pairs(SELF_COLLIDING) == [("panda_link2", "panda_link5")]
    acm = {"entry_names": ["panda_link2", "panda_link5"], "entry_values": [[0, 1], [1, 0]]}
    acm["entry_values"] = [[bool(v) for v in row] for row in acm["entry_values"]]
    mut.load_moveit_scene(scene, write(scene_text(box(), allowed_collision_matrix=acm)))
    assert scene.is_collision_free(SELF_COLLIDING)
    mut.load_moveit_scene(scene, write(scene_text(box())))
    assert not scene.is_collision_free(SELF_COLLIDING)
    assert scene.colliding_pairs(SELF_COLLIDING) == [("panda_link2", "panda_link5")]


@pytest.mark.parametrize("frame", ["", "world", "/world", "panda_link0"])
def test_world_frame_names(scene, write, frame):
    mut.load_moveit_scene(scene, write(scene_text(box(frame=frame))))
    np.testing.assert_allclose(scene.world_objects["b"].X_PO.translation(), [0.5, 0.0, 0.1])


def test_link_frames_at_the_scenes_joint_state(scene, write):
    q = [0.3, -0.5, 0.2, -2.0, 0.1, 1.8, 0.4]
    state = {"joint_state": {"name": list(ARM_JOINTS), "position": q}}
    pose = {"position": [0.0, 0.0, 0.2], "orientation": [0, 0, 0.3826834, 0.9238795]}
    entry = box(frame="panda_hand", pose=pose)
    mut.load_moveit_scene(scene, write(scene_text(entry, robot_state=state)))
    X_WH = scene.plant.EvalBodyPoseInWorld(
        scene.plant_context(q), scene.plant.GetBodyByName("panda_hand")
    )
    expected = (
        X_WH @ make_pose(pose["position"], pose["orientation"]) @ RigidTransform([0.5, 0, 0.1])
    )
    assert scene.world_objects["b"].X_PO.IsNearlyEqualTo(expected, 1e-9)
    # Joints the state does not name are at MoveIt's default: 0, or mid-range (joint 4).
    mut.load_moveit_scene(scene, write(scene_text(box(frame="panda_link5"))))
    lower, upper = scene.plant.GetPositionLowerLimits(), scene.plant.GetPositionUpperLimits()
    default = np.where((lower <= 0) & (upper >= 0), 0.0, (lower + upper) / 2)[:7]
    X_W5 = scene.plant.EvalBodyPoseInWorld(
        scene.plant_context(default), scene.plant.GetBodyByName("panda_link5")
    )
    expected = X_W5 @ RigidTransform([0.5, 0, 0.1])
    assert scene.world_objects["b"].X_PO.IsNearlyEqualTo(expected, 1e-9)


def test_fixed_frames(scene, write):
    fixed = [
        {
            "child_frame_id": "world",
            "transform": {"translation": [0, 0, 0], "rotation": [0, 0, 0, 1]},
        },
        {
            "header": {"frame_id": "world"},
            "child_frame_id": "shelf",
            "transform": {"translation": {"x": 1.0, "y": 2.0, "z": 0.0}},
        },
    ]
    mut.load_moveit_scene(
        scene, write(scene_text(box(frame="shelf"), fixed_frame_transforms=fixed))
    )
    np.testing.assert_allclose(scene.world_objects["b"].X_PO.translation(), [1.5, 2.0, 0.1])


def test_attached_collision_objects_hang_on_the_hand(scene, write):
    pose = {"position": [0.0, 0.0, 0.1]}
    held = {"link_name": "panda_hand", "object": box("held", frame="panda_hand", pose=pose)}
    held["touch_links"] = ["panda_hand", "panda_leftfinger", "panda_rightfinger"]
    state = {"attached_collision_objects": [held]}
    mut.load_moveit_scene(scene, write(scene_text(box(), robot_state=state)))
    assert list(scene.attached_objects) == ["held"] and list(scene.world_objects) == ["b"]
    X_WH = scene.plant.GetBodyByName("panda_hand")
    for q in (np.zeros(7), np.array(SELF_COLLIDING)):
        hand = scene.plant.EvalBodyPoseInWorld(scene.plant_context(q), X_WH)
        expected = hand @ RigidTransform([0.5, 0.0, 0.2])
        assert scene.object_pose("held", q).IsNearlyEqualTo(expected, 1e-9)
    # A held object given in the world is kept where it is at the scene's joint state.
    held["object"] = box("held", frame="world", position=(0.4, 0.1, 0.5))
    mut.load_moveit_scene(scene, write(scene_text(robot_state=state)))
    held_at = scene.object_pose("held", moveit_default(scene)).translation()
    np.testing.assert_allclose(held_at, [0.4, 0.1, 0.5], atol=1e-9)


def moveit_default(scene) -> np.ndarray:
    """MoveIt's default arm configuration: 0, or mid-range where 0 is out of range."""
    lower, upper = scene.plant.GetPositionLowerLimits(), scene.plant.GetPositionUpperLimits()
    return np.where((lower <= 0) & (upper >= 0), 0.0, (lower + upper) / 2)[:7]


def test_operations(caplog, scene, write):
    moved = {"position": [0.0, 1.0, 0.0]}
    objects = [
        box("a", position=(1, 0, 0)),
        box("b", position=(2, 0, 0), operation=0),
        box("c", position=(3, 0, 0), operation="ADD"),
        box("a", position=(1, 0, 1), operation=2),  # APPEND: a second shape for a
        box("b", operation="remove"),
        {"id": "c", "operation": 3, "pose": moved},  # MOVE by the object's pose
        box("d", position=(4, 0, 0)),
        {"id": "d", "operation": "MOVE", "primitive_poses": [{"position": [5, 0, 0]}]},
        box("e", position=(6, 0, 0)),
        box("e", position=(7, 0, 0), operation="ADD"),  # ADD again replaces
        {"id": "ghost", "operation": 1},  # REMOVE of nothing: a warning
    ]
    with caplog.at_level(logging.WARNING, logger=mut.__name__):
        mut.load_moveit_scene(scene, write(scene_text(*objects)))
    assert "ghost" in caplog.text
    objects = scene.world_objects
    assert sorted(objects) == ["a", "a#1", "c", "d", "e"]
    where = {name: objects[name].X_PO.translation().tolist() for name in objects}
    assert where == {
        "a": [1, 0, 0],
        "a#1": [1, 0, 1],
        "c": [3, 1, 0],
        "d": [5, 0, 0],
        "e": [7, 0, 0],
    }
    everything = scene_text(box("a"), box("b"), {"id": "", "operation": "REMOVE"}, box("z"))
    mut.load_moveit_scene(scene, write(everything))
    assert list(scene.world_objects) == ["z"]


def data_cases(kind: str, key: str) -> list:
    """The ``kind`` cases of data/malformed_moveit_scenes.yaml as (file contents, needle)."""
    cases = yaml.safe_load(
        (Path(__file__).parent / "data/malformed_moveit_scenes.yaml").read_text()
    )
    params = []
    for case in cases[kind]:
        data = case.get("scene", {})
        if "objects" in case:
            data = {**data, "world": {"collision_objects": case["objects"]}}
        params.append(pytest.param(data, case[key], id=case[key][:60]))
    return params


@pytest.mark.parametrize("data, needle", data_cases("cases", "error"))
def test_malformed_scenes_name_the_key_path(scene, write, data, needle):
    assert needle in load_error(scene, write(yaml.safe_dump(data)))
    assert needle in load_error(scene, write(yaml.safe_dump(data)), strict=True)


@pytest.mark.parametrize("data, needle", data_cases("dropped", "warning"))
def test_what_cannot_be_represented_is_one_warning_or_strictly_an_error(
    caplog, scene, write, data, needle
):
    path = write(yaml.safe_dump(data))
    assert needle in load_error(scene, path, strict=True)
    with caplog.at_level(logging.WARNING):
        loaded = mut.load_moveit_scene(scene, path)
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1 and needle in warnings[0] and str(path) in warnings[0]
    assert loaded.warnings == warnings
    assert scene.world_objects  # the rest of the file loaded


def test_files_that_are_not_scenes(scene, write, tmp_path):
    assert "not UTF-8" in load_error(scene, write(b"world: \xff\xfe"))
    assert "malformed YAML" in load_error(scene, write("world: {collision_objects: ["))
    assert "no such scene file" in load_error(scene, tmp_path / "nowhere.yml")
    assert "not a MoveIt scene file" in load_error(scene, write(SCENE, "scene.txt"))


@pytest.mark.parametrize("text", ["", "  \n\n", "# nothing here\n", "---\n", "null\n"])
def test_an_empty_file_is_an_invalid_scene(scene, write, text):
    message = load_error(scene, write(text))
    assert "empty scene file" in message


def test_a_scene_without_name_or_objects_loads_empty_with_one_warning(caplog, scene, write):
    with caplog.at_level(logging.WARNING, logger=mut.__name__):
        mut.load_moveit_scene(scene, write("{}\n"))
    assert scene.world_objects == {}
    warnings = [r for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1
    assert "no name and no objects" in warnings[0].getMessage()
    assert "scene.yaml" in warnings[0].getMessage()
    restore(scene)
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger=mut.__name__):
        mut.load_moveit_scene(scene, write("name: cleared\nworld: {collision_objects: []}\n"))
        mut.load_moveit_scene(scene, write(scene_text(box("b"))))  # objects, no name
    assert list(scene.world_objects) == ["b"]
    assert caplog.records == []  # an explicitly empty scene, or a nameless one with objects


def test_the_extension_picks_the_reader(scene, write):
    text_scene = "(noname)+\n* crate\n1\nbox\n0.1 0.2 0.3\n0.5 0 0.15\n0 0 0 1\n0 0 0 0\n.\n"
    for name, text in [("a.scene", text_scene), ("a.yml", SCENE), ("a.YAML", SCENE)]:
        restore(scene)
        scene.load_moveit(write(text, name))
        assert "crate" in scene.world_objects and "table" not in scene.world_objects, name


def test_parse_without_a_scene(scene):
    data = yaml.safe_load(SCENE)
    assert sorted(o.name for o in mut.parse_moveit_objects(data)) == ["crate", "pole", "pole#1"]
    without_robot = {"world": {"collision_objects": [box(frame="panda_hand")]}}
    assert mut.parse_moveit_objects(without_robot) == []  # left out, with a warning
    with pytest.raises(ValueError, match="unknown frame 'panda_hand'"):
        mut.parse_moveit_scene(without_robot, strict=True)
    world, held, allowed = mut.parse_moveit_scene(data, scene)
    assert len(world) == 3 and held == [] and allowed == [("panda_link1", "panda_link7")]


# ------------------------------------------------------------------------ property tests ----
def expected_objects(data: dict) -> dict:
    """The world objects a generated scene (world-frame names only, ADD) describes."""
    result = {}
    for entry in data["world"]["collision_objects"]:
        X_WO = read_pose(entry.get("pose"))
        for k, (primitive, pose) in enumerate(
            zip(entry["primitives"], entry["primitive_poses"], strict=True)
        ):
            kind = {1: "box", 2: "sphere", 3: "cylinder"}.get(primitive["type"], primitive["type"])
            kind, dims = str(kind).lower(), primitive["dimensions"]
            size = (dims[1], dims[0]) if kind == "cylinder" else tuple(dims)
            name = entry["id"] if k == 0 else f"{entry['id']}#{k}"
            result[name] = SceneObject(name, kind, size, X_WO @ read_pose(pose))
    return result


def read_pose(pose) -> RigidTransform:
    if pose is None:
        return RigidTransform()

    def values(v, keys):
        return [v[k] for k in keys] if isinstance(v, dict) else v

    orientation = pose.get("orientation")
    return make_pose(
        values(pose["position"], "xyz"),
        None if orientation is None else values(orientation, "xyzw"),
    )


@settings(max_examples=250, derandomize=True, deadline=None)
@given(corruption=corruptions(moveit_scenes()))
def test_corruptions_are_an_invalid_scene(shared_scene, tmp_path_factory, corruption):
    load_corrupted(mut.load_moveit_scene, shared_scene, tmp_path_factory, *corruption)


@settings(max_examples=60, derandomize=True, deadline=None)
@given(data=moveit_scenes())
def test_generated_scenes_load_as_described(shared_scene, tmp_path_factory, data):
    path = tmp_path_factory.mktemp("moveit") / "scene.yaml"
    path.write_text(yaml.safe_dump(data))
    try:
        mut.load_moveit_scene(shared_scene, path)
        assert_same_objects(shared_scene.world_objects, expected_objects(data))
        held = data["robot_state"].get("attached_collision_objects", [])
        count = len(held[0]["object"]["primitives"]) if held else 0
        assert sorted(shared_scene.attached_objects) == ["held", "held#1", "held#2"][:count]
        acm = data.get("allowed_collision_matrix")
        if acm:
            names, rows = acm["entry_names"], acm["entry_values"]
            body = shared_scene.plant.GetBodyByName
            for i, j in [(0, 3), (2, 4), (1, 2)]:
                filtered = shared_scene.checker.IsCollisionFilteredBetween(
                    body(names[i]), body(names[j])
                )
                assert (
                    filtered >= rows[i][j]
                )  # allowed pairs are filtered (others may be, by the SRDF)
    finally:
        restore(shared_scene)
