"""A 2D scanning lidar (a laser scanner) on a body: a LeafSystem that outputs ``LaserScan``s.

How the beams are cast, and why: pydrake has no ray-cast query, so there were two options,
both measured by ``benchmarks/lidar_benchmark.py`` on an arena-like scene (a 6 m x 5 m walled
room, 30 rotated boxes, 8 cylinders and a concave mesh of 4 096 triangles, all crossing the
scan plane) from four poses, against an exact 2D reference, on this project's 2-core VM:

* Depth renders (four ``RenderEngineVtk`` depth cameras of 90 degrees, 360 x 3 pixels each,
  each beam read from its nearest column): 3.8 to 4.4 ms per 360-beam scan, errors up to
  140 mm at silhouette edges (99th percentile 12 mm), and it sees the *visual* geometry,
  not the geometry the robot collides with.
* Geometric ray casting (``ray_casting``): 0.55 ms per scan (0.6 ms with the noise and the
  ``LaserScan``), within 2e-9 m of the exact ranges; its cost grows with the geometry that
  crosses the scan plane near the lidar, not with the scene.

So the lidar casts rays (``drake_sim.systems.sensors.scene_shapes``): it sees every proximity
geometry in the scene that crosses its scan plane within ``range_max`` (boxes, cylinders,
spheres, capsules, ellipsoids, the ground half-space when it tilts, and meshes from their OBJ
file, concavities included), except the geometry of the ``ignore``d model instances (its own
robot). The scan plane is the xy plane of the lidar frame L; beam i points along
``angle_min + i * angle_increment`` from L's x axis towards its y axis. The robot's tilt
tilts the plane.

The measured range is the exact range plus Gaussian noise (``noise_sigma``), rounded to
``resolution`` when it is positive; a measured range outside [``range_min``, ``range_max``]
(no return, too far, too near, as an LDS reports an invalid reading) is ``inf``. The noise is
seeded by ``seed`` and the scan's index, so a run is reproducible whatever else evaluates it.
"""

import dataclasses as dc
import math
from collections.abc import Sequence
from pathlib import Path
from typing import ClassVar

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import QueryObject, SceneGraph
from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import Frame, ModelInstanceIndex
from pydrake.systems.framework import DiagramBuilder, EventStatus, LeafSystem

from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from drake_sim.base.presets import preset_file
from drake_sim.systems.sensors.ray_casting import Fan
from drake_sim.systems.sensors.scene_shapes import SceneRayCaster


@dc.dataclass
class LidarConfig:
    """A planar laser scanner: beams, field of view, range limits, noise and scan rate.

    Presets (``PRESETS``): ``config/lidars/<name>.yaml``, named in a scenario (``lidar: lds_01``,
    ``--set lidar=sick_tim571``) or read by ``lidar_config``. The defaults are the TurtleBot3's
    LDS-01, ``config/lidars/lds_01.yaml`` (``test_lidar`` holds them equal).
    """

    PRESETS: ClassVar[str] = "lidars"

    samples: int = 360  # beams per scan.
    fov_deg: float = 360.0  # degrees, field of view, in (0, 360].
    angle_min_deg: float | None = None  # degrees, first beam from L's x axis (None: -fov/2).
    range_min: float = 0.12  # m, nearer readings are invalid (inf).
    range_max: float = 3.5  # m, farther readings (and no return) are inf.
    resolution: float = 0.0  # m, ranges are rounded to multiples of this (0: not rounded).
    noise_sigma: float = 0.01  # m, standard deviation of the Gaussian range noise.
    rate: float = 5.0  # Hz, scans a second.

    def angle_min(self) -> float:
        """Returns the first beam's angle (rad)."""
        first = -0.5 * self.fov_deg if self.angle_min_deg is None else self.angle_min_deg
        return math.radians(first)

    def angle_increment(self) -> float:
        """Returns the angle between beams (rad): a full circle is split into ``samples``
        equal steps (the last beam one step before the first); a smaller field of view has
        beams at both of its ends."""
        if self.samples < 2:
            return 0.0
        steps = self.samples if self.fov_deg >= 360.0 else self.samples - 1
        return math.radians(self.fov_deg) / steps

    def fan(self) -> Fan:
        """Returns the beams' directions."""
        return Fan(self.angle_min(), self.angle_increment(), self.samples)


