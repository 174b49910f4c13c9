"""MoveIt's text ``.scene`` format: hand-written files of the old layout (shape poses in the
world) and the new one (an object pose, shape poses in it, subframes), meshes and cones as
convex hulls, planes as a box behind them, colours and subframes kept, a missing end line a
warning, loading through ``PlanningScene.load_moveit``, and errors naming the file, the line
and what was expected. Property tests: generated scenes in either layout read back; any
corruption is a ValueError or a scene."""

import logging
from pathlib import Path

import numpy as np
import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st
from pydrake.math import RigidTransform, RollPitchYaw

import planning.io.moveit_scene as mut_scene
import planning.io.moveit_text as mut
from planning import ErrorCode, PlanningError, SceneObject, make_pose
from tests.planning.io.conftest import assert_same_objects
from tests.planning.io.scene_strategies import positions, quaternions

DATA = Path(__file__).parent / "data"


def read(name: str) -> dict:
    path = DATA / name
    return {o.name: o for o in mut.parse_scene_text(path.read_text(), str(path))}


def test_old_layout():
    objects = read("old_layout.scene")
    upright = RigidTransform()
    assert_same_objects(
        objects,
        {
            "table top": SceneObject(
                "table top", "box", (1.2, 0.8, 0.04), RigidTransform([0.5, 0, -0.02])
            ),
            "bottle": SceneObject(
                "bottle", "cylinder", (0.03, 0.2), upright @ RigidTransform([0.4, 0.2, 0.1])
            ),
            "bottle#1": SceneObject(
                "bottle#1", "sphere", (0.03,), RigidTransform([0.4, 0.2, 0.23])
            ),
        },
    )


def test_new_layout_shapes_sit_in_their_objects_frame():
    objects = read("new_layout.scene")
    R = RollPitchYaw(0, 0, np.pi / 2)
    assert_same_objects(
        objects,
        {
            "shelf": SceneObject(
                "shelf", "box", (0.3, 0.02, 0.4), RigidTransform(R, [0.5, -0.3, 0.5])
            ),
            "shelf#1": SceneObject(
                "shelf#1", "box", (0.3, 0.02, 0.4), RigidTransform(R, [0.7, -0.3, 0.5])
            ),
            "ball": SceneObject("ball", "sphere", (0.05,), RigidTransform([0.2, 0.4, 0.05])),
        },
    )


def test_planning_scene_loads_scene_files(table_scene):
    table_scene.load_moveit(DATA / "new_layout.scene")
    assert sorted(table_scene.world_objects) == ["ball", "shelf", "shelf#1"]  # table replaced


def test_an_object_named_again_gets_more_shapes():
    """As MoveIt's addToObject: the second block adds its shapes to the first's."""
    text = "s\n* a\n1\nsphere 0.1\n0 0 0\n0 0 0 1\n0 0 0 0\n"
    text += "* a\n1\nbox 1 1 1\n1 1 1\n0 0 0 1\n0 0 0 0\n."
    first, second = mut.parse_scene_text(text)
    assert (first.name, first.shape, second.name, second.shape) == ("a", "sphere", "a#1", "box")
    np.testing.assert_allclose(second.X_PO.translation(), [1, 1, 1])
    assert mut.parse_scene_text("empty scene\n.\n") == []  # a name and '.': valid, empty
    assert mut.parse_scene_text("\n.\n") == []  # MoveIt's name may be empty, its line not
    assert mut.parse_scene_text("s\n* none\n0\n.") == []  # no shapes: nothing


SPHERE = "sphere\n0.1\n0 0 0\n0 0 0 1\n0 0 0 0\n"


