"""Scene objects: validation naming the object and field, Drake shapes, poses from positions and
quaternions, free-body positions, and the JSON description of a scene."""

import dataclasses as dc
import json
from types import SimpleNamespace

import numpy as np
import pytest
from pydrake.geometry import Box, Convex, Cylinder, Sphere
from pydrake.math import RigidTransform, RollPitchYaw

import planning.scene_objects as mut

X = RigidTransform(RollPitchYaw(0.1, 0.2, 0.3), [0.4, -0.5, 0.6])


def test_shapes_and_sizes():
    box = mut.SceneObject("crate", "box", [0.1, 0.2, 0.3], X)
    assert box.size == (0.1, 0.2, 0.3) and all(type(s) is float for s in box.size)
    shape = box.drake_shape()
    assert isinstance(shape, Box) and (shape.width(), shape.depth(), shape.height()) == box.size
    can = mut.SceneObject("can", "cylinder", (0.03, 0.12), X).drake_shape()
    assert isinstance(can, Cylinder) and (can.radius(), can.length()) == (0.03, 0.12)
    ball = mut.SceneObject("ball", "sphere", (np.float32(0.05),), X)
    assert isinstance(ball.drake_shape(), Sphere)
    assert ball.drake_shape().radius() == pytest.approx(0.05)
    assert mut.SHAPE_SIZES == {"box": 3, "cylinder": 2, "sphere": 1}


def test_objects_are_frozen_and_move_by_copy():
    dut = mut.SceneObject("crate", "box", (0.1, 0.2, 0.3), X)
    with pytest.raises(dc.FrozenInstanceError):
        dut.name = "other"
    moved = dut.with_pose(RigidTransform([1.0, 0.0, 0.0]))
    assert (moved.name, moved.shape, moved.size) == (dut.name, dut.shape, dut.size)
    np.testing.assert_array_equal(moved.X_PO.translation(), [1.0, 0.0, 0.0])
    assert dut.X_PO.IsExactlyEqualTo(X)


@pytest.mark.parametrize(
    "name, shape, size, pose, needles",
    [
        ("", "box", (1, 1, 1), X, ["name", "''"]),
        (7, "box", (1, 1, 1), X, ["name", "7"]),
        ("c", "cone", (1, 1), X, ["'c'", "cone", "box", "convex"]),
        ("b", "box", (1, 1), X, ["'b'", "3 size values", "sx, sy, sz", "got 2"]),
        ("s", "sphere", (1, 1), X, ["'s'", "1 size values", "radius"]),
        ("y", "cylinder", (1,), X, ["'y'", "radius, length"]),
        ("n", "box", (1, "wide", 1), X, ["'n'", "numbers"]),
        ("z", "sphere", (0.0,), X, ["'z'", "positive"]),
        ("i", "sphere", (np.inf,), X, ["'i'", "finite"]),
        ("p", "sphere", (1,), np.eye(4), ["'p'", "RigidTransform"]),
    ],
)
def test_bad_objects_name_the_object_and_field(name, shape, size, pose, needles):
    with pytest.raises(ValueError) as info:
        mut.SceneObject(name, shape, size, pose)
    for needle in needles:
        assert needle in str(info.value)


def test_non_finite_pose_is_rejected():
    bad = RigidTransform([0.0, np.nan, 0.0])
    with pytest.raises(ValueError, match="'ghost': pose is not finite"):
        mut.validate_object("ghost", "box", (1, 1, 1), bad)
    mut.validate_object("fine", "box", (1, 1, 1), X)  # no error


def test_make_pose_normalises_the_quaternion():
    dut = mut.make_pose([1, 2, 3])
    assert dut.IsExactlyEqualTo(RigidTransform([1.0, 2.0, 3.0]))
    half_turn = mut.make_pose([0, 0, 0], [0, 0, 2.0, 0])  # [x, y, z, w], not unit
    np.testing.assert_allclose(
        half_turn.rotation().matrix(), np.diag([-1.0, -1.0, 1.0]), atol=1e-12
    )
    q = X.rotation().ToQuaternion()
    again = mut.make_pose(X.translation(), [3 * q.x(), 3 * q.y(), 3 * q.z(), 3 * q.w()])
    assert again.IsNearlyEqualTo(X, 1e-12)


