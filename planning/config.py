"""Typed configuration of the Panda planning model, its scene and its IK.

Every field has a default (the one place of each value), so a YAML file needs only the keys it
changes; unknown keys are errors (``drake_sim.base.config.load_typed``). In the pick-and-place
scenario this is the ``robot`` section (``diagrams.pickplace_scenario``). Joint positions are in
rad (arm) and m (fingers), lengths in m, times in s. This module has no ``from __future__ import
annotations``: the YAML loader reads the field types at run time.
"""

import dataclasses as dc
import math
from pathlib import Path

from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from planning.model.layout import FINGER_CLOSED, FINGER_OPEN, NUM_ARM_JOINTS, READY_Q


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
    finger_position: float = FINGER_OPEN
    # Named arm configurations, rad, 7 joints each; the SRDF's group_state entries are added
    # (a name here wins over the SRDF).
    named_configurations: dict[str, list[float]] = dc.field(
        default_factory=lambda: {
            "ready": list(READY_Q),  # franka "ready"
            "extended": [0.0, 0.6, 0.0, -0.9, 0.0, 1.5, math.pi / 4],  # reaching forward
            "transport": [0.0, -0.9, 0.0, -2.8, 0.0, 1.9, math.pi / 4],  # folded, hand up close
        }
    )
    # Link pairs never checked against each other, in addition to the SRDF's disabled pairs.
    # The hand-held object's body and the fingers never collide with what the fingers hold.
    extra_disabled_collisions: list[list[str]] = dc.field(
        default_factory=lambda: [
            ["panda_attachment", "panda_leftfinger"],
            ["panda_attachment", "panda_rightfinger"],
        ]
    )
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
    """The Panda for planning: its model, the table a new scene starts with, and IK."""

    model: PandaModelConfig = dc.field(default_factory=PandaModelConfig)
    # The table every new PlanningScene starts with, as a world object named "table"; null: none.
    table: TableConfig | None = dc.field(default_factory=TableConfig)
    ik: IkOptions = dc.field(default_factory=IkOptions)


def load_panda_config(
    filename: Path | str | None = None, *, data: str | None = None
) -> PandaPlanningConfig:
    """Loads a ``PandaPlanningConfig`` from a YAML file or string (missing keys keep defaults).

    Args:
        filename: the YAML file; or
        data: YAML text.

    Raises:
        ConfigError: the file is missing or malformed, or has an unknown key or a bad value.
    """
    where = str(filename) if filename is not None else "<yaml>"
    config = load_typed(PandaPlanningConfig, filename=filename, data=data, where=where)
    check_panda_config(config, where)
    return config


def check_panda_config(config: PandaPlanningConfig, where: str = "robot") -> None:
    """Raises ConfigError for values the planning model cannot use."""
    model = config.model
    for name, q in model.named_configurations.items():
        if len(q) != NUM_ARM_JOINTS:
            raise ConfigError(
                f"{where}: model.named_configurations.{name} has {len(q)} values, "
                f"expected {NUM_ARM_JOINTS}"
            )
    for pair in model.extra_disabled_collisions:
        if len(pair) != 2:
            raise ConfigError(
                f"{where}: model.extra_disabled_collisions entry {pair} is not a pair"
            )
    if not FINGER_CLOSED <= model.finger_position <= FINGER_OPEN:
        raise ConfigError(
            f"{where}: model.finger_position must be in [{FINGER_CLOSED}, {FINGER_OPEN}] m"
        )
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