def check_lidar_config(config: LidarConfig, where: str = "lidar") -> LidarConfig:
    """Returns ``config`` if its values make a lidar; raises ``ConfigError`` naming the key."""
    for key in dc.fields(LidarConfig):
        value = getattr(config, key.name)
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"{where}: '{key.name}' must be finite, got {value!r}")
    if config.samples < 1:
        raise ConfigError(f"{where}: 'samples' must be at least 1, got {config.samples}")
    if not 0.0 < config.fov_deg <= 360.0:
        raise ConfigError(f"{where}: 'fov_deg' must be in (0, 360] degrees, got {config.fov_deg}")
    if config.range_min < 0.0:
        raise ConfigError(f"{where}: 'range_min' must not be negative, got {config.range_min}")
    if not config.range_min < config.range_max:
        raise ConfigError(
            f"{where}: 'range_min' ({config.range_min}) must be less than 'range_max' "
            f"({config.range_max})"
        )
    if config.resolution < 0.0:
        raise ConfigError(f"{where}: 'resolution' must not be negative, got {config.resolution}")
    if config.noise_sigma < 0.0:
        raise ConfigError(f"{where}: 'noise_sigma' must not be negative, got {config.noise_sigma}")
    if not config.rate > 0.0:
        raise ConfigError(f"{where}: 'rate' must be positive, got {config.rate}")
    return config


def load_lidar_config(path: Path | str) -> LidarConfig:
    """Loads and checks a lidar YAML file (keys of ``LidarConfig``); raises ``ConfigError``."""
    return check_lidar_config(load_typed(LidarConfig, filename=path), where=str(path))


def lidar_config(name_or_path: str | Path, where: str = "lidar") -> LidarConfig:
    """The checked lidar of a preset's name (``lds_01``, the TurtleBot3's; ``sick_tim571``) or
    of a YAML file (a ``Path``, or text with a ``/`` or a ``.yaml`` ending): ``--lidar NAME|FILE``.

    Raises:
        ConfigError: an unknown name (naming the known ones), no such file, or a bad file.
    """
    path = preset_file(LidarConfig, name_or_path, where)
    return check_lidar_config(load_typed(LidarConfig, filename=path), where=str(path))


def lidar_preset_file(name: str = "lds_01") -> Path:
    """Returns ``config/lidars/<name>.yaml``: ``lds_01`` (TurtleBot3) or ``sick_tim571``.

    Raises:
        ConfigError: no such preset.
    """
    return preset_file(LidarConfig, name, "lidar preset")


@dc.dataclass(frozen=True, eq=False)
class LaserScan:
    """One scan, like ROS's sensor_msgs/LaserScan: ranges (m) of beams in the lidar frame's xy
    plane, ``inf`` for no valid return. The arrays are read-only."""

    time: float  # s, simulated time of the scan (nan: no scan yet).
    angle_min: float  # rad, the first beam's angle from the lidar frame's x axis.
    angle_increment: float  # rad, between beams (counter-clockwise).
    range_min: float  # m.
    range_max: float  # m.
    ranges: np.ndarray  # (n,) m, inf where there was no valid return.

    def __post_init__(self):
        ranges = np.array(self.ranges, dtype=float)
        ranges.setflags(write=False)
        object.__setattr__(self, "ranges", ranges)

    def __deepcopy__(self, memo):
        return self  # immutable: Drake's state copies can share it

    def angles(self) -> np.ndarray:
        """Returns the beams' angles (rad), one per range."""
        return self.angle_min + self.angle_increment * np.arange(len(self.ranges))

    def points(self) -> np.ndarray:
        """Returns the (m, 2) points (m) of the finite ranges in the lidar frame's xy plane."""
        valid = np.isfinite(self.ranges)
        r, a = self.ranges[valid], self.angles()[valid]
        return np.column_stack([r * np.cos(a), r * np.sin(a)])

    def to_dict(self) -> dict:
        """Returns the scan as JSON-friendly values (``None`` for ``inf`` ranges)."""
        values = {f.name: getattr(self, f.name) for f in dc.fields(self)}
        values["ranges"] = [float(r) if math.isfinite(r) else None for r in self.ranges]
        return values


def measured_ranges(exact: np.ndarray, config: LidarConfig, rng: np.random.Generator):
    """Returns what the lidar reports for the ``exact`` ranges (m): noise, rounding, limits."""
    ranges = (
        exact + rng.normal(0.0, config.noise_sigma, exact.shape) if config.noise_sigma else exact
    )
    if config.resolution > 0.0:
        ranges = np.round(ranges / config.resolution) * config.resolution
    return np.where((ranges >= config.range_min) & (ranges <= config.range_max), ranges, np.inf)


