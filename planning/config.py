"""Typed configuration of the planning robot (the Panda by default), its scene and its IK.

The model's and the table's sections (``RobotModelConfig``, ``TableConfig``) live with the model
that reads them, in ``planning.model.model_config``; this module gathers them with the IK's
options, and loads and checks the whole. Every field has a default (the one place of each
value), so a YAML file needs only the keys it changes; unknown keys are errors
(``drake_sim.base.config.load_typed``). In the pick-and-place scenario this is the ``robot``
section (``diagrams.pickplace_scenario``). Joint positions are in rad (arm) and m (fingers),
lengths in m, times in s. This module has no ``from __future__ import annotations``: the YAML
loader reads the field types at run time.
"""

import dataclasses as dc
from pathlib import Path

from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from planning.model.model_config import RobotModelConfig, TableConfig
from planning.model.planning_model import finger_defaults, named_configurations


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
class PlanningConfig:
    """A robot for planning: its model (a description: the Panda by default), the table a new
    scene starts with, and IK."""

    model: RobotModelConfig = dc.field(default_factory=RobotModelConfig)
    # The table every new PlanningScene starts with, as a world object named "table"; null: none.
    table: TableConfig | None = dc.field(default_factory=TableConfig)
    ik: IkOptions = dc.field(default_factory=IkOptions)


def load_planning_config(
    filename: Path | str | None = None, *, data: str | None = None
) -> PlanningConfig:
    """Loads a ``PlanningConfig`` from a YAML file or string (missing keys keep defaults).

    Args:
        filename: the YAML file; or
        data: YAML text.

    Raises:
        ConfigError: the file is missing or malformed, or has an unknown key or a bad value.
    """
    where = str(filename) if filename is not None else "<yaml>"
    config = load_typed(PlanningConfig, filename=filename, data=data, where=where)
    check_planning_config(config, where)
    return config


def check_planning_config(config: PlanningConfig, where: str = "robot") -> None:
    """Raises ConfigError for values the planning model cannot use (the robot's files are read
    to check the named configurations' sizes and the finger position against its joints)."""
    model = config.model
    try:
        named_configurations(model)
        finger_defaults(model)
    except ConfigError as e:
        raise ConfigError(f"{where}: {e}") from None
    for pair in model.extra_disabled_collisions:
        if len(pair) != 2:
            raise ConfigError(
                f"{where}: model.extra_disabled_collisions entry {pair} is not a pair"
            )
    if not model.description:
        raise ConfigError(f"{where}: model.description must name a robot (e.g. panda)")
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
