"""Hypothesis strategies for the scene file tests: valid scenes in our YAML and in MoveIt's
PlanningScene YAML, and corruptions of a parsed file (a value of the wrong kind, a container
turned scalar, an unknown key, a deleted key) or of its bytes."""

import copy
import math

import yaml
from hypothesis import strategies as st

from planning.model.panda import ARM_JOINTS

WORLD_FRAMES = ("", "world", "/world", "panda_link0")  # panda_link0 is at the world origin
_ID = {"translation": [0.0, 0.0, 0.0], "rotation": [0.0, 0.0, 0.0, 1.0]}
LINKS = ("panda_link1", "panda_link3", "panda_link5", "panda_hand", "panda_leftfinger")


def _number(low: float, high: float):
    return st.floats(low, high, allow_nan=False).map(lambda x: round(x, 6))


positions = st.lists(_number(-2.0, 2.0), min_size=3, max_size=3)
# [x, y, z, w] with |w| >= 0.3: never near zero (the normalised rotations still cover all).
quaternions = st.lists(_number(-1.0, 1.0), min_size=4, max_size=4).map(
    lambda q: [*q[:3], q[3] if abs(q[3]) >= 0.3 else 0.3 + q[3]]
)
_SIZES = {"box": 3, "cylinder": 2, "sphere": 1}


@st.composite
def our_object(draw, name: str) -> dict:
    shape = draw(st.sampled_from(sorted(_SIZES)))
    size = draw(st.lists(_number(0.01, 0.5), min_size=_SIZES[shape], max_size=_SIZES[shape]))
    entry = {"name": name, "shape": shape, "size": size, "position": draw(positions)}
    if draw(st.booleans()):
        entry["orientation"] = draw(quaternions)
    return entry


@st.composite
def our_box(draw) -> dict:
    box = {"size": draw(st.lists(_number(0.01, 1.0), min_size=3, max_size=3))}
    box["position"] = draw(positions)
    box["yaw"] = draw(_number(-3.0, 3.0))
    return box


@st.composite
def our_scenes(draw) -> dict:
    """A valid scene of our YAML: some of table, object, obstacle, place; world and held objects
    of every shape, all named apart."""
    data = {key: draw(our_box()) for key in ("table", "object", "obstacle") if draw(st.booleans())}
    if draw(st.booleans()):
        data["place"] = {"position": draw(positions)}
    world = draw(st.lists(st.integers(0, 9), unique=True, max_size=4))
    held = draw(st.lists(st.integers(0, 9), unique=True, max_size=2))
    if world:
        data["objects"] = [draw(our_object(f"o{i}")) for i in world]
    if held:
        data["attached"] = [draw(our_object(f"h{i}")) for i in held]
    return data


def _xyz(values: list, keys: str, as_mapping: bool):
    return dict(zip(keys, values, strict=True)) if as_mapping else list(values)


@st.composite
def moveit_pose(draw, with_orientation: bool = True) -> dict:
    as_mapping = draw(st.booleans())
    pose = {"position": _xyz(draw(positions), "xyz", as_mapping)}
    if with_orientation and draw(st.booleans()):
        pose["orientation"] = _xyz(draw(quaternions), "xyzw", as_mapping)
    return pose


@st.composite
def moveit_primitive(draw) -> dict:
    kind = draw(st.sampled_from(["box", "sphere", "cylinder"]))
    count = {"box": 3, "sphere": 1, "cylinder": 2}[kind]
    code = {"box": 1, "sphere": 2, "cylinder": 3}[kind]
    spelled = draw(st.sampled_from([kind, kind.upper(), code]))
    dims = draw(st.lists(_number(0.01, 0.5), min_size=count, max_size=count))
    return {"type": spelled, "dimensions": dims}


@st.composite
def moveit_object(draw, name: str) -> dict:
    count = draw(st.integers(1, 3))
    entry = {
        "id": name,
        "primitives": [draw(moveit_primitive()) for _ in range(count)],
        "primitive_poses": [draw(moveit_pose()) for _ in range(count)],
    }
    if draw(st.booleans()):
        entry["header"] = {"frame_id": draw(st.sampled_from(WORLD_FRAMES))}
    if draw(st.booleans()):
        entry["pose"] = draw(moveit_pose())
    if draw(st.booleans()):
        entry["operation"] = draw(st.sampled_from([0, "ADD", "add"]))
    return entry


