"""MoveIt's message schemas and the readers of numbers, vectors, poses, primitives, colours and
operations: every value in its MoveIt forms (ROS 2's printed bytes too), and errors naming the
key path."""

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw

import planning.io.moveit_msgs as mut
from drake_sim.base.config import check_tree
from drake_sim.base.errors import ConfigError


def test_numbers():
    assert mut.number(1, "a") == 1.0 and mut.number(-0.5, "a") == -0.5
    assert mut.number("1e-3", "a") == 0.001  # PyYAML reads 1e-3 as text
    for bad, needle in [(True, "must be a number"), ("abc", "'abc'"), (math.nan, "finite")]:
        with pytest.raises(ValueError, match=needle):
            mut.number(bad, "x.y[2]")
    with pytest.raises(ValueError, match=r"^x.y\[2\] must be finite, got inf"):
        mut.number(math.inf, "x.y[2]")


def test_vectors_as_lists_or_mappings():
    assert mut.vector([1, 2, 3], "xyz", "p") == [1.0, 2.0, 3.0]
    assert mut.vector({"x": 1, "z": 3}, "xyz", "p") == [1.0, 0.0, 3.0]  # missing keys are 0
    for bad, needle in [
        ([1, 2], r"p must have 3 values \[x, y, z\]"),
        ({"x": 1, "w": 2}, "p: unknown key 'w'"),
        ({"x": None}, "p.x must be a number"),
        ([1, False, 3], r"p\[1\] must be a number"),
        ("1 2 3", "p must be a list"),
    ]:
        with pytest.raises(ValueError, match=needle):
            mut.vector(bad, "xyz", "p")


def test_poses_and_transforms():
    assert mut.pose(None, "p").IsExactlyIdentity()
    X = mut.pose({"position": [1, 2, 3], "orientation": {"z": 1, "w": 1}}, "p")
    expected = RigidTransform(RollPitchYaw(0, 0, np.pi / 2), [1, 2, 3])
    assert X.IsNearlyEqualTo(expected, 1e-12)  # the quaternion is normalised
    assert mut.pose({"position": [1, 2, 3]}, "p").IsNearlyEqualTo(RigidTransform([1, 2, 3]), 0)
    T = mut.pose({"translation": [0, 0, 1]}, "t", position="translation", orientation="rotation")
    assert T.IsNearlyEqualTo(RigidTransform([0, 0, 1]), 0)
    with pytest.raises(ValueError, match="p: a pose needs a position"):
        mut.pose({"orientation": [0, 0, 0, 1]}, "p")
    with pytest.raises(ValueError, match="zero quaternion"):
        mut.pose({"position": [0, 0, 0], "orientation": [0, 0, 0, 0]}, "p")


def test_primitives():
    assert mut.primitive({"type": 1, "dimensions": [1, 2, 3]}, "s") == ("box", (1.0, 2.0, 3.0))
    assert mut.primitive({"type": "SPHERE", "dimensions": [0.5]}, "s") == ("sphere", (0.5,))
    # A cylinder's [height, radius] becomes our (radius, length).
    assert mut.primitive({"type": 3, "dimensions": [2, 0.5]}, "s") == ("cylinder", (0.5, 2.0))
    # A cone's [height, radius] too; a prism's [height] (its polygon is read elsewhere).
    assert mut.primitive({"type": 4, "dimensions": [2, 0.5]}, "s") == ("cone", (0.5, 2.0))
    assert mut.primitive({"type": "prism", "dimensions": [0.3]}, "s") == ("prism", (0.3,))
    assert mut.primitive({"type": "b'\\x01'", "dimensions": [1, 1, 1]}, "s")[0] == "box"
    for bad, needle in [
        ({"type": 5}, r"s.dimensions: a prism needs \[height\]"),
        ({"dimensions": [1]}, "s.type: unknown primitive type 0"),
        ({"type": 9, "dimensions": [1]}, "unknown primitive type 9 .known: 1 box"),
        ({"type": True, "dimensions": [1]}, "unknown primitive type 'true'"),
        ({"type": "box", "dimensions": [1, 1]}, r"s.dimensions: a box needs \[x, y, z\]"),
        ({"type": "sphere", "dimensions": [0]}, r"s.dimensions\[0\] must be positive"),
        ({"type": "sphere", "dimensions": [True]}, r"s.dimensions\[0\] must be a number"),
    ]:
        with pytest.raises(ValueError, match=needle):
            mut.primitive(bad, "s")


def test_operations():
    for value, name in [(0, "ADD"), (1, "REMOVE"), (2, "APPEND"), (3, "MOVE"), ("move", "MOVE")]:
        assert mut.operation(value, "o") == name
    # ros2 topic echo prints a byte field as Python's bytes: b'\x00', b'\x03'.
    assert mut.operation("b'\\x00'", "o") == "ADD" and mut.operation("b'\\x03'", "o") == "MOVE"
    assert mut.byte("b'a'") == 97 and mut.byte("plain") == "plain" and mut.byte(2) == 2
    for bad in (4, -1, True, "DELETE", "b'\\x07'"):
        with pytest.raises(ValueError, match="o: unknown operation"):
            mut.operation(bad, "o")


def test_colours():
    assert mut.color({"r": 1.0, "g": 0.5, "b": 0, "a": 1}, "c") == (1.0, 0.5, 0.0, 1.0)
    assert mut.color([0.2, 0.2, 0.2, 2.0], "c") == (0.2, 0.2, 0.2, 1.0)  # clipped to [0, 1]
    assert mut.color({"r": 1}, "c") == (1.0, 0.0, 0.0, 0.0)  # missing components are 0
    with pytest.raises(ValueError, match="c: an object colour needs a color"):
        mut.color(None, "c")
    with pytest.raises(ValueError, match="c: unknown key 'x'"):
        mut.color({"x": 1}, "c")


def test_the_schema_names_unknown_keys_and_wrong_types():
    good = {
        "name": "",
        "robot_state": {"joint_state": {"name": ["panda_joint1"], "position": [0.1]}},
        "world": {"collision_objects": [{"id": "a", "primitives": [{"type": 1}]}]},
        "allowed_collision_matrix": {"entry_names": ["a"], "entry_values": [[False]]},
        "fixed_frame_transforms": [{"header": {"frame_id": "world", "stamp": {"sec": 1}}}],
    }
    check_tree(mut.PlanningScene, good, "f")
    for bad, needle in [
        ({"wrold": {}}, "unknown key 'wrold'"),
        ({"world": {"collision_objects": [{"idd": "a"}]}}, "'world.collision_objects[0].idd'"),
        ({"world": {"collision_objects": [{"operation": 1.5}]}}, "operation' must be"),
        ({"robot_state": {"is_diff": "no"}}, "'robot_state.is_diff' must be true or false"),
        ({"world": {"collision_objects": {}}}, "must be a list"),
        ({"world": {"collision_objects": [{"meshes": [{"triangels": []}]}]}}, "triangels"),
        ({"world": {"collision_objects": [{"planes": [{"coef": "0 0 1 0"}]}]}}, "must be a list"),
    ]:
        with pytest.raises(ConfigError) as info:
            check_tree(mut.PlanningScene, bad, "f")
        assert needle in str(info.value)
