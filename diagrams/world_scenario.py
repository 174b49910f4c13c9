"""Typed scenario for the diff-drive world: what to load, where the robot starts, and how the
plant, the simulator and the visualiser are configured. Values live in ``config/*.yaml``."""

import dataclasses as dc
import math

from pydrake.multibody.plant import MultibodyPlantConfig
from pydrake.systems.analysis import SimulatorConfig
from pydrake.visualization import VisualizationConfig

from drake_sim.base.config import load_typed, read_text
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import resolve_uri


@dc.dataclass
class PlanarPose:
    """A pose on the ground plane."""

    x: float = 0.0  # m, world x.
    y: float = 0.0  # m, world y.
    yaw: float = 0.0  # rad, about world z; 0 means the robot's wheels point along +x.
    upside_down: bool = False  # Start on the top caster (turned over about the body's x axis).


@dc.dataclass
class GroundConfig:
    """The ground: a half-space at z = 0 on the world body (asphalt by default)."""

    mu_static: float = 0.9  # Coulomb friction, unitless.
    mu_dynamic: float = 0.8  # Coulomb friction, unitless; at most mu_static.


@dc.dataclass
class WorldScenario:
    """The diff-drive robot in its world."""

    # SDFormat world (package:// URI or path); empty for the bare ground.
    world: str = "package://drake_sim_models/worlds/ddrive.world.sdf"
    ground: GroundConfig = dc.field(default_factory=GroundConfig)
    # Where the robot starts, standing on its wheels and bottom caster.
    robot_pose: PlanarPose = dc.field(default_factory=PlanarPose)
    # Length of the frame triads drawn on the robot's links, m; 0 hides them.
    frame_triad_length: float = 0.15
    plant: MultibodyPlantConfig = dc.field(
        default_factory=lambda: MultibodyPlantConfig(
            time_step=2e-3,
            contact_model="point",
            discrete_contact_approximation="sap",
        )
    )
    simulator: SimulatorConfig = dc.field(
        default_factory=lambda: SimulatorConfig(target_realtime_rate=1.0)
    )
    visualization: VisualizationConfig = dc.field(
        default_factory=lambda: VisualizationConfig(publish_inertia=False, publish_proximity=False)
    )
    random_seed: int = 0  # Seed for anything random in the scenario.


def load_scenario(filename, schema=WorldScenario, *, defaults=None, check=True):
    """Loads a scenario YAML into ``schema`` (unknown keys are errors; missing keys keep defaults).

    With ``check`` (for a ``WorldScenario``), the values are checked too.

    Raises:
        ConfigError: if the file cannot be read or parsed, or holds a bad value.
    """
    text = read_text(filename, "scenario file")
    scenario = load_typed(schema, data=text, defaults=defaults, where=str(filename))
    if check:
        check_world_scenario(scenario, str(filename))
    return scenario


def check_world_scenario(scenario: WorldScenario, filename: str = "scenario") -> None:
    """Raises ConfigError for non-finite or out-of-range values in ``scenario``."""
    if scenario.world:
        try:
            world_file = resolve_uri(scenario.world)
        except ValueError as e:
            raise ConfigError(f"{filename}: 'world': {e}") from None
        if not world_file.is_file():
            raise ConfigError(f"{filename}: 'world' file not found: {scenario.world}")
    pose = scenario.robot_pose
    for key in ("x", "y", "yaw"):
        if not math.isfinite(getattr(pose, key)):
            raise ConfigError(f"{filename}: 'robot_pose.{key}' must be finite")
    if not scenario.plant.time_step > 0:
        raise ConfigError(f"{filename}: 'plant.time_step' must be > 0 (a discrete plant)")
    g = scenario.ground
    if not (math.isfinite(g.mu_static) and math.isfinite(g.mu_dynamic) and g.mu_dynamic >= 0):
        raise ConfigError(f"{filename}: 'ground' friction must be finite and >= 0")
    if g.mu_dynamic > g.mu_static:
        raise ConfigError(f"{filename}: 'ground.mu_dynamic' must not exceed 'ground.mu_static'")
    if not (math.isfinite(scenario.frame_triad_length) and scenario.frame_triad_length >= 0):
        raise ConfigError(f"{filename}: 'frame_triad_length' must be finite and >= 0")
