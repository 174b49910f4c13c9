"""The plan file schema: each kind of bad field is one typed error naming the field; property
tests of the file round trip and of corrupted plan dicts (any corruption is the typed error or a
valid plan, never another exception)."""

import copy
import json
import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import planning.io.plan_files as mut
from planning import ErrorCode, Plan, PlanningError
from planning.model.layout import READY_Q
from planning.timing.retime import RetimeOptions
from tests.plan_file_helpers import field_name, json_type, parent_of, walk

V_MAX = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])
A_MAX = np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])
READY = np.array(READY_Q)
SCENE = {
    "world": [
        {
            "name": "table",
            "shape": "box",
            "size": [1.2, 0.8, 0.05],
            "position": [0.5, 0.0, -0.025],
            "orientation": [0.0, 0.0, 0.0, 1.0],
        }
    ],
    "attached": [
        {
            "name": "cup",
            "shape": "cylinder",
            "size": [0.03, 0.1],
            "position": [0.0, 0.0, 0.1],
            "orientation": [0.0, 0.0, 0.0, 1.0],
        }
    ],
}
ROUND_TRIP = settings(
    max_examples=60,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)


def valid_dict() -> dict:
    """A valid plan (three waypoints, a smoothed corner) in its file form."""
    waypoints = [READY, READY + [0.3, 0.2, 0, 0, 0, 0, 0], READY + [0.5, 0.6, 0, 0, 0, 0, 0]]
    plan = Plan(waypoints, V_MAX, A_MAX, scene=SCENE, info={"planner": "test", "n": [1, 2]})
    return plan.to_dict()


BASE = valid_dict()


def expect_error(data, fragment: str) -> str:
    with pytest.raises(PlanningError) as error:
        Plan.from_dict(data)
    assert error.value.code is ErrorCode.INVALID_MOTION_PLAN
    assert fragment in error.value.message, error.value.message
    return error.value.message


def changed(edit) -> dict:
    data = copy.deepcopy(BASE)
    edit(data)
    return data


# ------------------------------------------------------------------------- examples ----
@pytest.mark.parametrize(
    "edit,fragment",
    [
        (lambda d: d["waypoints"][1].__setitem__(2, math.nan), "waypoints[1][2] must be a finite"),
        (
            lambda d: d["waypoints"][2].pop(),
            "waypoints[2] must have 7 values (robot.joints), got 6",
        ),
        (lambda d: d.pop("waypoints"), "plan: waypoints is missing"),
        (lambda d: d.__setitem__("waypoints", []), "waypoints must be a non-empty list"),
        (lambda d: d.__setitem__("colour", "red"), "colour is not a field of a plan"),
        (lambda d: d.__setitem__("velocity_scaling", "fast"), "velocity_scaling must be a number"),
        (lambda d: d.__setitem__("velocity_scaling", 2.0), "velocity_scaling must be in (0, 1]"),
        (lambda d: d.__setitem__("version", True), "version must be an integer >= 1, got True"),
        (lambda d: d["max_velocity"].__setitem__(3, -1.0), "max_velocity[3] must be in (0, inf]"),
        (lambda d: d["max_acceleration"].__setitem__(0, math.inf), "max_acceleration[0] must be"),
        (lambda d: d["finger_positions"].__setitem__(1, 500), "finger_positions[1] must be in"),
        (lambda d: d["robot"].pop("joints"), "robot.joints is missing"),
        (lambda d: d["robot"]["joints"].__setitem__(3, 4), "robot.joints[3] must be a non-empty"),
        (lambda d: d["scene"]["world"][0].__setitem__("shape", "cone"), "world[0].shape must be"),
        (lambda d: d["scene"]["attached"][0]["size"].pop(), "attached[0].size must have 2 values"),
        (lambda d: d["scene"]["world"].append(d["scene"]["world"][0]), "'table' is repeated"),
        (
            lambda d: d["scene"]["world"][0].__setitem__("orientation", [0.0] * 4),
            "world[0].orientation must be a rotation",
        ),
        (lambda d: d["info"].__setitem__("t", math.nan), "info must hold JSON values without NaN"),
        (lambda d: d["timing"].__setitem__("method", "fastest"), "timing.method must be one of"),
        (lambda d: d["timing"].__setitem__("margin", 0.5), "timing.margin must be in [0, 0.5)"),
        (lambda d: d["timing"].pop("margin"), "timing.margin is missing"),
        (lambda d: d.pop("timing"), "plan: timing is missing"),
        (lambda d: d.__setitem__("format", "other"), "format must be 'drake_sim.plan'"),
        (lambda d: d.pop("format"), "format is missing: not a plan file"),
    ],
)
def test_each_bad_field_is_named(edit, fragment):
    expect_error(changed(edit), fragment)


