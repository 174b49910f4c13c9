"""Typed scenario for Wall-E on a line-following course: the mode, the course, the camera, the
line detector and follower, and the robot's own sensors, controllers and pushes (a nested
``WalleBalanceScenario``). Values live in ``config/walle_scenario.yaml``; units in comments."""

import dataclasses as dc
import math
from pathlib import Path

from diagrams.walle_balance_scenario import WalleBalanceScenario, check_walle_balance_scenario
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from drake_sim.systems.control.balance_controller import CONTROLLERS
from drake_sim.systems.control.line_follower import (
    LineFollowerConfig,
    check_line_follower_config,
)
from drake_sim.systems.perception.line_detection import (
    LineDetectorConfig,
    check_line_detector_config,
)
from drake_sim.systems.sensors.camera import CameraConfig, check_camera_config

MODES = ("balance", "follow", "both")
"""``balance``: the robot balances on the course's start and holds its position (or is
driven by teleop); ``follow``: the statically stable variant (support casters, diff-drive
driver) follows the line; ``both``: the robot balances while it follows the line."""


@dc.dataclass
class WalleScenario:
    """Wall-E on a course: what it does, with which sensors and controllers."""

    mode: str = "both"  # One of MODES.
    course: str = "courses/oval.yaml"  # Course file; a relative path is from config/.
    controller: str = "lqr"  # The balance controller: one of CONTROLLERS.
    # 100 degrees: the image's bottom edge looks straight down from the camera (40 degrees
    # below horizontal on config/walle.yaml's robot), so the detector sees the line 6 cm
    # ahead of the body's centre instead of 12: much less extrapolation under the robot.
    camera: CameraConfig = dc.field(default_factory=lambda: CameraConfig(fov_y=100.0))
    # A shorter, nearer fit follows a turn's start better (config/walle_scenario.yaml).
    line_detector: LineDetectorConfig = dc.field(
        default_factory=lambda: LineDetectorConfig(fit_length=0.2, near_scale=0.15)
    )
    line_follower: LineFollowerConfig = dc.field(default_factory=LineFollowerConfig)
    # The robot's IMU, pitch estimator, balance and diff-drive controllers, pushes, plant,
    # simulator, visualisation, log period and random seed (its start and driver are set from
    # the course and the mode).
    walle: WalleBalanceScenario = dc.field(default_factory=WalleBalanceScenario)
    duration: float = 0.0  # s simulated; 0: long enough for one lap (see drake_sim.runs.walle).
    finish_margin: float = 0.2  # m: an open course is finished this far before its end.
    duration_margin: float = 5.0  # s added to 1.5 x the course's length / speed.


def course_path(scenario: WalleScenario) -> Path:
    """The scenario's course file: as given if absolute, else under ``config/``."""
    path = Path(scenario.course)
    return path if path.is_absolute() else config_dir() / path


def check_walle_scenario(scenario: WalleScenario, filename: str = "scenario") -> WalleScenario:
    """Returns ``scenario`` if valid; raises ConfigError naming the first bad value."""
    if scenario.mode not in MODES:
        raise ConfigError(f"{filename}: 'mode' must be one of {MODES}, got {scenario.mode!r}")
    if scenario.controller not in CONTROLLERS:
        raise ConfigError(
            f"{filename}: 'controller' must be one of {CONTROLLERS}, got {scenario.controller!r}"
        )
    check_camera_config(scenario.camera, f"{filename}: camera")
    check_line_detector_config(scenario.line_detector, f"{filename}: line_detector")
    check_line_follower_config(scenario.line_follower, f"{filename}: line_follower")
    check_walle_balance_scenario(scenario.walle, f"{filename}: walle")
    for key in ("duration", "finish_margin", "duration_margin"):
        value = getattr(scenario, key)
        if not (math.isfinite(value) and value >= 0):
            raise ConfigError(f"{filename}: '{key}' must be finite and >= 0, got {value!r}")
    return scenario


def default_scenario_file() -> Path:
    """Returns ``config/walle_scenario.yaml``."""
    return config_dir() / "walle_scenario.yaml"
