"""The arm station's settings: ``ArmStationConfig`` (the ``station`` section of the pick-and-place
scenario), the positions its ports carry (``station_layout``), its start and its checks. The
station itself is ``diagrams.arm_station``.
"""

import dataclasses as dc

import numpy as np
from pydrake.multibody.plant import MultibodyPlantConfig
from pydrake.visualization import VisualizationConfig

from drake_sim.base.errors import ConfigError
from planning.io.scene_files import SceneFile
from planning.model.arm_layout import ArmLayout
from planning.model.model_config import RobotModelConfig
from planning.model.planning_model import finger_defaults, home_configuration, robot_model

MODES = ("physics", "kinematic")
"""The station's modes (``diagrams.arm_station``)."""


def _default_plant() -> MultibodyPlantConfig:
    return MultibodyPlantConfig(
        time_step=0.001,
        discrete_contact_approximation="sap",
        contact_model="point",
        sap_near_rigid_threshold=0.01,
    )


@dc.dataclass
class ArmStationConfig:
    """Everything the station needs: plant, gains, friction, viewer, and (filled in by the
    scenario) the robot model, the scene and the start.

    Gains are Drake implicit PD gains per joint actuator; effort limits clamp PD plus gravity
    compensation. Arm values are one per joint of the group (the defaults are the Panda's 7,
    Franka's datasheet); finger values are per finger. The kinematic station uses none of them.
    """

    plant: MultibodyPlantConfig = dc.field(default_factory=_default_plant)
    model: RobotModelConfig = dc.field(default_factory=RobotModelConfig)
    arm_kp: list[float] = dc.field(default_factory=lambda: [2000.0] * 4 + [500.0] * 3)  # N m/rad
    arm_kd: list[float] = dc.field(default_factory=lambda: [100.0] * 4 + [20.0] * 3)  # N m s/rad
    arm_effort_limits: list[float] = dc.field(  # N m, Franka's datasheet
        default_factory=lambda: [87.0] * 4 + [12.0] * 3
    )
    finger_kp: float = 10000.0  # N/m
    finger_kd: float = 100.0  # N s/m
    finger_force_limit: float = 70.0  # N, per finger (Franka hand: 70 N continuous)
    finger_friction: list[float] = dc.field(default_factory=lambda: [1.0, 1.0])  # static, dynamic
    object_friction: list[float] = dc.field(default_factory=lambda: [1.0, 1.0])  # unless the scene
    obstacle_friction: list[float] = dc.field(default_factory=lambda: [0.5, 0.5])
    table_friction: list[float] = dc.field(default_factory=lambda: [0.8, 0.6])
    # Point-contact stiffness of the fingers, the object, the table and the obstacle, N/m
    # (pairs combine in series); the plant's default lets 70 N sink a finger ~9 mm in.
    point_stiffness: float = 1.0e6
    # Initial positions: the group's joints (rad or m) then the fingers (m); empty for the
    # model's home configuration with the fingers at their defaults. In a pick-and-place
    # scenario: its initial_configuration, fingers at robot.model.finger_position.
    initial_q: list[float] = dc.field(default_factory=list)
    visualization: VisualizationConfig = dc.field(
        default_factory=lambda: VisualizationConfig(
            publish_contacts=False, publish_proximity=False, publish_inertia=False
        )
    )
    # The scene (table, object, obstacle; place is ignored here). In a pick-and-place
    # scenario: its scene section.
    scene: SceneFile = dc.field(default_factory=SceneFile)


def station_layout(config: ArmStationConfig) -> ArmLayout:
    """The positions the station's ports carry (``planning.model.arm_layout``).

    Raises:
        ConfigError: the robot description cannot be loaded.
    """
    return ArmLayout.of(robot_model(config.model))


def initial_positions(config: ArmStationConfig) -> np.ndarray:
    """The station's start: ``initial_q``, or the model's home with the default fingers."""
    if config.initial_q:
        return np.asarray(config.initial_q, dtype=float)
    home = home_configuration(config.model)
    return np.concatenate([home, finger_defaults(config.model)])


def validate_station_config(config: ArmStationConfig, mode: str = "kinematic") -> None:
    """Raises ConfigError for values the builder cannot use in ``mode`` (the gains only count
    in physics)."""
    layout = station_layout(config)
    n = layout.num_positions
    if config.initial_q and len(config.initial_q) != n:
        raise ConfigError(
            f"initial_q has {len(config.initial_q)} values, expected {n} "
            f"({layout.num_joints} joints of the group, {layout.num_fingers} fingers)"
        )
    if mode == "physics":
        if layout.others:
            raise ConfigError(
                f"physics station: {layout.robot} has moving joints outside its group and "
                f"fingers ({', '.join(layout.others)}), which nothing would hold: use the "
                "kinematic mode"
            )
        for name in ("arm_kp", "arm_kd", "arm_effort_limits"):
            if len(getattr(config, name)) != layout.num_joints:
                raise ConfigError(
                    f"station.{name} needs {layout.num_joints} values, one per joint of "
                    f"{layout.robot}'s group ({', '.join(layout.group)}); it has "
                    f"{len(getattr(config, name))}"
                )
    scene = config.scene
    for name in ("table", "object", "obstacle"):
        box = getattr(scene, name)
        if box is not None and (len(box.size) != 3 or len(box.position) != 3):
            raise ConfigError(f"scene {name}: size and position need 3 values each")
        if box is not None and min(box.size) <= 0.0:
            raise ConfigError(f"scene {name}: sizes must be positive")
    if scene.object is not None and scene.object.mass <= 0.0:
        raise ConfigError("scene object: mass must be positive (kg)")