class Lidar(LeafSystem):
    """A planar laser scanner rigidly attached to a frame of a MultibodyPlant.

    .. pydrake_system::

        name: Lidar
        input_ports:
        - query_object
        output_ports:
        - scan

    ``query_object`` comes from the SceneGraph (``add_lidar`` connects it); the lidar's pose
    is read from it too. ``scan`` is a ``LaserScan`` taken at t = 0, 1/rate, 2/rate, ... and
    held in between (zero-order hold); before the first scan its time is nan and its ranges inf.

    Args:
        plant: the finalised plant that holds ``frame`` and the ``ignore``d instances.
        frame: the plant frame the lidar is fixed to.
        X_FL: the lidar frame L's pose in ``frame``.
        config: the scanner.
        ignore: model instances the lidar does not see (its own robot).
        seed: seeds the range noise.
    """

    def __init__(
        self,
        *,
        plant: MultibodyPlant,
        frame: Frame,
        X_FL: RigidTransform | None = None,
        config: LidarConfig | None = None,
        ignore: Sequence[ModelInstanceIndex] = (),
        seed: int = 0,
    ):
        super().__init__()
        self._config = check_lidar_config(config if config is not None else LidarConfig())
        body = frame.body()
        X_FL = X_FL if X_FL is not None else RigidTransform()
        self._X_BL = frame.GetFixedPoseInBodyFrame() @ X_FL
        self._frame_id = plant.GetBodyFrameIdOrThrow(body.index())
        self._seed = int(seed)
        self._fan = self._config.fan()
        ignore_frames = [
            plant.GetBodyFrameIdIfExists(index)
            for instance in ignore
            for index in plant.GetBodyIndices(instance)
        ]
        static_frames = [
            plant.GetBodyFrameIdIfExists(b.index())
            for b in plant.GetBodiesWeldedTo(plant.world_body())
        ]
        self._caster = SceneRayCaster(
            ignore_frames=[f for f in ignore_frames if f is not None],
            static_frames=[f for f in static_frames if f is not None],
        )
        self._query = self.DeclareAbstractInputPort(
            "query_object", AbstractValue.Make(QueryObject())
        )
        c = self._config
        blank = LaserScan(
            math.nan, c.angle_min(), c.angle_increment(), c.range_min, c.range_max,
            np.full(c.samples, np.inf),
        )  # fmt: skip
        state = self.DeclareAbstractState(AbstractValue.Make(blank))
        self.DeclarePeriodicUnrestrictedUpdateEvent(1.0 / c.rate, 0.0, self._scan)
        self.DeclareStateOutputPort("scan", state)

    @property
    def config(self) -> LidarConfig:
        """The scanner's settings."""
        return self._config

    def exact_ranges(self, context) -> np.ndarray:
        """Returns the true distances (m) along the beams at ``context`` to the first surface,
        inf where there is none within ``range_max``: no noise, no ``range_min``."""
        query_object = self._query.Eval(context)
        X_WL = query_object.GetPoseInWorld(self._frame_id) @ self._X_BL
        return self._caster.cast(query_object, X_WL, self._fan, self._config.range_max)

    def scan_now(self, context) -> LaserScan:
        """Returns the scan the lidar would take at ``context``'s time (its input connected)."""
        c, time = self._config, context.get_time()
        rng = np.random.default_rng([self._seed, round(time * c.rate)])
        ranges = measured_ranges(self.exact_ranges(context), c, rng)
        return LaserScan(time, c.angle_min(), c.angle_increment(), c.range_min, c.range_max, ranges)

    def _scan(self, context, state) -> EventStatus:
        state.get_mutable_abstract_state(0).set_value(self.scan_now(context))
        return EventStatus.Succeeded()


def add_lidar(
    builder: DiagramBuilder,
    plant: MultibodyPlant,
    scene_graph: SceneGraph,
    *,
    name: str = "lidar",
    **lidar,
) -> Lidar:
    """Adds a ``Lidar(plant=plant, **lidar)`` called ``name`` (``frame``, ``X_FL``, ``config``,
    ``ignore``, ``seed``: see ``Lidar``) and connects its ``query_object`` input to
    ``scene_graph``."""
    system = builder.AddNamedSystem(name, Lidar(plant=plant, **lidar))
    builder.Connect(scene_graph.get_query_output_port(), system.get_input_port(0))
    return system
