"""The plan file schema: every field of a saved ``Plan`` checked before a plan is built from it.

``read_plan_json(filename)`` reads a file's JSON; ``check_plan_data(data, where)`` checks it
field by field (the format itself is in ``planning.plan``) and returns the values to build the
plan from. Everything wrong with a file is one typed error:
``PlanningError(ErrorCode.INVALID_MOTION_PLAN)`` whose message starts with the file name (or
"plan" for a dict) and names the field by its path, e.g.
``move.json: waypoints[3][2] must be a finite number, got nan``: a missing field, an unknown
one, a value of the wrong type, NaN or infinity, a number out of range, a list of the wrong
length (a ragged waypoint), a file that is not UTF-8 or not JSON, a repeated key.

``PlanningError`` rather than ``drake_sim.base.errors.ConfigError``: a plan that cannot be loaded
and a loaded plan that the check before motion (``planning.execution.gate``) refuses are the
same failure for a caller (nothing moves), with the same code; scene files likewise raise
``PlanningError(INVALID_SCENE)``.

The schema checks the file on its own: values a robot could never follow are out of range here
(|q| > ``MAX_JOINT_VALUE``), while the robot's own joint, velocity and acceleration limits are
checked against the robot before motion (a plan for a joint at 5.85 rad loads, and is refused).
"""

from __future__ import annotations

import json
import math
import numbers
from pathlib import Path

import numpy as np

from drake_sim.base.config import read_text
from drake_sim.base.errors import ConfigError
from planning.errors import ErrorCode, PlanningError
from planning.model.panda import FINGER_JOINTS  # a version 1 or 2 file's fingers
from planning.scene_objects import CONVEX, SHAPE_SIZES, make_pose, validate_object

FORMAT = "drake_sim.plan"
"""The value of a plan file's ``format``."""
VERSION = 3
"""The newest plan file version (1: no ``timing``, timed rest to rest; 2: the Panda's arm only,
no ``robot.group``; 3: any robot, ``robot.group`` and as many joints as it names)."""
MAX_JOINT_VALUE = 100.0
"""rad, the largest |waypoint| a file may hold: no joint turns that far (the robot's own limits
are checked before motion)."""
TIMING_METHODS = ("toppra", "rest_to_rest")
"""The values of ``timing.method`` (``planning.timing.retime.RetimeOptions``)."""

FIELDS = (
    "format",
    "version",
    "robot",
    "waypoints",
    "max_velocity",
    "max_acceleration",
    "velocity_scaling",
    "acceleration_scaling",
    "finger_positions",
    "scene",
    "info",
    "timing",
)
"""The top-level fields of a plan file, all required (``timing`` from version 2)."""
_OBJECT_FIELDS = ("name", "shape", "size", "position", "orientation", "vertices")
_ROBOT_FIELDS = ("name", "group", "joints", "fingers")
_TIMING_FIELDS = ("method", "max_corner_angle", "path_tolerance", "margin")
_VERSION_1_TIMING = {"method": "rest_to_rest"}  # version 1 files were timed rest to rest


def invalid(where: str, message: str) -> PlanningError:
    """The error of a bad plan file: ``INVALID_MOTION_PLAN``, "<where>: <message>"."""
    return PlanningError(ErrorCode.INVALID_MOTION_PLAN, f"{where}: {message}")


def read_plan_json(filename: Path | str):
    """Returns the decoded JSON of a plan file (not yet checked: see ``check_plan_data``).

    Raises:
        PlanningError: INVALID_MOTION_PLAN naming the file: missing, unreadable, not UTF-8,
            not JSON, or with a key repeated in an object.
    """
    try:
        text = read_text(filename, "plan file")
    except ConfigError as e:
        raise PlanningError(ErrorCode.INVALID_MOTION_PLAN, str(e)) from None
    try:
        return json.loads(text, object_pairs_hook=_unique_keys)
    except json.JSONDecodeError as e:
        raise invalid(
            str(filename), f"not JSON (line {e.lineno}, column {e.colno}: {e.msg})"
        ) from None
    except _RepeatedKeyError as e:
        raise invalid(str(filename), f"the key {e.args[0]!r} is repeated in an object") from None
    except RecursionError:
        raise invalid(str(filename), "not a plan: JSON nested too deeply") from None


class _RepeatedKeyError(ValueError):
    pass


def _unique_keys(pairs):
    data = {}
    for key, value in pairs:
        if key in data:
            raise _RepeatedKeyError(key)
        data[key] = value
    return data


def check_plan_data(data, where: str = "plan") -> dict:
    """Checks a plan file's decoded JSON against the schema.

    Args:
        data: the decoded JSON (``Plan.to_dict``'s form).
        where: how messages name the source: the file name, or "plan".

    Returns:
        The ``Plan`` fields: ``waypoints`` (N, 7) rad, ``max_velocity`` (7,) rad/s,
        ``max_acceleration`` (7,) rad/s^2, ``velocity_scaling``, ``acceleration_scaling``,
        ``finger_positions`` (2,) m, ``scene``, ``robot``, ``info``, and ``timing`` (the
        ``RetimeOptions`` fields; ``method: rest_to_rest`` for a version-1 file).

    Raises:
        PlanningError: INVALID_MOTION_PLAN naming the first field at fault.
    """
    return _Schema(where).plan(data)