@pytest.mark.parametrize(
    "text, needle",
    [
        ("", ": empty scene file (expected the scene name on line 1"),
        (" \n\t\n\n", ": empty scene file"),
        ("* a\n1\n" + SPHERE + ".", ":1: expected the scene name, got '* a'"),
        ("s\n* a\n1\nsphere 1\n", "shape 1: position x y z, got the end of the file"),
        ("s\nbox\n.", ":2: expected '*' (an object) or '.' (the end), got 'box'"),
        ("s\n*\n1\n" + SPHERE + ".", ":2: an object needs a name"),
        (
            "s\n* a\none\n" + SPHERE + ".",
            ":3: object 'a': the number of shapes: expected a whole number",
        ),
        ("s\n* a\n-1\n" + SPHERE + ".", "expected a whole number, got '-1'"),
        ("s\n* a\n1\nmesh\n3 1\n.", ":6: object 'a', shape 1: mesh vertex x y z: expected"),
        ("s\n* a\n1\nmesh\n3 x\n", "shape 1: mesh triangle count: expected a whole number"),
        ("s\n* a\n1\nmesh 3 1\n0 0 0 1 0 0 0 1 0\n0 1 3\n", "vertex index 3 of 3 vertices"),
        ("s\n* a\n1\ncone 1 0\n.", "cone sizes must be positive"),
        ("s\n* a\n1\nplane 0 0 0 1\n.", "a plane's normal (a, b, c) is zero"),
        ("s\n* a\n1\nblob 1\n.", "unknown shape 'blob' (box, sphere, cylinder, cone, plane"),
        (
            "s\n* a\n1\nbox 1 x 1\n.",
            ":4: object 'a', shape 1: box x y z: expected a number, got 'x'",
        ),
        ("s\n* a\n1\nbox 1 0 1\n.", "box sizes must be positive"),
        ("s\n* a\n1\nsphere nan\n.", "'nan' is not finite"),
        ("s\n* a\n1\nsphere 1\n0 0\n0 0 0 1\n", "shape 1: orientation qx qy qz qw, got the end"),
        (
            "s\n* a\n1\nsphere 1\n0 0 0\n0 0 0 0\n0 0 0 0\n.",
            ":6: object 'a', shape 1 orientation is a zero",
        ),
        (
            "s\n* a\n1\nsphere 1\n0 0 0\n0 0 0 1\n0 0 0\n.",
            "colour r g b a: expected a number, got '.'",
        ),
        (
            "s\n* a\n0 0 0\n0 0 0 1\n1\n" + SPHERE + "x\n.",
            "the number of subframes: expected a whole number",
        ),
    ],
)
def test_errors_name_the_line_and_what_was_expected(text, needle):
    with pytest.raises(ValueError) as info:
        mut.parse_scene_text(text, "my.scene")
    assert str(info.value).startswith("my.scene") and needle in str(info.value)


def test_an_empty_file_is_an_invalid_scene(table_scene, write):
    for text in ("", "\n  \n"):
        path = write(text, "empty.scene")
        with pytest.raises(PlanningError) as info:
            table_scene.load_moveit(path)
        assert info.value.code == ErrorCode.INVALID_SCENE
        assert info.value.message.startswith(f"{path}: empty scene file")
        assert list(table_scene.world_objects) == ["table"]
    table_scene.load_moveit(write("(noname)+\n.\n", "nothing.scene"))
    assert table_scene.world_objects == {}  # an explicitly empty scene replaces the table


def test_a_bad_file_is_an_invalid_scene(table_scene, write):
    path = write("s\n* a\n1\nmesh\n3 1\n.", "bad.scene")
    with pytest.raises(PlanningError) as info:
        table_scene.load_moveit(path)
    assert info.value.code == ErrorCode.INVALID_SCENE
    assert f"{path}:6" in info.value.message and "mesh" in info.value.message
    assert list(table_scene.world_objects) == ["table"]


# A tetrahedron with a vertex no triangle uses (left out of the hull), then a cone and a plane.
SHAPES = """shapes
* tetra
1
mesh
5 4
0 0 0
1 0 0
0 1 0
0 0 1
9 9 9
0 1 2
0 1 3
0 2 3
1 2 3
0.5 0 0
0 0 0 1
0.2 0.4 0.6 1
* cone
1
cone
0.1 0.4
0 0.5 0.2
0 0 0 1
0 0 0 0
* floor
1
plane
0 0 2 0.2
0 0 0
0 0 0 1
0 0 0 0
.
"""


def test_meshes_cones_and_planes():
    objects = {o.name: o for o in mut.parse_scene_text(SHAPES, "shapes.scene")}
    tetra, cone, floor = objects["tetra"], objects["cone"], objects["floor"]
    assert tetra.shape == "convex" and sorted(tetra.vertices) == [
        (0, 0, 0),
        (0, 0, 1),
        (0, 1, 0),
        (1, 0, 0),
    ]
    np.testing.assert_allclose(tetra.X_PO.translation(), [0.5, 0, 0])
    assert tetra.color == (0.2, 0.4, 0.6, 1.0) and cone.color is None  # all 0: no colour
    # The cone (radius 0.1, length 0.4 along z) is the hull of its apex and a 24-gon around
    # its base: it holds the cone and is at most 1 % wider.
    points = np.array(cone.vertices)
    assert cone.shape == "convex" and len(points) == 25
    np.testing.assert_allclose(points[:, 2].max(), 0.2)
    radii = np.hypot(points[:, 0], points[:, 1])[points[:, 2] < 0]
    assert np.all(radii >= 0.1) and np.all(radii <= 0.101)
    # The plane 2z + 0.2 = 0 (z = -0.1) is a box below it, its top face on the plane.
    assert floor.shape == "box" and floor.size == (20.0, 20.0, 10.0)
    top = floor.X_PO @ np.array([0.0, 0.0, 5.0])
    np.testing.assert_allclose(top, [0, 0, -0.1], atol=1e-12)
    np.testing.assert_allclose(floor.X_PO.rotation().col(2), [0, 0, 1], atol=1e-12)