def test_a_plan_that_cannot_be_timed_is_the_same_error():
    data = changed(lambda d: d.__setitem__("max_velocity", [1e-320] * 7))
    expect_error(data, "the waypoints cannot be timed within the limits: Failure at")  # TOPP-RA
    data["timing"]["method"] = "rest_to_rest"
    expect_error(data, "the timing of the waypoints is not finite (duration inf s)")


@pytest.mark.parametrize(
    "content,fragment",
    [
        (b"\xff\xfe{}", "not UTF-8 text (byte 0)"),
        (b'{"format": ', "not JSON (line 1, column 12"),
        (b'{"info": {}, "info": {}}', "the key 'info' is repeated"),
        (b"[1, 2]", "a plan must be a JSON object, got [1, 2]"),
        (b"[" * 100_000, "not"),
    ],
    ids=["not_utf8", "truncated", "repeated_key", "a_list", "nested"],
)
def test_files_that_are_not_plans_are_named(tmp_path, content, fragment):
    path = tmp_path / "bad.json"
    path.write_bytes(content)
    with pytest.raises(PlanningError) as error:
        Plan.load(path)
    assert error.value.code is ErrorCode.INVALID_MOTION_PLAN
    assert error.value.message.startswith(str(path)) and fragment in error.value.message
    for missing in (tmp_path / "none.json", tmp_path):
        with pytest.raises(PlanningError, match=re.escape(str(missing))):
            Plan.load(missing)


def test_a_field_error_in_a_file_names_the_file(tmp_path):
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(changed(lambda d: d["waypoints"][0].__setitem__(6, "x"))))
    with pytest.raises(PlanningError, match=r"plan.json: waypoints\[0\]\[6\] must be a number"):
        Plan.load(path)


# ------------------------------------------------------------------ property: round trip ----
finite = st.floats(-2.5, 2.5, allow_nan=False)
json_scalars = st.none() | st.booleans() | st.integers(-100, 100) | st.text(max_size=4) | finite


@st.composite
def plans(draw) -> Plan:
    """Valid plans: 1 to 4 waypoints, limits and scaling below the Panda's, any timing."""
    waypoints = draw(st.lists(st.lists(finite, min_size=7, max_size=7), min_size=1, max_size=4))
    factors = [draw(st.floats(0.05, 1.0)) for _ in range(2)]
    timing = RetimeOptions(
        method=draw(st.sampled_from(mut.TIMING_METHODS)),
        max_corner_angle=draw(st.floats(0.0, 3.1)),
        # 0 < path_tolerance <= ~1e-16 rad blends at knots that round onto the waypoints, which
        # Timing cannot time (Plan.from_dict: the typed error); a planner uses 2 mrad.
        path_tolerance=draw(st.just(0.0) | st.floats(1e-4, 0.01)),
        margin=draw(st.floats(0.0, 0.2)),
    )
    return Plan(
        waypoints,
        factors[0] * V_MAX,
        factors[1] * A_MAX,
        velocity_scaling=factors[0],
        acceleration_scaling=factors[1],
        finger_positions=draw(st.lists(st.floats(0.0, 0.04), min_size=2, max_size=2)),
        scene=draw(st.sampled_from([SCENE, {"world": [], "attached": []}])),
        info=draw(st.dictionaries(st.text(max_size=5), json_scalars, max_size=3)),
        timing=timing,
    )


@ROUND_TRIP
@given(plan=plans())
def test_a_saved_plan_loads_back_equal(tmp_path, plan):
    plan.save(tmp_path / "plan.json")
    loaded = Plan.load(tmp_path / "plan.json")
    assert loaded == plan
    np.testing.assert_array_equal(loaded.times, plan.times)
    for t in np.linspace(0.0, plan.duration, 5):
        np.testing.assert_array_equal(loaded.sample(t)[0], plan.sample(t)[0])


