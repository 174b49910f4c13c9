"""The TurtleBot3 Waffle's dimensions: a typed schema for ``config/turtlebot3.yaml`` and its
checks.

The xacro (``models/turtlebot3/turtlebot3.urdf.xacro``) reads the YAML itself through
``xacro.load_yaml``; this module validates a user's file first, so a bad value is reported as
one clear ``ConfigError`` naming the key instead of a broken model, and fills optional keys with
their defaults before the xacro sees them.

Frame F is ``base_footprint``: on the floor under the midpoint of the wheel axle, x forward,
y left (along the axle), z up. Every mount position is given in F. ``base_link`` (B), the
chassis body, has F's axes and its origin on the axle, ``wheel.radius`` above F. A field whose
default is NaN is required in the YAML.
"""

import dataclasses as dc
import math
from pathlib import Path

import yaml

from drake_sim.base.config import load_checked, read_text
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from drake_sim.robots.mobile_description import MobileDescription, read_numbers
from drake_sim.robots.params_common import RobotParamsBase, check_values, write_params


@dc.dataclass
class ChassisParams:
    length: float = math.nan  # m, along x.
    width: float = math.nan  # m, along y (the deck, wider than the wheel track).
    height: float = math.nan  # m, along z, from the bottom face to the top of the deck.
    mass: float = math.nan  # kg, everything but the wheels and casters.
    offset_x: float = 0.0  # m, x of the chassis's centre in F (the axle is ahead of it).
    ground_clearance: float = 0.02  # m, from the floor to the chassis's bottom face.


@dc.dataclass
class DriveWheelParams:
    radius: float = math.nan  # m.
    width: float = math.nan  # m.
    separation: float = math.nan  # m, between the two wheels' mid-planes.
    mass: float = math.nan  # kg, each wheel.
    gap: float = 0.005  # m, clearance from each wheel to the chassis (side and top).


@dc.dataclass
class BallCasterParams:
    """Two frictionless ball casters at (x, +-y) in F, touching the floor."""

    radius: float = 0.01  # m, each ball.
    mass: float = 0.05  # kg, each.
    x: float = math.nan  # m, in F (behind the axle: negative).
    y: float = math.nan  # m, in F, the left one; the right one is at -y.


@dc.dataclass
class WheelMotorParams:
    max_torque: float = math.nan  # N m, per wheel.


@dc.dataclass
class VelocityLimits:
    """The robot's limits for a ``cmd_vel`` (the ROS turtlebot3 Waffle's by default)."""

    max_linear_velocity: float = 0.26  # m/s.
    max_angular_velocity: float = 1.82  # rad/s.
    max_linear_acceleration: float = 1.0  # m/s^2.
    max_angular_acceleration: float = 4.0  # rad/s^2.


@dc.dataclass
class MountParams:
    """A sensor frame's origin in F (m); its axes are F's."""

    x: float = math.nan
    y: float = 0.0
    z: float = math.nan


@dc.dataclass
class Turtlebot3Params(RobotParamsBase):
    """Dimensions, masses and limits of the TurtleBot3 Waffle (SI units)."""

    UNSCALED = ("motor", "limits")  # ``scaled`` leaves the torque and the limits alone.
    FILES = ("description",)
    body: ChassisParams = dc.field(default_factory=ChassisParams)
    wheel: DriveWheelParams = dc.field(default_factory=DriveWheelParams)
    caster: BallCasterParams = dc.field(default_factory=BallCasterParams)
    motor: WheelMotorParams = dc.field(default_factory=WheelMotorParams)  # One per wheel.
    limits: VelocityLimits = dc.field(default_factory=VelocityLimits)
    # Sensor mounts: imu_link, camera_rgb_frame (looking forward) and base_scan (the lidar).
    imu: MountParams = dc.field(default_factory=MountParams)
    camera: MountParams = dc.field(default_factory=MountParams)
    lidar: MountParams = dc.field(default_factory=MountParams)
    # The robot's own ROS description instead of the project's model (``mobile_description``).
    description: MobileDescription = dc.field(default_factory=MobileDescription)

    # Derived geometry. The xacro computes the same.
    @property
    def wheel_separation(self) -> float:
        """Distance between the two wheels' mid-planes (m)."""
        return self.wheel.separation

    @property
    def plate_width(self) -> float:
        """Width of the chassis's lower plate, between the wheels (m)."""
        return self.wheel.separation - self.wheel.width - 2 * self.wheel.gap

    @property
    def deck_bottom(self) -> float:
        """Height of the deck's bottom face above the floor, just over the wheels (m)."""
        return 2 * self.wheel.radius + self.wheel.gap

    @property
    def top_z(self) -> float:
        """Height of the chassis's top face above the floor (m)."""
        return self.body.ground_clearance + self.body.height

    @property
    def scan_height(self) -> float:
        """Height of the lidar's scan plane above the floor (m)."""
        return self.lidar.z

    @property
    def lidar_mount(self) -> tuple[float, float, float]:
        """p_FL: the lidar frame ``base_scan``'s origin in ``base_footprint`` (m); its axes are
        F's, so the planar pose of the sensor in the base is ``(x, y, 0)``."""
        return (self.lidar.x, self.lidar.y, self.lidar.z)

    @property
    def total_mass(self) -> float:
        """Mass of the whole robot: chassis, wheels and casters (kg)."""
        return self.body.mass + 2 * self.wheel.mass + 2 * self.caster.mass


# Fields that may be zero or negative: positions. Every other value must be > 0.
_POSITIONS = frozenset(
    ("body.offset_x", "caster.x", "imu.x", "imu.y", "camera.x", "camera.y", "lidar.x", "lidar.y")
)