@pytest.mark.parametrize(
    "position, quaternion, needles",
    [
        ([0, 0], None, ["shelf position", "3 values"]),
        ([0, 0, "x"], None, ["shelf position", "3 numbers"]),
        ([0, np.inf, 0], None, ["shelf position", "finite"]),
        ([0, 0, 0], [0, 0, 1], ["shelf orientation [x, y, z, w]", "4 values"]),
        ([0, 0, 0], [0, 0, np.nan, 1], ["shelf orientation", "finite"]),
        ([0, 0, 0], [0, 0, 0, 0], ["shelf orientation", "zero"]),
    ],
)
def test_make_pose_rejects_bad_values_naming_them(position, quaternion, needles):
    with pytest.raises(ValueError) as info:
        mut.make_pose(position, quaternion, name="shelf")
    for needle in needles:
        assert needle in str(info.value)


def test_free_body_positions_round_trip():
    q = mut.free_body_positions(X)
    assert q.shape == (7,)
    np.testing.assert_allclose(q[4:], X.translation())
    np.testing.assert_allclose(q[:4], X.rotation().ToQuaternion().wxyz())
    assert mut.free_body_pose(q).IsNearlyEqualTo(X, 1e-12)
    scaled = np.concatenate([2.5 * q[:4], q[4:]])  # the quaternion is normalised
    assert mut.free_body_pose(scaled).IsNearlyEqualTo(X, 1e-12)


def test_describe_scene_lists_world_and_held_objects():
    crate = mut.SceneObject("crate", "box", (0.1, 0.2, 0.3), X)
    held = mut.SceneObject("held", "sphere", (0.02,), RigidTransform([0, 0, 0.1]))
    scene = SimpleNamespace(world_objects={"crate": crate}, attached_objects={"held": held})
    dut = mut.describe_scene(scene)
    assert json.loads(json.dumps(dut)) == dut  # JSON-ready
    (entry,) = dut["world"]
    assert entry["name"] == "crate" and entry["shape"] == "box" and entry["size"] == [0.1, 0.2, 0.3]
    x, y, z, w = entry["orientation"]
    assert mut.make_pose(entry["position"], [x, y, z, w]).IsNearlyEqualTo(X, 1e-12)
    assert dut["attached"] == [
        {
            "name": "held",
            "shape": "sphere",
            "size": [0.02],
            "position": [0.0, 0.0, 0.1],
            "orientation": [0.0, 0.0, 0.0, 1.0],
        }
    ]
    assert mut.describe_scene(SimpleNamespace(world_objects={}, attached_objects={})) == {
        "world": [],
        "attached": [],
    }


CORNERS = [(x, y, z) for x in (0.0, 0.1) for y in (0.0, 0.2) for z in (0.0, 0.3)]


def test_convex_objects_are_the_hull_of_their_vertices():
    dut = mut.SceneObject("mesh", "convex", (), X, vertices=[list(p) for p in CORNERS])
    assert dut.vertices == tuple(CORNERS) and dut.size == ()
    shape = dut.drake_shape()
    assert isinstance(shape, Convex)
    hull = shape.GetConvexHull()
    assert hull.num_vertices() == 8
    vertices = [hull.vertex(i) for i in range(hull.num_vertices())]
    points = sorted(tuple(round(float(c), 12) for c in v) for v in vertices)
    assert points == sorted(CORNERS)
    flat = mut.SceneObject("flat", "convex", (), X, vertices=[(0, 0, 0), (1, 0, 0), (0, 1, 0)] * 2)
    assert isinstance(flat.drake_shape(), Convex)  # a polygon is a hull too