@st.composite
def moveit_scenes(draw) -> dict:
    """A valid PlanningScene: world objects of 1 to 3 primitives in world-frame names, and maybe
    a joint state, an object held in the hand, identity frames and an allowed collision matrix
    of Panda links."""
    names = draw(st.lists(st.integers(0, 9), unique=True, max_size=4))
    data = {"world": {"collision_objects": [draw(moveit_object(f"c{i}")) for i in names]}}
    state = data["robot_state"] = {}
    if draw(st.booleans()):
        q = draw(st.lists(_number(-0.5, 0.5), min_size=7, max_size=7))
        state["joint_state"] = {"name": list(ARM_JOINTS), "position": q}
    if draw(st.booleans()):  # what MotionBenchMaker files hold besides: all identities
        state["multi_dof_joint_state"] = {"joint_names": ["virtual_joint"], "transforms": [_ID]}
        data["fixed_frame_transforms"] = [{"child_frame_id": "world", "transform": _ID}]
        data["link_padding"] = [{"link_name": "panda_hand", "padding": 0.0}]
        data["world"]["octomap"] = {"octomap": {"data": []}}
    if draw(st.booleans()):
        held = draw(moveit_object("held"))
        held["header"] = {"frame_id": "panda_hand"}
        state["attached_collision_objects"] = [{"link_name": "panda_hand", "object": held}]
    if draw(st.booleans()):
        n = len(LINKS)
        upper = draw(st.lists(st.booleans(), min_size=n * n, max_size=n * n))
        rows = [[i != j and upper[min(i, j) * n + max(i, j)] for j in range(n)] for i in range(n)]
        data["allowed_collision_matrix"] = {"entry_names": list(LINKS), "entry_values": rows}
    return data


def _nodes(tree, path=()):
    """Every (path, value) of a parsed YAML tree, containers included (the root excluded)."""
    items = tree.items() if isinstance(tree, dict) else enumerate(tree)
    for key, value in items:
        yield (*path, key), value
        if isinstance(value, dict | list):
            yield from _nodes(value, (*path, key))


def _wrong_kind(value) -> list:
    """Values of another kind than ``value`` (all invalid where ``value`` is valid)."""
    if isinstance(value, bool):
        return [1, 1.5, "abc", None, []]
    if isinstance(value, int | float):
        return [True, "abc", None, math.nan, [], {}]
    if isinstance(value, str):
        return [True, 1.5, None, [], {}]
    return [True, 1.5, "abc"]  # a container turned scalar


def _set(tree, path, value) -> None:
    for key in path[:-1]:
        tree = tree[key]
    tree[path[-1]] = value


@st.composite
def corrupted(draw, scenes) -> tuple[dict, bool]:
    """A scene from ``scenes`` with one corruption, and whether it must be invalid: a value of
    the wrong kind or an unknown key must be; a deleted key may leave a valid scene."""
    data = copy.deepcopy(draw(scenes))
    nodes = list(_nodes(data))
    mappings = [((), data)] + [(p, v) for p, v in nodes if isinstance(v, dict)]
    kind = draw(st.sampled_from(["wrong kind", "unknown key", "deleted key"]))
    if kind == "wrong kind" and nodes:
        path, value = draw(st.sampled_from(nodes))
        _set(data, path, draw(st.sampled_from(_wrong_kind(value))))
        return data, True
    path, mapping = draw(st.sampled_from(mappings))
    if kind == "deleted key" and mapping:
        del mapping[draw(st.sampled_from(sorted(mapping)))]
        return data, False
    mapping["bogus_key"] = 1
    return data, True


@st.composite
def corrupted_bytes(draw, scenes) -> bytes:
    """The YAML of a scene from ``scenes`` with its bytes cut, overwritten or inserted."""
    text = yaml.safe_dump(draw(scenes)).encode()
    at = draw(st.integers(0, len(text)))
    junk = draw(st.binary(min_size=1, max_size=4))
    return draw(st.sampled_from([text[:at], text[:at] + junk + text[at + 1 :], junk + text]))


def corruptions(scenes):
    """(a corrupted parsed scene or corrupted YAML bytes, whether it must be invalid)."""
    return st.one_of(corrupted(scenes), corrupted_bytes(scenes).map(lambda b: (b, False)))
