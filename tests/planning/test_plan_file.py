"""Fault injection on a saved plan file: each field of the JSON corrupted in turn (NaN, out of
range, wrong type, removed, ragged, scaled limits, ...), then loaded and executed in a kinematic
station: either the load or the execution refuses it, and the robot never moves."""

import copy
import json
import math

import numpy as np
import pytest

from diagrams.pickplace_scenario import load_pickplace_scenario
from diagrams.planning_station import make_planning_station
from planning import ErrorCode, Plan, PlanningError
from tests.plan_file_helpers import field_name, json_type, parent_of, walk

# Values out of each numeric field's range, by the field's name without indices. Waypoints at
# 5.85 rad load (the file cannot know the robot) and are refused before motion.
OUT_OF_RANGE = {
    "version": [0, 4],
    "waypoints": [5.85, -5.85, 1e6],
    "max_velocity": [-1.0, 0.0],
    "max_acceleration": [-1.0, 0.0],
    "velocity_scaling": [0.0, 1.5],
    "acceleration_scaling": [0.0, 1.5],
    "finger_positions": [-0.01, 0.05],  # refused before motion: the fingers' limits
    "timing.max_corner_angle": [-0.1, 4.0],
    "timing.path_tolerance": [-0.1],
    "timing.margin": [-0.1, 0.5],
    "scene.world.size": [0.0, -0.1],
    "scene.attached.size": [0.0, -0.1],
}
OTHER_TYPE = {"number": "text", "str": 7, "list": {}, "dict": [], "True": 1.0, "None": 1.0}


@pytest.fixture(scope="module")
def station():
    return make_planning_station(load_pickplace_scenario(), mode="kinematic")


@pytest.fixture(scope="module")
def saved(station, tmp_path_factory) -> dict:
    """A valid plan from the robot's state, in its file form (read back from its file)."""
    result = station.planner.plan_to_named("extended", q_start=station.state.q)
    assert result.success, result.message
    path = tmp_path_factory.mktemp("plan") / "plan.json"
    result.trajectory.save(path)
    return json.loads(path.read_text())


def paths(saved):
    """The paths of every field, the free-form ``info`` counted as one."""
    return [p for p, _ in walk(saved) if p and (p[0] != "info" or len(p) == 1)]


def unindexed(path) -> str:
    return field_name(tuple(k for k in path if isinstance(k, str)))


def corruptions(saved: dict, kind: str):
    """Yields (label, corrupted dict) for every field that ``kind`` applies to."""
    for path in paths(saved):
        data = copy.deepcopy(saved)
        parent, key = parent_of(data, path)
        old, name = parent[key], field_name(path)
        if kind == "nan":
            parent[key] = math.nan
            yield name, data
        elif kind == "infinity":
            parent[key] = math.inf
            yield name, data
        elif kind == "wrong_type":
            parent[key] = OTHER_TYPE[json_type(old)]
            yield name, data
        elif kind == "removed" and isinstance(key, str):
            del parent[key]
            yield name, data
        elif kind == "unknown_key" and isinstance(old, dict) and path != ("info",):
            old["colour"] = "red"
            yield name, data
        elif kind == "ragged" and isinstance(old, list) and old and json_type(old[0]) != "dict":
            if isinstance(old[0], list):
                old[-1] = old[-1][:-1]  # a ragged row
            else:
                old.pop()
            yield name, data
        elif kind == "out_of_range" and json_type(old) == "number":
            for value in OUT_OF_RANGE.get(unindexed(path), []):
                parent[key] = value
                yield f"{name} = {value}", copy.deepcopy(data)


def special_cases(saved: dict):
    """Files whose every field is valid, refused before motion: limits above the robot's, a
    start away from it, joints of another robot."""
    for fields in (["max_velocity"], ["max_acceleration"], ["max_velocity", "max_acceleration"]):
        data = copy.deepcopy(saved)
        for field in fields:
            data[field] = [50.0 * v for v in data[field]]
        yield f"{' and '.join(fields)} x 50", data
    data = copy.deepcopy(saved)
    data["max_velocity"][3] *= 1.5
    yield "max_velocity[3] x 1.5", data
    for j in range(7):
        data = copy.deepcopy(saved)
        data["waypoints"][0][j] += 0.1 if j != 3 else -0.1  # joint 4's upper limit is near
        yield f"waypoints[0][{j}] + 0.1 (the start)", data
    data = copy.deepcopy(saved)
    data["robot"]["joints"][2] = "elbow"
    yield "robot.joints[2] = elbow", data


def attempt(station, tmp_path, data) -> str:
    """Writes, loads and executes a plan file; returns which refused it ("load", "execute") or
    "executed"."""
    path = tmp_path / "corrupted.json"
    path.write_text(json.dumps(data))
    try:
        plan = Plan.load(path)
    except PlanningError as e:
        assert e.code is ErrorCode.INVALID_MOTION_PLAN and e.message.startswith(str(path))
        return "load"
    try:
        station.execute(plan)
    except PlanningError as e:
        assert e.code in (ErrorCode.INVALID_MOTION_PLAN, ErrorCode.INVALID_START)
        return "execute"
    return "executed"


def run_cases(station, tmp_path, cases) -> dict:
    x0 = station.read_state()
    outcomes = {}
    for label, data in cases:
        outcomes[label] = attempt(station, tmp_path, data)
        station.advance(0.05)
        if not np.array_equal(station.read_state(), x0):
            pytest.fail(f"the robot moved after {label} ({outcomes[label]})")
    assert "executed" not in outcomes.values(), outcomes
    return outcomes


KINDS = ["nan", "infinity", "wrong_type", "removed", "unknown_key", "ragged", "out_of_range"]


@pytest.mark.parametrize("kind", KINDS)
def test_each_corrupted_field_is_refused_and_the_robot_never_moves(station, saved, kind, tmp_path):
    outcomes = run_cases(station, tmp_path, corruptions(saved, kind))
    assert len(outcomes) >= 5  # every field it applies to
    if kind == "out_of_range":  # joint limits are the robot's: checked before motion
        assert outcomes["waypoints[1][0] = 5.85"] == "execute"
        assert outcomes["max_velocity[0] = -1.0"] == "load"


def test_valid_files_beyond_the_robot_are_refused_before_motion(station, saved, tmp_path):
    outcomes = run_cases(station, tmp_path, special_cases(saved))
    assert set(outcomes.values()) == {"execute"}


def test_the_intact_file_executes(station, saved, tmp_path):
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(saved))
    result = station.execute(Plan.load(path))
    assert result.success, result.message
    np.testing.assert_allclose(station.state.q, saved["waypoints"][-1], atol=1e-6)