@pytest.mark.parametrize(
    "size, vertices, needle",
    [
        ((), [(0, 0, 0)] * 3, "at least 4 vertices"),
        ((), [(0, 0)] * 4, "at least 4 vertices"),
        ((), [(0, 0, 0), (1, 0, 0), (2, 0, 0), (3, 0, 0)], "lie on one line"),
        ((), [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, np.nan)], "not finite"),
        ((), [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, "x")], "vertices must be"),
        ((1.0,), CORNERS, "a convex object has no size"),
    ],
)
def test_bad_convex_objects_name_the_object(size, vertices, needle):
    with pytest.raises(ValueError, match=f"'hull'.*{needle}"):
        mut.SceneObject("hull", "convex", size, X, vertices=vertices)
    with pytest.raises(ValueError, match="only a convex object has vertices"):
        mut.SceneObject("box", "box", (1, 1, 1), X, vertices=CORNERS)


def test_colours_and_subframes_travel_with_the_object():
    tip = RigidTransform([0.0, 0.0, 0.1])
    dut = mut.SceneObject("crate", "box", (0.1, 0.1, 0.1), X, color=[1, 0.5, 0, 1])
    dut = dc.replace(dut, subframes=[("tip", tip)])
    assert dut.color == (1.0, 0.5, 0.0, 1.0) and dut.subframes[0][0] == "tip"
    moved = dut.with_pose(RigidTransform([1.0, 0.0, 0.0]))
    assert (moved.color, moved.subframes) == (dut.color, dut.subframes)
    np.testing.assert_allclose(moved.frame("tip").translation(), [1.0, 0.0, 0.1])
    assert dut.frame("tip").IsNearlyEqualTo(X @ tip, 1e-12)
    with pytest.raises(KeyError, match="'crate' has no frame 'top' .its frames: tip"):
        dut.frame("top")
    for color in ([1, 0, 0], [2, 0, 0, 1], ["red", 0, 0, 1]):
        with pytest.raises(ValueError, match="'c': color must be"):
            mut.SceneObject("c", "sphere", (1,), X, color=color)
    with pytest.raises(ValueError, match="subframe names must be unique"):
        mut.SceneObject("s", "sphere", (1,), X, subframes=[("a", tip), ("a", tip)])
    with pytest.raises(ValueError, match="'s/a': pose must be a RigidTransform"):
        mut.SceneObject("s", "sphere", (1,), X, subframes=[("a", np.eye(4))])


def test_subframe_pose_of_world_and_held_objects():
    tip = RigidTransform([0.0, 0.0, 0.1])
    crate = mut.SceneObject("crate", "box", (0.1,) * 3, X, subframes=(("tip", tip),))
    held = mut.SceneObject("held", "sphere", (0.02,), RigidTransform([0, 0, 0.1]))
    held = dc.replace(held, subframes=(("tip", tip),))
    X_WA = RigidTransform([1.0, 2.0, 3.0])

    def object_pose(name, q=None):
        return crate.X_PO if name == "crate" else X_WA @ held.X_PO

    scene = SimpleNamespace(
        world_objects={"crate": crate}, attached_objects={"held": held}, object_pose=object_pose
    )
    assert mut.subframe_pose(scene, "crate/tip").IsNearlyEqualTo(X @ tip, 1e-12)
    assert mut.subframe_pose(scene, "crate").IsNearlyEqualTo(X, 1e-12)
    np.testing.assert_allclose(mut.subframe_pose(scene, "held/tip", q=0).translation(), [1, 2, 3.2])


def test_describe_scene_holds_a_convex_objects_vertices():
    hull = mut.SceneObject("hull", "convex", (), X, vertices=CORNERS)
    scene = SimpleNamespace(world_objects={"hull": hull}, attached_objects={})
    (entry,) = mut.describe_scene(scene)["world"]
    assert entry["shape"] == "convex" and entry["size"] == []
    assert entry["vertices"] == [list(p) for p in CORNERS]