def _check_on_footprint(params: Turtlebot3Params, section: str, filename: str) -> None:
    """A mount must sit over the chassis's footprint."""
    b, mount = params.body, getattr(params, section)
    for axis, low, high in (
        ("x", b.offset_x - b.length / 2, b.offset_x + b.length / 2),
        ("y", -b.width / 2, b.width / 2),
    ):
        value = getattr(mount, axis)
        if not low - 1e-9 <= value <= high + 1e-9:
            raise ConfigError(
                f"{filename}: '{section}.{axis}' ({value}) is off the chassis "
                f"(must be between {low:.4g} and {high:.4g} m)"
            )


def validate(params: Turtlebot3Params, filename: str = "robot") -> Turtlebot3Params:
    """Checks every value is a finite number (positive but for positions) and that the robot
    can be built: wheels beside the plate and under the deck, the axle over the chassis, the
    casters behind the axle under the chassis, the sensors on it and the lidar on top.

    Raises:
        ConfigError: naming the first bad key.
    """
    check_values(params, filename, _POSITIONS)
    if params.description.urdf:  # the description's own geometry: nothing here builds it
        return params
    b, w, c = params.body, params.wheel, params.caster
    if params.plate_width <= 0:
        raise ConfigError(
            f"{filename}: 'wheel.separation' ({w.separation}) leaves no room for the chassis "
            f"between the wheels (must exceed wheel.width + 2 wheel.gap = "
            f"{w.width + 2 * w.gap:.4g} m)"
        )
    if w.separation + w.width > b.width + 1e-9:
        raise ConfigError(
            f"{filename}: 'body.width' ({b.width}) must cover the wheels under the deck "
            f"(at least wheel.separation + wheel.width = {w.separation + w.width:.4g} m)"
        )
    if not b.ground_clearance < params.deck_bottom < params.top_z:
        raise ConfigError(
            f"{filename}: 'body.height' ({b.height}) must put the deck above the wheels "
            f"(the top at more than {params.deck_bottom:.4g} m above the floor), with "
            f"'body.ground_clearance' ({b.ground_clearance}) below it"
        )
    if not b.offset_x - b.length / 2 < 0 < b.offset_x + b.length / 2:
        raise ConfigError(
            f"{filename}: 'body.offset_x' ({b.offset_x}) puts the wheel axle off the chassis"
        )
    if not b.offset_x - b.length / 2 + c.radius <= c.x < 0:
        raise ConfigError(
            f"{filename}: 'caster.x' ({c.x}) must be behind the axle and under the chassis "
            f"(between {b.offset_x - b.length / 2 + c.radius:.4g} and 0 m)"
        )
    if not c.radius <= c.y <= params.plate_width / 2 - c.radius:
        raise ConfigError(
            f"{filename}: 'caster.y' ({c.y}) must put both casters under the plate "
            f"(between {c.radius:.4g} and {params.plate_width / 2 - c.radius:.4g} m)"
        )
    if 2 * c.radius > b.ground_clearance + 1e-12:
        raise ConfigError(
            f"{filename}: 'caster.radius' ({c.radius}) is too large: a ball must fit under the "
            f"chassis (at most body.ground_clearance / 2 = {b.ground_clearance / 2:.4g} m)"
        )
    for section in ("imu", "camera", "lidar"):
        _check_on_footprint(params, section, filename)
    for section in ("imu", "camera"):
        z = getattr(params, section).z
        if not b.ground_clearance <= z <= params.top_z:
            raise ConfigError(
                f"{filename}: '{section}.z' ({z}) must be inside the chassis "
                f"(between {b.ground_clearance:.4g} and {params.top_z:.4g} m)"
            )
    if params.lidar.z <= params.top_z:
        raise ConfigError(
            f"{filename}: 'lidar.z' ({params.lidar.z}) must be above the chassis's top "
            f"({params.top_z:.4g} m): the lidar sits on the deck and must see over it"
        )
    return params


def load_turtlebot3_params(filename) -> Turtlebot3Params:
    """Loads and validates a TurtleBot3 YAML file (see ``config/turtlebot3.yaml``); a
    ``ConfigError`` names the file and the key for a missing or malformed file, unknown or
    missing keys, or a value that is not a finite number, is out of range or gives an
    impossible robot.

    A file with a ``description`` section (the robot's own URDF or xacro,
    ``mobile_description``) needs nothing else: its other keys default to the shipped
    TurtleBot3's, and the wheels' radius, separation and mass and the lidar's mount are read
    from the description."""
    where = str(filename)
    try:  # only to see the section; load_checked reports a malformed file
        data = yaml.safe_load(read_text(filename, "robot file"))
    except yaml.YAMLError:
        data = None
    described = isinstance(data, dict) and isinstance(data.get("description"), dict)
    defaults = load_checked(Turtlebot3Params, _SHIPPED, validate) if described else None
    params = load_checked(
        Turtlebot3Params, filename, validate, what="robot file", defaults=defaults
    )
    if not params.description.urdf:
        return params
    description = dc.replace(params.description, source=str(Path(filename).resolve()))
    numbers = read_numbers(description)
    description.wheel_signs = list(numbers.wheel_signs)
    x, y, z = numbers.lidar_mount
    params = dc.replace(
        params,
        description=description,
        wheel=dc.replace(
            params.wheel,
            radius=numbers.wheel_radius,
            separation=numbers.wheel_separation,
            mass=numbers.wheel_mass,
        ),
        lidar=MountParams(x=x, y=y, z=z),
    )
    return validate(params, where)


_SHIPPED = config_dir() / "turtlebot3.yaml"
"""The shipped TurtleBot3's file: a described robot's defaults."""

write_turtlebot3_params = write_params
"""``write_turtlebot3_params(params, filename)``: writes ``params`` as a complete TurtleBot3 YAML
file."""
