"""Typed configuration of the Panda planning model, its scene and its IK (``config/panda.yaml``).

Every field has a default, so a YAML file needs only the keys it changes; unknown keys are errors
(``pydrake.common.yaml.yaml_load_typed``). Joint positions are in rad (arm) and m (fingers),
lengths in m, times in s. This module has no ``from __future__ import annotations``: the YAML
loader reads the field types at run time.
"""

import dataclasses as dc
from pathlib import Path

import yaml
from pydrake.common.yaml import yaml_load_typed

from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir


@dc.dataclass
class TableConfig:
    """A box table in the world frame W, by default under the Panda with its top at z = 0."""

    size: list[float] = dc.field(default_factory=lambda: [1.2, 1.4, 0.04])  # m, full extents
    position: list[float] = dc.field(default_factory=lambda: [0.3, 0.0, -0.02])  # m, p_WT centre


@dc.dataclass
class PandaModelConfig:
    """How the Panda is loaded for planning."""

    # "convex_mesh" (the URDF's STL collision meshes, declared convex) or "primitives" (the
    # spheres and cylinders of example-robot-data's panda_collision.urdf).
    collision_geometry: str = "convex_mesh"
    # Frame whose pose RobotState reports and IK targets: the tool centre point between the
    # fingertips, 0.1034 m beyond the hand's flange side along its z axis (MoveIt's end effector).
    ee_frame: str = "panda_hand_tcp"
    # Default opening of each finger, m from the centre (0 closed, 0.04 fully open).
    finger_position: float = 0.04
    # Named arm configurations, rad, 7 joints each; the SRDF's group_state entries are added
    # (a name here wins over the SRDF).
    named_configurations: dict[str, list[float]] = dc.field(default_factory=dict)
    # Link pairs never checked against each other, in addition to the SRDF's disabled pairs.
    extra_disabled_collisions: list[list[str]] = dc.field(default_factory=list)
    # Joint-space step for edge collision checks, rad.
    edge_step_size: float = 0.05
    # Padding added to robot-environment and robot-robot distances, m.
    env_collision_padding: float = 0.0
    self_collision_padding: float = 0.0
    # How far a held object may sink into world objects, m: a grasped object still resting on
    # the table, or set down on it, touches it (MoveIt allows this with ACM / touch links).
    held_object_touch_tolerance: float = 0.002


@dc.dataclass
class IkOptions:
    """Inverse kinematics: tolerances, restarts and time budget."""

    position_tolerance: float = 1e-3  # m, per axis, about the target point
    orientation_tolerance: float = 1e-2  # rad, angle between the target and reached rotations
    # Smallest allowed signed distance between collision geometries, m; None: no collision
    # constraint (only the final check, when check_collisions is true).
    minimum_distance: float | None = 0.0
    # Distance at which pairs start to count in the collision constraint, m beyond the minimum.
    influence_distance: float = 0.05
    check_collisions: bool = True  # reject solutions the collision checker says collide
    max_restarts: int = 20  # random restarts after the seeded attempt
    time_budget: float = 2.0  # s of wall time over all attempts
    seed: int = 0  # seed of np.random.default_rng for the restarts


@dc.dataclass
class PandaPlanningConfig:
    """Everything ``config/panda.yaml`` holds."""

    model: PandaModelConfig = dc.field(default_factory=PandaModelConfig)
    # The table every new PlanningScene starts with, as a world object named "table"; null: none.
    table: TableConfig | None = dc.field(default_factory=TableConfig)
    ik: IkOptions = dc.field(default_factory=IkOptions)


def default_config_path() -> Path:
    """Returns the path of ``config/panda.yaml``."""
    return config_dir() / "panda.yaml"


def load_panda_config(
    filename: Path | str | None = None, *, data: str | None = None
) -> PandaPlanningConfig:
    """Loads a ``PandaPlanningConfig`` from a YAML file or string.

    Args:
        filename: the YAML file; ``config/panda.yaml`` when both arguments are None.
        data: YAML text to load instead of a file.

    Raises:
        ConfigError: the file is missing or malformed, or has an unknown key or a bad value.
    """
    if data is None:
        filename = Path(filename) if filename is not None else default_config_path()
        if not filename.is_file():
            raise ConfigError(f"{filename}: no such file")
    where = str(filename) if data is None else "<yaml string>"
    try:
        if data is None:
            config = yaml_load_typed(schema=PandaPlanningConfig, filename=str(filename))
        else:
            config = yaml_load_typed(schema=PandaPlanningConfig, data=data)
    except (yaml.YAMLError, RuntimeError, ValueError, TypeError, AttributeError) as e:
        raise ConfigError(f"{where}: {e}") from e
    _validate(config, where)
    return config


def _validate(config: PandaPlanningConfig, where: str) -> None:
    model = config.model
    for name, q in model.named_configurations.items():
        if len(q) != 7:
            raise ConfigError(
                f"{where}: model.named_configurations.{name} has {len(q)} values, expected 7"
            )
    for pair in model.extra_disabled_collisions:
        if len(pair) != 2:
            raise ConfigError(
                f"{where}: model.extra_disabled_collisions entry {pair} is not a pair"
            )
    if not 0.0 <= model.finger_position <= 0.04:
        raise ConfigError(f"{where}: model.finger_position must be in [0, 0.04] m")
    if model.edge_step_size <= 0.0:
        raise ConfigError(f"{where}: model.edge_step_size must be positive")
    if config.table is not None and (
        len(config.table.size) != 3
        or len(config.table.position) != 3
        or min(config.table.size) <= 0.0
    ):
        raise ConfigError(f"{where}: table needs a positive 3-vector size and a 3-vector position")
    ik = config.ik
    if ik.time_budget <= 0.0 or ik.max_restarts < 0:
        raise ConfigError(f"{where}: ik.time_budget must be positive and ik.max_restarts >= 0")
    if ik.position_tolerance <= 0.0 or ik.orientation_tolerance <= 0.0:
        raise ConfigError(f"{where}: ik tolerances must be positive")
