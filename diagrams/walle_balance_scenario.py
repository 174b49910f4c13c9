"""Typed scenario for Wall-E balancing on a flat floor: plant, start, sensors, controller,
pushes. Values live in ``config/walle_balance.yaml``; every field's unit is in its comment."""

import dataclasses as dc
import math

from pydrake.multibody.plant import MultibodyPlantConfig
from pydrake.systems.analysis import SimulatorConfig
from pydrake.visualization import VisualizationConfig

from diagrams.world_scenario import GroundConfig
from drake_sim.base.config import load_typed, read_text
from drake_sim.base.errors import ConfigError
from drake_sim.systems.control.balance_controller import CONTROLLERS, BalanceConfig
from drake_sim.systems.control.diff_drive_controller import DiffDriveConfig
from drake_sim.systems.estimation.pitch_estimator import PitchEstimatorConfig
from drake_sim.systems.sensors.imu import ImuConfig

DRIVERS = ("balance", "diff_drive", "none")
"""What drives the wheels: the ``BalanceController`` (the robot as built, balancing); a
``DiffDriveController`` on the follow variant, which stands on support casters; or nothing
(motors off: the robot falls)."""


@dc.dataclass
class Push:
    """A constant force on the body's top (the middle of its top face) for a while."""

    time: float = 0.0  # s, when it starts.
    force: list[float] = dc.field(default_factory=lambda: [0.0, 0.0, 0.0])  # N, world frame.
    duration: float = 0.1  # s.


@dc.dataclass
class WalleStart:
    """Where the robot starts, its wheels on the floor."""

    x: float = 0.0  # m, world x of the axle's midpoint.
    y: float = 0.0  # m, world y.
    yaw: float = 0.0  # deg, heading of the body's x axis, counter-clockwise from world x.
    pitch: float = 0.0  # deg, lean about the axle, positive forward.


@dc.dataclass
class WalleBalanceScenario:
    """Wall-E on a flat floor, balancing (or driven on its casters), with pushes."""

    ground: GroundConfig = dc.field(default_factory=GroundConfig)
    start: WalleStart = dc.field(default_factory=WalleStart)
    driver: str = "balance"  # One of DRIVERS.
    imu: ImuConfig = dc.field(default_factory=ImuConfig)
    pitch_estimator: PitchEstimatorConfig = dc.field(default_factory=PitchEstimatorConfig)
    balance: BalanceConfig = dc.field(default_factory=BalanceConfig)
    drive: DiffDriveConfig = dc.field(default_factory=DiffDriveConfig)
    pushes: list[Push] = dc.field(default_factory=list)
    plant: MultibodyPlantConfig = dc.field(
        default_factory=lambda: MultibodyPlantConfig(
            time_step=2.5e-3, contact_model="point", discrete_contact_approximation="sap"
        )
    )
    simulator: SimulatorConfig = dc.field(
        default_factory=lambda: SimulatorConfig(target_realtime_rate=1.0)
    )
    visualization: VisualizationConfig = dc.field(
        default_factory=lambda: VisualizationConfig(publish_inertia=False, publish_proximity=False)
    )
    log_period: float = 0.01  # s, how often the loggers sample.
    random_seed: int = 0  # Seed of the IMU's noise.


# Values that may be zero (no noise, no integral term); every other one must be > 0.
_ZERO_OK = ("noise", "bias", "integral")


def _check_block(block, prefix: str, filename: str) -> None:
    """Checks every number of a config dataclass (recursively): finite, and > 0 unless its
    name says it may be zero (>= 0 then)."""
    for field in dc.fields(block):
        value = getattr(block, field.name)
        key = f"{prefix}.{field.name}"
        if dc.is_dataclass(value):
            _check_block(value, key, filename)
        elif isinstance(value, float | int) and not isinstance(value, bool):
            zero_ok = any(word in field.name for word in _ZERO_OK)
            if not math.isfinite(value) or value < 0 or (value == 0 and not zero_ok):
                bound = ">= 0" if zero_ok else "> 0"
                raise ConfigError(f"{filename}: '{key}' must be finite and {bound}, got {value!r}")


def check_walle_balance_scenario(scenario: WalleBalanceScenario, filename: str = "scenario"):
    """Raises ConfigError naming the first bad value of ``scenario``."""
    if scenario.driver not in DRIVERS:
        raise ConfigError(f"{filename}: 'driver' must be one of {DRIVERS}, got {scenario.driver!r}")
    if scenario.balance.controller not in CONTROLLERS:
        raise ConfigError(
            f"{filename}: 'balance.controller' must be one of {CONTROLLERS}, "
            f"got {scenario.balance.controller!r}"
        )
    for section in ("imu", "pitch_estimator", "balance", "drive"):
        _check_block(getattr(scenario, section), section, filename)
    if not abs(scenario.start.pitch) < 90:
        raise ConfigError(f"{filename}: 'start.pitch' must be between -90 and 90 degrees")
    if not scenario.plant.time_step > 0:
        raise ConfigError(f"{filename}: 'plant.time_step' must be > 0 (a discrete plant)")
    g = scenario.ground
    if not 0 <= g.mu_dynamic <= g.mu_static:
        raise ConfigError(f"{filename}: 'ground' needs 0 <= mu_dynamic <= mu_static")
    for i, push in enumerate(scenario.pushes):
        if len(push.force) != 3:
            raise ConfigError(f"{filename}: 'pushes[{i}].force' must be [x, y, z] in N")
        if push.time < 0 or push.duration <= 0:
            raise ConfigError(f"{filename}: 'pushes[{i}]' needs time >= 0 and duration > 0")
    if not scenario.log_period > 0:
        raise ConfigError(f"{filename}: 'log_period' must be > 0, got {scenario.log_period!r}")


def load_walle_balance_scenario(filename, *, defaults=None) -> WalleBalanceScenario:
    """Loads ``filename`` into a WalleBalanceScenario (unknown keys are errors; missing keys
    keep ``defaults``, the schema's own when None) and checks it.

    Raises:
        ConfigError: naming the file and the key at fault.
    """
    text = read_text(filename, "scenario file")
    scenario = load_typed(WalleBalanceScenario, data=text, defaults=defaults, where=str(filename))
    check_walle_balance_scenario(scenario, str(filename))
    return scenario
