"""Wall-E's dimensions: a typed schema for ``config/walle.yaml`` and its checks.

The xacro (``models/walle/walle.urdf.xacro``) reads the YAML itself through
``xacro.load_yaml``; this module validates a user's file first, so a bad value is reported as
one clear ``ConfigError`` naming the key instead of a broken model or a robot that cannot
balance, and fills optional keys with their defaults before the xacro sees them.

Frame B is ``base_link``: origin at the body's centre, x forward, y left (along the axle),
z up. A field whose default is NaN is required in the YAML.
"""

import dataclasses as dc
import functools
import math

from drake_sim.base.config import load_checked
from drake_sim.base.errors import ConfigError
from drake_sim.robots.ddrive_params import MotorParams, WheelParams  # The same parts.
from drake_sim.robots.params_common import RobotParamsBase, check_values, write_params

GRAVITY = 9.81  # m/s^2.

HOLD_TILT = 10.0
"""deg: the two motors together must at least hold the body's weight moment about the axle at
this lean, or no controller could bring the robot back from a small push."""


@dc.dataclass
class BodyParams:
    length: float = math.nan  # m, along x.
    width: float = math.nan  # m, along y (between the wheels).
    height: float = math.nan  # m, along z.
    mass: float = math.nan  # kg, everything but the wheels.
    ground_clearance: float = 0.03  # m, from the floor to the body's bottom face, upright.


@dc.dataclass
class ImuMountParams:
    """Where the IMU sits: p_BS, its position in B (m); its axes are B's."""

    x: float = math.nan
    y: float = 0.0
    z: float = math.nan


@dc.dataclass
class CameraMountParams:
    """Where the camera sits: the origin of ``camera_link`` in B (m), and its tilt."""

    x: float = math.nan
    y: float = 0.0
    z: float = math.nan
    pitch: float = math.nan  # deg below horizontal (a rotation about B's y axis), 0 to 90.


@dc.dataclass
class CasterParams:
    """The support casters of the "follow" variant (front and rear, under the body)."""

    radius: float = 0.012  # m, each ball.
    mass: float = 0.01  # kg, each.


@dc.dataclass
class WalleParams(RobotParamsBase):
    """Dimensions and masses of Wall-E, the self-balancing two-wheeler (SI units)."""

    UNSCALED = ("pitch", "max_torque")  # ``scaled`` leaves the camera's tilt and torque alone.
    # The tall box, and the two wheels on one axle near its bottom.
    body: BodyParams = dc.field(default_factory=BodyParams)
    wheel: WheelParams = dc.field(default_factory=WheelParams)
    motor: MotorParams = dc.field(default_factory=MotorParams)  # One per wheel.
    # The sensor mounts: the IMU on the axle, the line camera high on the front face.
    imu: ImuMountParams = dc.field(default_factory=ImuMountParams)
    camera: CameraMountParams = dc.field(default_factory=CameraMountParams)
    # Only in the follow variant (support:=true).
    caster: CasterParams = dc.field(default_factory=CasterParams)

    # Derived geometry, in B. The xacro computes the same.
    @property
    def axle_z(self) -> float:
        """z of the wheel axle in B (m, negative: below the body's centre)."""
        return -0.5 * self.body.height - self.body.ground_clearance + self.wheel.radius

    @property
    def com_height(self) -> float:
        """Height of the body's centre of mass above the axle (m)."""
        return -self.axle_z

    @property
    def top_z(self) -> float:
        """z of the body's top face in B (m): where a push lands."""
        return 0.5 * self.body.height

    @property
    def wheel_separation(self) -> float:
        """Distance between the two wheels' mid-planes (m)."""
        return self.body.width + 2 * self.wheel.gap + self.wheel.width

    @property
    def caster_x(self) -> float:
        """|x| of the support casters' centres in B (m)."""
        return 0.5 * self.body.length - self.caster.radius

    @property
    def caster_z(self) -> float:
        """z of the support casters' centres in B: they touch the floor when upright (m)."""
        return -0.5 * self.body.height - self.body.ground_clearance + self.caster.radius

    @property
    def total_mass(self) -> float:
        """Mass of the balancing robot, body and both wheels (kg); the follow variant's casters
        add ``2 * caster.mass``."""
        return self.body.mass + 2 * self.wheel.mass


# Fields that may be zero or negative: positions. Every other value must be > 0.
_POSITIONS = frozenset(("imu.x", "imu.y", "imu.z", "camera.x", "camera.y", "camera.z"))


def _check_inside_body(params: WalleParams, section: str, what: str, filename: str) -> None:
    b = params.body
    mount = getattr(params, section)
    for axis, half in (("x", b.length / 2), ("y", b.width / 2), ("z", b.height / 2)):
        value = getattr(mount, axis)
        if abs(value) > half * (1 + 1e-9):
            raise ConfigError(
                f"{filename}: '{section}.{axis}' ({value}) puts the {what} off the body "
                f"(|{axis}| must be at most {half:.4g} m)"
            )


def validate(params: WalleParams, filename: str = "robot") -> WalleParams:
    """Checks every value is a finite number (positive but for positions) and that the robot
    can be built and balanced.

    Raises:
        ConfigError: naming the first bad key.
    """
    check_values(params, filename, _POSITIONS)
    b, w, c = params.body, params.wheel, params.caster
    if w.radius <= b.ground_clearance:
        raise ConfigError(
            f"{filename}: 'wheel.radius' ({w.radius}) must exceed 'body.ground_clearance' "
            f"({b.ground_clearance}): the axle is mounted on the body's sides"
        )
    if params.com_height <= 0:
        raise ConfigError(
            f"{filename}: 'wheel.radius' ({w.radius}) puts the axle above the body's centre: "
            f"it must be below {b.height / 2 + b.ground_clearance:.4g} m for a robot that "
            "balances over its axle"
        )
    _check_inside_body(params, "imu", "IMU", filename)
    _check_inside_body(params, "camera", "camera", filename)
    if not 0 < params.camera.pitch < 90:
        raise ConfigError(
            f"{filename}: 'camera.pitch' ({params.camera.pitch}) must be between 0 and 90 "
            "degrees below horizontal: the camera looks at the floor ahead"
        )
    if 2 * c.radius > b.ground_clearance or 2 * c.radius > b.length / 2:
        raise ConfigError(
            f"{filename}: 'caster.radius' ({c.radius}) is too large: a caster must fit under "
            f"the body (at most {min(b.ground_clearance, b.length / 2) / 2:.4g} m)"
        )
    hold = b.mass * GRAVITY * params.com_height * math.sin(math.radians(HOLD_TILT))
    if 2 * params.motor.max_torque < hold:
        raise ConfigError(
            f"{filename}: 'motor.max_torque' ({params.motor.max_torque}) is too weak: the two "
            f"motors must hold the body's weight moment at {HOLD_TILT:g} degrees of lean "
            f"({hold:.3g} N m), so at least {hold / 2:.3g} N m each"
        )
    return params


load_walle_params = functools.partial(load_checked, WalleParams, check=validate, what="robot file")
"""``load_walle_params(filename)``: loads and validates a Wall-E YAML file (see
``config/walle.yaml``); a ``ConfigError`` names the file and the key for a missing or malformed
file, unknown or missing keys, or a value that is not a finite number, is out of range or gives
an impossible robot."""

write_walle_params = write_params
"""``write_walle_params(params, filename)``: writes ``params`` as a complete Wall-E YAML
file."""