def test_subframes_are_frames_of_the_object():
    (shelf, shelf1, ball) = mut.parse_scene_text((DATA / "new_layout.scene").read_text())
    # The shelf's object frame is at (0.6, -0.3, 0.5) turned 90 degrees about z; "top" is
    # 0.2 above it. The first shape carries the frame (given in its own frame).
    np.testing.assert_allclose(shelf.frame("top").translation(), [0.6, -0.3, 0.7], atol=1e-9)
    assert shelf1.subframes == () and ball.subframes == ()
    with pytest.raises(KeyError, match="no frame 'bottom' .its frames: top"):
        shelf.frame("bottom")


def test_a_missing_end_line_is_a_warning(caplog, table_scene, write):
    text = "s\n* a\n1\n" + SPHERE  # MoveIt reads the object, then reports a bad stream
    with caplog.at_level(logging.WARNING):
        assert [o.name for o in mut.parse_scene_text(text, "cut.scene")] == ["a"]
        assert mut.parse_scene_text(".\n", "dot.scene") == []  # the name "." and no end
    assert "cut.scene:8: no '.' line at the end" in caplog.text
    assert "dot.scene:1: '.' alone" in caplog.text
    with pytest.raises(ValueError, match="cut.scene:8: no '.' line .* .strict"):
        mut.parse_scene_text(text, "cut.scene", strict=True)
    path = write(text, "cut.scene")
    with pytest.raises(PlanningError, match="strict"):
        mut_scene.load_moveit_scene(table_scene, path, strict=True)
    assert list(table_scene.world_objects) == ["table"]  # a strict error changes nothing
    loaded = mut_scene.load_moveit_scene(table_scene, path)
    assert list(table_scene.world_objects) == ["a"] and loaded.name == "s"
    assert len(loaded.warnings) == 1 and loaded.start is None


def test_a_mesh_without_volume_or_area_is_left_out(caplog):
    text = "s\n* line\n1\nmesh 3 1\n0 0 0 1 0 0 2 0 0\n0 1 2\n0 0 0\n0 0 0 1\n0 0 0 0\n"
    text += "* ok\n1\n" + SPHERE + "."
    with caplog.at_level(logging.WARNING):
        assert [o.name for o in mut.parse_scene_text(text, "flat.scene")] == ["ok"]
    assert "flat.scene:4: object 'line', shape 1 skipped: its vertices lie on one line" in (
        caplog.text
    )


# ------------------------------------------------------------------------ property tests ----
def words(values) -> str:
    return " ".join(repr(float(v)) for v in values)


@st.composite
def text_scenes(draw) -> tuple[str, dict]:
    """A ``.scene`` text of either layout and the objects it describes."""
    newer = draw(st.booleans())
    lines, expected = ["generated"], {}
    for i in draw(st.lists(st.integers(0, 9), unique=True, max_size=4)):
        X_WO = make_pose(draw(positions), draw(quaternions)) if newer else RigidTransform()
        lines.append(f"* thing {i}")
        if newer:
            q = X_WO.rotation().ToQuaternion()
            lines += [words(X_WO.translation()), words([q.x(), q.y(), q.z(), q.w()])]
        count = draw(st.integers(1, 2))
        lines.append(str(count))
        for k in range(count):
            shape = draw(st.sampled_from(["box", "sphere", "cylinder"]))
            n = {"box": 3, "sphere": 1, "cylinder": 2}[shape]
            size = draw(st.lists(st.floats(0.01, 1.0), min_size=n, max_size=n))
            position, quaternion = draw(positions), draw(quaternions)
            lines += [shape, words(size), words(position), words(quaternion), "0.5 0.5 0.5 1"]
            name = f"thing {i}" if k == 0 else f"thing {i}#{k}"
            X = X_WO @ make_pose(position, quaternion)
            expected[name] = SceneObject(name, shape, tuple(size), X)
        if newer:
            lines += ["1", "grip", "0 0 0.1", "0 0 0 1"]
    return "\n".join([*lines, "."]) + "\n", expected


@settings(max_examples=60, derandomize=True, deadline=None)
@given(scene=text_scenes())
def test_generated_scenes_read_back(scene):
    text, expected = scene
    assert_same_objects({o.name: o for o in mut.parse_scene_text(text)}, expected)


@settings(max_examples=200, derandomize=True, deadline=None)
@given(scene=text_scenes(), data=st.data())
def test_corruptions_are_a_value_error(scene, data):
    """Any word replaced, dropped or doubled: a ValueError naming the file, or a scene."""
    tokens = scene[0].split(" ")
    at = data.draw(st.integers(0, len(tokens) - 1))
    junk = data.draw(
        st.sampled_from(["x", "-1", "nan", "*", ".", "mesh", "cone", "plane", "1e309", ""])
    )
    edits = [tokens[:at] + [junk] + tokens[at + 1 :], tokens[:at] + tokens[at + 1 :]]
    edits.append(tokens[: at + 1] + tokens[at:])
    text = " ".join(data.draw(st.sampled_from(edits)))
    try:
        mut.parse_scene_text(text, "gen.scene")
        event("read")
    except ValueError as e:
        assert str(e).startswith("gen.scene")
        event("ValueError")
