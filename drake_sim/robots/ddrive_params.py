"""The diff-drive robot's dimensions: a typed schema for ``config/ddrive.yaml`` and its checks.

The xacro (``models/ddrive/ddrive.urdf.xacro``) reads the YAML itself through
``xacro.load_yaml``; this module validates a user's file first, so a bad value is reported as
one clear ``ConfigError`` instead of a broken model or a NaN simulation, and fills optional keys
with their defaults before the xacro sees them.
"""

import dataclasses as dc
import math
from pathlib import Path

from drake_sim.base.checks import require_positive
from drake_sim.base.config import load_typed, parse_yaml, read_text
from drake_sim.base.errors import ConfigError
from drake_sim.robots.params_common import RobotParamsBase, number_fields, write_params


@dc.dataclass
class BodyParams:
    length: float = math.nan  # m, along x (towards the wheels).
    width: float = math.nan  # m, along y.
    height: float = math.nan  # m, along z.
    mass: float = math.nan  # kg.


@dc.dataclass
class WheelParams:
    radius: float = math.nan  # m.
    width: float = math.nan  # m.
    mass: float = math.nan  # kg, each wheel.
    gap: float = 0.01  # m, clearance between the body's side and the wheel.


@dc.dataclass
class CasterParams:
    radius: float = math.nan  # m, each ball caster.
    mass: float = 0.05  # kg, each caster.


@dc.dataclass
class MotorParams:
    max_torque: float = math.nan  # N m, per wheel.


@dc.dataclass
class RobotParams(RobotParamsBase):
    """Dimensions and masses of the flipping diff-drive robot (SI units)."""

    UNSCALED = ("motor",)  # ``scaled`` leaves the torque alone: the motors are the same.
    body: BodyParams = dc.field(default_factory=BodyParams)
    wheel: WheelParams = dc.field(default_factory=WheelParams)
    caster: CasterParams = dc.field(default_factory=CasterParams)
    motor: MotorParams = dc.field(default_factory=MotorParams)

    # Derived geometry, in the body frame B (origin at the body's centre, x forward, z up).
    @property
    def axle_x(self) -> float:
        """x of the wheel axle in B: half a body height behind the front face (m)."""
        return 0.5 * self.body.length - 0.5 * self.body.height

    @property
    def wheel_separation(self) -> float:
        """Distance between the two wheels' mid-planes (m)."""
        return self.body.width + 2 * self.wheel.gap + self.wheel.width

    @property
    def caster_x(self) -> float:
        """x of the casters' centres in B (m)."""
        return -0.5 * self.body.length + self.caster.radius

    @property
    def caster_z(self) -> float:
        """|z| of the casters' centres in B: the body stands level on wheels and caster (m)."""
        return self.wheel.radius - self.caster.radius

    @property
    def total_mass(self) -> float:
        """Mass of the whole robot (kg)."""
        return self.body.mass + 2 * self.wheel.mass + 2 * self.caster.mass


_REQUIRED = {
    "body": ("length", "width", "height", "mass"),
    "wheel": ("radius", "width", "mass"),
    "caster": ("radius",),
    "motor": ("max_torque",),
}


def _check_required(raw, filename: str) -> None:
    if not isinstance(raw, dict):
        raise ConfigError(f"{filename}: expected a mapping with keys {sorted(_REQUIRED)}")
    for section, keys in _REQUIRED.items():
        block = raw.get(section)
        if not isinstance(block, dict):
            raise ConfigError(f"{filename}: missing section '{section}' (keys {list(keys)})")
        for key in keys:
            if key not in block:
                raise ConfigError(f"{filename}: missing key '{section}.{key}'")
        for key, value in block.items():
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ConfigError(f"{filename}: '{section}.{key}' must be a number, got {value!r}")


def validate(params: RobotParams, filename: str = "robot") -> RobotParams:
    """Checks every value is a finite positive number and the geometry makes sense.

    Raises:
        ConfigError: naming the first bad key.
    """
    require_positive(filename, number_fields(params, filename))
    b, w, c = params.body, params.wheel, params.caster
    corner = math.hypot(b.length / 2 - params.axle_x, b.height / 2)  # axle to front corner
    if w.radius <= corner:
        raise ConfigError(
            f"{filename}: 'wheel.radius' ({w.radius}) must exceed {corner:.4g} "
            "(the body's front corners must clear the ground when it flips over the axle)"
        )
    if params.caster_z - c.radius < 0.5 * b.height:
        raise ConfigError(
            f"{filename}: 'caster.radius' ({c.radius}) is too large: the casters must fit "
            f"between the body (half-height {0.5 * b.height}) and the ground "
            f"(at most {0.5 * (w.radius - 0.5 * b.height):.4g} m)"
        )
    if 2 * c.radius > b.width or 2 * c.radius > b.length:
        raise ConfigError(f"{filename}: 'caster.radius' ({c.radius}) is larger than the body")
    return params


def load_robot_params(filename: str | Path) -> RobotParams:
    """Loads and validates a robot YAML file (see ``config/ddrive.yaml``).

    Raises:
        ConfigError: if the file is missing, malformed, has unknown or missing keys, or a value
            that is not a finite positive number or gives an impossible robot.
    """
    name = str(filename)
    text = read_text(filename, "robot file")
    _check_required(parse_yaml(text, name), name)
    return validate(load_typed(RobotParams, data=text, where=name), name)


write_robot_params = write_params
"""``write_robot_params(params, filename)``: writes ``params`` as a complete robot YAML file."""
