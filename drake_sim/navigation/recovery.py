"""Recovery behaviours of the navigator, like nav2's: clear the costmap, spin, back up.

The navigator runs them in the order of ``BEHAVIOURS`` (cycling) when the robot is stuck
(``StuckMonitor``: no valid local trajectory for ``no_valid_trajectory_timeout`` s, or less
than ``progress_distance`` m moved in ``progress_timeout`` s) or its path cannot be replanned. After
``max_recoveries`` of them for one goal without reaching it, the goal fails ("blocked").

``clear_costmap`` is instantaneous (the navigator forgets its obstacle layer and replans);
``rotate`` and ``back_up`` are driven by ``step_behaviour`` once per control cycle until they
are done, each with a time limit so that a robot that cannot move does not wait forever.
"""

import dataclasses as dc
import math

import numpy as np

from drake_sim.base.errors import ConfigError
from drake_sim.base.planar import wrap_angle
from drake_sim.navigation.costmap import LETHAL

BEHAVIOURS = ("clear_costmap", "rotate", "back_up")


@dc.dataclass
class RecoveryConfig:
    """When the navigator is stuck, and what its recovery behaviours do."""

    no_valid_trajectory_timeout: float = 1.0  # s without a valid local trajectory: stuck.
    progress_distance: float = 0.1  # m the robot must move within progress_timeout ...
    progress_timeout: float = 10.0  # s ... or it is stuck.
    rotate_angle: float = 2 * math.pi  # rad, the spin in place.
    rotate_speed: float = 1.0  # rad/s.
    backup_distance: float = 0.15  # m, backing up.
    backup_speed: float = 0.05  # m/s.
    time_margin: float = 5.0  # s a behaviour may take beyond its nominal duration.
    max_recoveries: int = 3  # behaviours per goal before it fails.


def check_recovery_config(config: RecoveryConfig, where: str = "recovery", prefix: str = ""):
    """Returns ``config`` if every value is finite and positive (``max_recoveries`` an integer
    >= 0); else raises ``ConfigError`` naming ``where`` and the key."""
    for field in dc.fields(config):
        value = getattr(config, field.name)
        name = f"{prefix}{field.name}"
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(f"{where}: '{name}' must be a number, got {value!r}")
        if field.name == "max_recoveries":
            if not (isinstance(value, int) and value >= 0):
                raise ConfigError(f"{where}: '{name}' must be an integer >= 0, got {value!r}")
        elif not (math.isfinite(value) and value > 0):
            raise ConfigError(f"{where}: '{name}' must be finite and > 0, got {value!r}")
    return config


@dc.dataclass(frozen=True)
class StuckMonitor:
    """Tells when the robot following a path is stuck: no valid local trajectory for more than
    ``no_valid_trajectory_timeout`` s, or less than ``progress_distance`` m moved in
    ``progress_timeout`` s (turning on the spot to the goal's yaw counts as progress).

    Attributes:
        xy: (x, y) m, where the robot was when progress was last seen.
        time: s, when.
        invalid_since: s, since when no trajectory was valid (None: the last one was).
    """

    xy: tuple[float, float] = (0.0, 0.0)
    time: float = 0.0
    invalid_since: float | None = None

    @staticmethod
    def start(xy, time: float) -> "StuckMonitor":
        """A monitor that has just seen progress at ``xy`` (m) at ``time`` (s)."""
        return StuckMonitor((float(xy[0]), float(xy[1])), float(time), None)

    def check(self, xy, time: float, status: str, config: RecoveryConfig):
        """Returns (the updated monitor, why the robot is stuck or "") after a control cycle
        at ``xy`` and ``time`` whose local planner reported ``status``."""
        if status == "no_valid_trajectory":
            since = time if self.invalid_since is None else self.invalid_since
            stuck = time - since > config.no_valid_trajectory_timeout
            return dc.replace(self, invalid_since=since), "no valid trajectory" if stuck else ""
        moved = math.hypot(xy[0] - self.xy[0], xy[1] - self.xy[1])
        if moved >= config.progress_distance or status == "rotating_to_goal":
            return StuckMonitor.start(xy, time), ""
        stuck = time - self.time > config.progress_timeout
        return dc.replace(self, invalid_since=None), "no progress" if stuck else ""


@dc.dataclass
class Behaviour:
    """A running recovery behaviour.

    Attributes:
        kind: one of ``BEHAVIOURS``.
        start_pose: [x, y, yaw] where it started.
        start_time: s.
        last_yaw: rad, the yaw at the previous step (for ``rotate``).
        turned: rad turned so far (for ``rotate``).
    """

    kind: str
    start_pose: np.ndarray
    start_time: float
    last_yaw: float
    turned: float = 0.0


def start_behaviour(kind: str, pose, time: float) -> Behaviour:
    """Returns the behaviour ``kind`` starting at ``pose`` ([x, y, yaw]) at ``time`` (s)."""
    if kind not in BEHAVIOURS:
        raise ValueError(f"unknown recovery behaviour {kind!r}")
    pose = np.array(pose, dtype=float)
    return Behaviour(kind, pose, float(time), float(pose[2]))


def step_behaviour(
    behaviour: Behaviour, pose, time: float, costmap, config: RecoveryConfig
) -> tuple[bool, float, float]:
    """Advances ``behaviour`` (updated in place) to ``pose`` at ``time``.

    Returns:
        (done, v, omega): whether it is over, and the command (m/s, rad/s) for this cycle.
    """
    pose = np.asarray(pose, dtype=float)
    elapsed = time - behaviour.start_time
    if behaviour.kind == "rotate":
        step = wrap_angle(pose[2] - behaviour.last_yaw)
        behaviour.turned += abs(step)
        behaviour.last_yaw = float(pose[2])
        limit = config.rotate_angle / config.rotate_speed + config.time_margin
        if behaviour.turned >= config.rotate_angle or elapsed > limit:
            return True, 0.0, 0.0
        return False, 0.0, config.rotate_speed
    if behaviour.kind == "back_up":
        moved = math.hypot(*(pose[:2] - behaviour.start_pose[:2]))
        left = config.backup_distance - moved
        limit = config.backup_distance / config.backup_speed + config.time_margin
        if left <= 0 or elapsed > limit or not _clear_behind(pose, left, costmap):
            return True, 0.0, 0.0
        return False, -config.backup_speed, 0.0
    return True, 0.0, 0.0


def _clear_behind(pose, distance: float, costmap) -> bool:
    """True if no obstacle (LETHAL) cell lies within ``distance`` plus the robot's radius
    straight behind ``pose``."""
    reach = distance + costmap.config.robot_radius
    s = np.linspace(0.0, reach, max(2, math.ceil(reach / (0.5 * costmap.resolution)) + 1))
    back = pose[:2] - np.outer(s, [math.cos(pose[2]), math.sin(pose[2])])
    return bool(np.all(costmap.cost_at(back) != LETHAL))
