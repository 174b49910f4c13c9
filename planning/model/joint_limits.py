"""MoveIt's ``joint_limits.yaml``: per-joint limits that override the URDF's.

The file maps ``joint_limits`` (at the top, as in MoveIt 1 configs, or under
``robot_description_planning`` as in MoveIt 2 configs) to one entry per joint::

    joint_limits:
      panda_joint1:
        has_velocity_limits: true
        max_velocity: 2.175          # rad/s (m/s for a prismatic joint)
        has_acceleration_limits: true
        max_acceleration: 3.75       # rad/s^2
        has_jerk_limits: false

As in MoveIt, a limit applies only when its ``has_..._limits`` flag is true (an absent flag is
false), and then it replaces the URDF's; ``has_position_limits`` with ``min_position`` and
``max_position`` narrows the position range. Keys read nowhere here (``max_effort``, the
``default_velocity_scaling_factor`` at the top, ...) are listed on one warning line. A value of
the wrong type, a number that is not finite, a negative limit, a flag set without its value, a
zero limit that is switched on and ``min_position > max_position`` are ``ConfigError`` naming
the file and the key. Whether each joint is in the URDF is for the caller to check.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path

from drake_sim.base.config import parse_yaml, read_text
from drake_sim.base.errors import ConfigError

_log = logging.getLogger(__name__)
_LIMITS = {  # flag -> the keys it switches on
    "has_velocity_limits": ("max_velocity",),
    "has_acceleration_limits": ("max_acceleration",),
    "has_jerk_limits": ("max_jerk",),
    "has_position_limits": ("min_position", "max_position"),
}
_SIGNED = ("min_position", "max_position")  # the values that may be negative


@dataclass
class JointLimit:
    """One joint's entry. A ``max_...`` value is None when absent; it applies only when its
    ``has_..._limits`` flag is true.

    Attributes:
        has_velocity_limits, max_velocity: speed limit (rad/s or m/s).
        has_acceleration_limits, max_acceleration: acceleration limit (rad/s^2 or m/s^2).
        has_jerk_limits, max_jerk: jerk limit (rad/s^3 or m/s^3).
        has_position_limits, min_position, max_position: position range (rad or m).
    """

    has_velocity_limits: bool = False
    max_velocity: float | None = None
    has_acceleration_limits: bool = False
    max_acceleration: float | None = None
    has_jerk_limits: bool = False
    max_jerk: float | None = None
    has_position_limits: bool = False
    min_position: float | None = None
    max_position: float | None = None


def load_joint_limits(path: Path | str) -> dict[str, JointLimit]:
    """Reads a MoveIt ``joint_limits.yaml``.

    Returns:
        Joint name -> ``JointLimit``, in file order.

    Raises:
        ConfigError: naming the file and the key, for a missing or malformed file.
    """
    where = str(path)
    data = parse_yaml(read_text(path, "joint limits file"), where)
    ignored: list[str] = []
    if isinstance(data, dict) and "robot_description_planning" in data:
        ignored += [key for key in data if key != "robot_description_planning"]
        data = data["robot_description_planning"]
        prefix = "robot_description_planning."
    else:
        prefix = ""
    if not isinstance(data, dict) or not isinstance(data.get("joint_limits"), dict):
        raise ConfigError(f"{where}: no {prefix}joint_limits mapping (joint name -> limits)")
    ignored += [prefix + key for key in data if key != "joint_limits"]
    limits = {}
    for joint, entry in data["joint_limits"].items():
        key = f"{prefix}joint_limits.{joint}"
        if not isinstance(entry, dict):
            raise ConfigError(f"{where}: {key} must be a mapping of limits, got {entry!r}")
        limits[str(joint)] = _read_entry(entry, where, key, ignored)
    if ignored:
        _log.warning("%s: keys not used (ignored): %s", where, ", ".join(ignored))
    return limits


def _read_entry(entry: dict, where: str, key: str, ignored: list[str]) -> JointLimit:
    limit = JointLimit()
    for name, value in entry.items():
        at = f"{where}: {key}.{name}"
        if name in _LIMITS:
            if not isinstance(value, bool):
                raise ConfigError(f"{at} must be true or false, got {value!r}")
        elif any(name in values for values in _LIMITS.values()):
            is_number = isinstance(value, (int, float)) and not isinstance(value, bool)
            if not is_number or not math.isfinite(value):
                raise ConfigError(f"{at} must be a finite number, got {value!r}")
            if value < 0 and name not in _SIGNED:
                raise ConfigError(f"{at} is {value}, a limit cannot be negative")
            value = float(value)
        else:
            ignored.append(f"{key}.{name}")
            continue
        setattr(limit, name, value)
    for flag, names in _LIMITS.items():
        for name in names if getattr(limit, flag) else ():
            value = getattr(limit, name)
            if value is None:
                raise ConfigError(f"{where}: {key}.{flag} is true but {name} is missing")
            if value == 0 and name not in _SIGNED:
                raise ConfigError(f"{where}: {key}.{name} is 0 with {flag} true: nothing can move")
    low, high = limit.min_position, limit.max_position
    if low is not None and high is not None and low > high:
        raise ConfigError(f"{where}: {key}: min_position {low} > max_position {high}")
    return limit