# ------------------------------------------------------------- property: corrupted dicts ----
PATHS = [path for path, _ in walk(BASE) if path]
OTHER_TYPES = [None, True, "text", 7, 2.5, [], {}]
ANY_JSON = st.recursive(json_scalars, lambda kids: st.lists(kids, max_size=3), max_leaves=8)


def corrupt(data: dict, path, kind: str, value=None) -> tuple[dict, bool, str]:
    """Applies a corruption at path; returns (the dict, whether it must be refused, the field
    the message must name)."""
    data = copy.deepcopy(data)
    parent, key = parent_of(data, path)
    old = parent[key]
    in_info = len(path) > 1 and path[0] == "info"  # free-form: only NaN and infinity are wrong
    name = "info" if in_info else field_name(path)
    if kind in ("nan", "inf"):
        parent[key] = math.nan if kind == "nan" else -math.inf
        return data, True, name
    if kind == "wrong_type":
        parent[key] = value
        return data, not in_info, name
    if kind == "removed" and isinstance(key, str):
        del parent[key]
        return data, not in_info, name
    if kind == "unknown_key" and isinstance(old, dict) and path[0] != "info":
        old["colour"] = "red"
        return data, True, f"{name}.colour"
    if kind == "ragged" and isinstance(old, list) and old and not in_info:
        if len(old) > 1 and value:
            old.pop()
        else:
            old.append(copy.deepcopy(old[-1]))
        return data, not isinstance(old[0], dict | list), name  # a vector must be refused
    if kind == "scaled" and json_type(old) == "number":
        parent[key] = old * value
        return data, False, name
    parent[key] = value if kind == "any" else old
    return data, False, name


BASE_VALUES = dict(walk(BASE))
APPLICABLE = {  # the paths each corruption applies to
    "nan": PATHS,
    "inf": PATHS,
    "wrong_type": PATHS,
    "removed": [p for p in PATHS if isinstance(p[-1], str)],
    "unknown_key": [p for p in PATHS if isinstance(BASE_VALUES[p], dict)],
    "ragged": [p for p in PATHS if isinstance(BASE_VALUES[p], list) and BASE_VALUES[p]],
    "scaled": [p for p in PATHS if json_type(BASE_VALUES[p]) == "number"],
    "any": PATHS,
}


@st.composite
def corruptions(draw):
    kind = draw(st.sampled_from(list(APPLICABLE)))
    path = draw(st.sampled_from(APPLICABLE[kind]))
    old_type = json_type(BASE_VALUES[path])
    value = {
        "wrong_type": st.sampled_from([v for v in OTHER_TYPES if json_type(v) != old_type]),
        "scaled": st.sampled_from([50.0, -1.0, 0.0, 1e6, 1e-6, 1e300]),
        "any": ANY_JSON,
        "ragged": st.booleans(),
    }.get(kind, st.none())
    return path, kind, draw(value)


@settings(max_examples=400, derandomize=True, deadline=None)
@given(corruption=corruptions())
def test_any_corruption_is_the_typed_error_or_a_valid_plan(corruption):
    data, must_fail, name = corrupt(BASE, *corruption)
    event(f"{corruption[1]}, must be refused: {must_fail}")
    try:
        plan = Plan.from_dict(data)
    except PlanningError as e:
        assert e.code is ErrorCode.INVALID_MOTION_PLAN
        if must_fail:
            assert name in e.message, (corruption, e.message)
        event("refused")
        return
    assert not must_fail, corruption
    event("a valid plan")
    assert Plan.from_dict(json.loads(json.dumps(plan.to_dict()))) == plan


@settings(max_examples=100, derandomize=True, deadline=None)
@given(content=st.binary(max_size=64) | st.text(max_size=64).map(str.encode))
def test_any_bytes_are_the_typed_error_naming_the_file(tmp_path_factory, content):
    path = tmp_path_factory.mktemp("bytes") / "plan.json"
    path.write_bytes(content)
    with pytest.raises(PlanningError) as error:
        Plan.load(path)
    assert error.value.code is ErrorCode.INVALID_MOTION_PLAN
    assert error.value.message.startswith(str(path))
