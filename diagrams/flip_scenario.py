"""Typed scenario for ``python -m drake_sim.flip``: the world plus sensors and controllers."""

import dataclasses as dc
import math

from diagrams.world_scenario import WorldScenario, check_world_scenario, load_scenario
from drake_sim.base.checks import fields_of, require_positive
from drake_sim.base.errors import ConfigError
from drake_sim.systems.control.diff_drive_controller import DiffDriveConfig
from drake_sim.systems.control.flip_controller import FlipConfig
from drake_sim.systems.estimation.odometry import OdometryConfig
from drake_sim.systems.sensors.imu import ImuConfig
from drake_sim.systems.viewer.teleop import TeleopConfig


@dc.dataclass
class FlipScenario:
    """The flipping robot in its world. Values live in ``config/flip.yaml``."""

    scene: WorldScenario = dc.field(default_factory=WorldScenario)
    imu: ImuConfig = dc.field(default_factory=ImuConfig)
    odometry: OdometryConfig = dc.field(default_factory=OdometryConfig)
    flip: FlipConfig = dc.field(default_factory=FlipConfig)
    drive: DiffDriveConfig = dc.field(default_factory=DiffDriveConfig)
    teleop: TeleopConfig = dc.field(default_factory=TeleopConfig)
    log_period: float = 0.02  # s, how often the run's report samples the robot.
    trail_period: float = 0.1  # s, how often the Meshcat trails grow.


def check_flip_scenario(scenario: FlipScenario, filename: str = "scenario") -> None:
    """Raises ConfigError naming the first non-finite or non-positive value that must be > 0."""
    check_world_scenario(scenario.scene, filename)
    for section in ("imu", "odometry", "flip", "drive", "teleop"):
        block = getattr(scenario, section)
        for field in dc.fields(block):
            value = getattr(block, field.name)
            key = f"{section}.{field.name}"
            if not math.isfinite(value):
                raise ConfigError(f"{filename}: '{key}' must be finite, got {value!r}")
            # Rates, times and limits must be positive; noise levels may be zero.
            zero_ok = "noise" in field.name or "bias" in field.name or "variance" in field.name
            zero_ok = zero_ok or field.name == "integral_time"
            if value < 0 or (value == 0 and not zero_ok):
                raise ConfigError(f"{filename}: '{key}' must be > 0, got {value!r}")
    require_positive(filename, fields_of(scenario, ("log_period", "trail_period")))


def load_flip_scenario(filename) -> FlipScenario:
    """Loads ``filename`` into a FlipScenario (unknown keys are errors) and checks it."""
    scenario = load_scenario(filename, FlipScenario, check=False)
    check_flip_scenario(scenario, str(filename))
    return scenario