class _Schema:
    """The checks, each raising ``invalid(where, "<field path> <problem>")``."""

    def __init__(self, where: str):
        self.where = where

    def fail(self, path: str, problem: str):
        raise invalid(self.where, f"{path} {problem}" if path else problem)

    # --------------------------------------------------------------------------- values ----
    def mapping(self, value, path: str, fields, optional=()) -> dict:
        what = path or "a plan"
        if not isinstance(value, dict):
            self.fail("", f"{what} must be a JSON object, got {_show(value)}")
        for key in value:
            if key not in fields:
                known = ", ".join(fields)
                self.fail(_join(path, key), f"is not a field of {what} (known: {known})")
        for key in fields:
            if key not in value and key not in optional:
                self.fail(_join(path, key), "is missing")
        return value

    def number(self, value, path: str, low=-math.inf, high=math.inf, *, open_ends="") -> float:
        """A finite number in [low, high]; ``open_ends`` "low" and/or "high" exclude an end."""
        if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
            self.fail(path, f"must be a number, got {_show(value)}")
        try:
            x = float(value)
        except (OverflowError, ValueError):
            x = math.nan
        if not math.isfinite(x):
            self.fail(path, f"must be a finite number, got {_show(value)}")
        below = x < low or ("low" in open_ends and x == low)
        above = x > high or ("high" in open_ends and x == high)
        if below or above:
            left = "(" if "low" in open_ends else "["
            right = ")" if "high" in open_ends else "]"
            self.fail(path, f"must be in {left}{low:g}, {high:g}{right}, got {x!r}")
        return x

    def vector(self, value, path: str, size: int, **limits) -> np.ndarray:
        if not isinstance(value, list):
            self.fail(path, f"must be a list of {size} numbers, got {_show(value)}")
        if len(value) != size:
            self.fail(path, f"must have {size} values, got {len(value)}")
        return np.array([self.number(v, f"{path}[{i}]", **limits) for i, v in enumerate(value)])

    def string(self, value, path: str, choices=None) -> str:
        if not isinstance(value, str) or not value:
            self.fail(path, f"must be a non-empty string, got {_show(value)}")
        if choices is not None and value not in choices:
            self.fail(path, f"must be one of {list(choices)}, got {value!r}")
        return value

    # --------------------------------------------------------------------------- fields ----
    def plan(self, data) -> dict:
        if isinstance(data, dict) and "format" not in data:
            self.fail("format", "is missing: not a plan file")
        if isinstance(data, dict) and not (
            isinstance(data["format"], str) and data["format"] == FORMAT
        ):
            self.fail("format", f"must be {FORMAT!r}: not a plan file, got {_show(data['format'])}")
        self.mapping(data, "", FIELDS, optional=("timing",))
        version = data["version"]
        if isinstance(version, bool) or not isinstance(version, int) or version < 1:
            self.fail("version", f"must be an integer >= 1, got {_show(version)}")
        if version > VERSION:
            self.fail("version", f"{version} is newer than this library's {VERSION}")
        if version >= 2 and "timing" not in data:
            self.fail("timing", "is missing")
        robot = self.robot(data["robot"], version)
        n, fingers = len(robot["joints"]), data["finger_positions"]
        if isinstance(fingers, list) and len(fingers) != len(robot["fingers"]):
            self.fail(
                "finger_positions",
                f"must have {len(robot['fingers'])} values (robot.fingers), got {len(fingers)}",
            )
        return {
            "robot": robot,
            "waypoints": self.waypoints(data["waypoints"], n),
            "max_velocity": self.vector(
                data["max_velocity"], "max_velocity", n, low=0.0, open_ends="low"
            ),
            "max_acceleration": self.vector(
                data["max_acceleration"], "max_acceleration", n, low=0.0, open_ends="low"
            ),
            "velocity_scaling": self.number(
                data["velocity_scaling"], "velocity_scaling", 0.0, 1.0, open_ends="low"
            ),
            "acceleration_scaling": self.number(
                data["acceleration_scaling"], "acceleration_scaling", 0.0, 1.0, open_ends="low"
            ),
            "finger_positions": self.vector(
                data["finger_positions"],
                "finger_positions",
                len(robot["fingers"]),
                low=-MAX_JOINT_VALUE,
                high=MAX_JOINT_VALUE,
            ),
            "scene": self.scene(data["scene"]),
            "info": self.info(data["info"]),
            "timing": self.timing(data["timing"]) if "timing" in data else dict(_VERSION_1_TIMING),
        }

    def robot(self, value, version: int) -> dict:
        """The robot, its group, the group's joints and the fingers' (version 3; a version 1 or
        2 file is the Panda's arm: its group recorded as "", its two fingers)."""
        optional = ("group", "fingers") if version < 3 else ()
        self.mapping(value, "robot", _ROBOT_FIELDS, optional=optional)
        self.string(value["name"], "robot.name")
        group = self.string(value["group"], "robot.group") if "group" in value else ""
        joints = self.names(value["joints"], "robot.joints", empty=False)
        fingers = self.names(value.get("fingers", list(FINGER_JOINTS)), "robot.fingers", empty=True)
        return {"name": value["name"], "group": group, "joints": joints, "fingers": fingers}

    def names(self, value, path: str, *, empty: bool) -> list[str]:
        if not isinstance(value, list) or not (value or empty):
            self.fail(
                path, f"must be a {'' if empty else 'non-empty '}list of names, got {_show(value)}"
            )
        for i, name in enumerate(value):
            self.string(name, f"{path}[{i}]")
        if len(set(value)) != len(value):
            self.fail(path, f"names a joint twice: {_show(value)}")
        return list(value)

    def waypoints(self, value, n: int) -> np.ndarray:
        """Waypoints of ``n`` values each (as many as ``robot.joints`` names)."""
        if not isinstance(value, list) or not value:
            self.fail("waypoints", f"must be a non-empty list of waypoints, got {_show(value)}")
        rows = []
        for i, q in enumerate(value):
            if isinstance(q, list) and len(q) != n:
                self.fail(f"waypoints[{i}]", f"must have {n} values (robot.joints), got {len(q)}")
            rows.append(
                self.vector(q, f"waypoints[{i}]", n, low=-MAX_JOINT_VALUE, high=MAX_JOINT_VALUE)
            )
        return np.array(rows)

    def scene(self, value) -> dict:
        self.mapping(value, "scene", ("world", "attached"))
        for part in ("world", "attached"):
            objects, names = value[part], set()
            if not isinstance(objects, list):
                self.fail(f"scene.{part}", f"must be a list of objects, got {_show(objects)}")
            for i, obj in enumerate(objects):
                path = f"scene.{part}[{i}]"
                self.scene_object(obj, path)
                if obj["name"] in names:
                    self.fail(f"{path}.name", f"{obj['name']!r} is repeated")
                names.add(obj["name"])
        return value

    def scene_object(self, obj, path: str) -> None:
        self.mapping(obj, path, _OBJECT_FIELDS, optional=("vertices",))
        name = self.string(obj["name"], f"{path}.name")
        shape = self.string(obj["shape"], f"{path}.shape", [*SHAPE_SIZES, CONVEX])
        vertices = ()
        if shape == CONVEX:
            points = obj.get("vertices")
            if not isinstance(points, list) or len(points) < 4:
                self.fail(f"{path}.vertices", f"must be 4 or more points, got {_show(points)}")
            vertices = tuple(
                tuple(self.vector(p, f"{path}.vertices[{i}]", 3)) for i, p in enumerate(points)
            )
            self.vector(obj["size"], f"{path}.size", 0)  # a convex object has no size
        else:
            self.vector(obj["size"], f"{path}.size", SHAPE_SIZES[shape], low=0.0, open_ends="low")
        self.vector(obj["position"], f"{path}.position", 3)
        self.vector(obj["orientation"], f"{path}.orientation", 4)
        try:
            with np.errstate(all="ignore"):
                X_PO = make_pose(obj["position"], obj["orientation"])
        except (ValueError, RuntimeError) as e:  # a zero (or overflowing) quaternion
            self.fail(f"{path}.orientation", f"must be a rotation [x, y, z, w]: {e}")
        try:
            validate_object(name, shape, obj["size"], X_PO, vertices)
        except ValueError as e:
            self.fail(path, f"is not a valid object: {e}")

    def info(self, value) -> dict:
        if not isinstance(value, dict):
            self.fail("info", f"must be a JSON object, got {_show(value)}")
        try:
            json.dumps(value, allow_nan=False)
        except (TypeError, ValueError) as e:
            self.fail("info", f"must hold JSON values without NaN or infinity ({e})")
        return value

    def timing(self, value) -> dict:
        self.mapping(value, "timing", _TIMING_FIELDS)
        return {
            "method": self.string(value["method"], "timing.method", TIMING_METHODS),
            "max_corner_angle": self.number(
                value["max_corner_angle"], "timing.max_corner_angle", 0.0, math.pi, open_ends="high"
            ),
            "path_tolerance": self.number(value["path_tolerance"], "timing.path_tolerance", 0.0),
            "margin": self.number(value["margin"], "timing.margin", 0.0, 0.5, open_ends="high"),
        }


def _join(path: str, key) -> str:
    return f"{path}.{key}" if path else str(key)


def _show(value, limit: int = 60) -> str:
    """A bad value's repr, shortened to ``limit`` characters."""
    text = repr(value)
    return text if len(text) <= limit else f"{text[: limit - 3]}..."
