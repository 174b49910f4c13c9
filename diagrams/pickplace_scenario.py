"""The pick-and-place scenario: all that ``python -m drake_sim.pickplace`` runs, in one typed file.

A ``PickPlaceScenario`` (``config/pickplace_scenario.yaml``) has one section per part, each
typed by the schema that part uses, and every value lives in one place:

* ``scene`` (``planning.io.scene_files.SceneFile``): table, object, obstacle, place. When absent,
  the scene is read from ``scene_file`` (relative to the scenario file), by default
  ``config/pickplace.yaml``. The table lives here only.
* ``robot`` (``planning.config.PlanningConfig``): the robot's model (the Panda by default, or any
  description: ``model.description``; collision geometry,
  named configurations, disabled pairs) and IK, shared by the planner and the simulated station.
* ``initial_configuration``: the named configuration the arm starts in (fingers open at
  ``robot.model.finger_position``).
* ``station`` (``diagrams.arm_station.ArmStationConfig``): plant, gains, friction, viewer.
* ``planner`` (``planning.motion_planner.MotionPlannerOptions``), ``task``
  (``planning.task.options.PickPlaceOptions``), ``interface``
  (``planning.execution.options.InterfaceOptions``), and ``mode`` (physics or kinematic).

A missing key keeps the schema's default; unknown keys and bad values are ``ConfigError``s naming
the file and the key. This module has no ``from __future__ import annotations`` (the YAML loader
reads the field types at run time).
"""

import dataclasses as dc
from pathlib import Path

import yaml
from pydrake.common.yaml import yaml_dump_typed

from diagrams.arm_station_config import (
    MODES,
    ArmStationConfig,
    station_layout,
    validate_station_config,
)
from drake_sim.base.config import apply_overrides, check_tree, load_typed, parse_yaml, read_text
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from planning.config import PlanningConfig, check_planning_config
from planning.execution.options import InterfaceOptions
from planning.io.scene_files import SceneFile
from planning.model.planning_model import finger_defaults, named_configurations
from planning.motion_planner import MotionPlannerOptions
from planning.task.options import PickPlaceOptions

DEFAULT_SCENARIO = "pickplace_scenario.yaml"
"""The shipped scenario, in ``config/``."""

# Keys of a section that the scenario fills from its one place, with where that place is.
_FILLED = {
    "station.model": "robot.model",
    "station.scene": "scene (or scene_file)",
    "station.initial_q": "initial_configuration",
    "robot.table": "scene.table",
}


def _robot_without_table() -> PlanningConfig:
    return PlanningConfig(table=None)


@dc.dataclass
class PickPlaceScenario:
    """A pick-and-place: scene, robot, station, planner, task, interface and mode.

    An arm without finger joints (the UR5 of VAMP's set) runs in the kinematic mode only; one
    with a group of other than 7 joints needs ``station.arm_kp``, ``arm_kd`` and
    ``arm_effort_limits`` of its size in the physics mode."""

    # Our scene YAML, relative to the scenario file; read when ``scene`` is not given.
    scene_file: str = "pickplace.yaml"
    scene: SceneFile | None = None
    robot: PlanningConfig = dc.field(default_factory=_robot_without_table)
    # Named configuration of ``robot.model`` (or the SRDF's) the arm starts in.
    initial_configuration: str = "ready"
    station: ArmStationConfig = dc.field(default_factory=ArmStationConfig)
    planner: MotionPlannerOptions = dc.field(default_factory=MotionPlannerOptions)
    task: PickPlaceOptions = dc.field(default_factory=PickPlaceOptions)
    interface: InterfaceOptions = dc.field(default_factory=InterfaceOptions)
    mode: str = "physics"  # "physics" (contact, grasp by friction) or "kinematic" (played back)

    def station_config(self) -> ArmStationConfig:
        """The station's config with the robot model, the scene and the start filled in."""
        if self.scene is None:
            raise ConfigError("scenario: no scene (load it with load_pickplace_scenario)")
        named = named_configurations(self.robot.model)
        q_arm = named.get(self.initial_configuration)
        if q_arm is None:
            known = ", ".join(sorted(named))
            raise ConfigError(
                f"scenario: initial_configuration {self.initial_configuration!r} is not a named "
                f"configuration of robot.model (known: {known})"
            )
        fingers = finger_defaults(self.robot.model)
        return dc.replace(
            self.station,
            model=self.robot.model,
            scene=self.scene,
            initial_q=[*map(float, q_arm), *fingers],
        )


def load_pickplace_scenario(
    filename: Path | str | None = None,
    *,
    scene_file: Path | str | None = None,
    overrides: list[str] | tuple[str, ...] = (),
) -> PickPlaceScenario:
    """Loads a scenario, then its scene, then ``--set``-style overrides, and checks it all.

    Args:
        filename: the scenario YAML; ``config/pickplace_scenario.yaml`` when None.
        scene_file: a scene YAML that replaces the scenario's scene (``--scene FILE``).
        overrides: ``KEY=VALUE`` strings with dotted keys (``--set task.lift_height=0.08``).

    Raises:
        ConfigError: naming the file and the key, for anything malformed or out of range.
    """
    path = Path(filename) if filename is not None else config_dir() / DEFAULT_SCENARIO
    text = read_text(path, "scenario file")
    _refuse_filled_keys(parse_yaml(text, str(path)), str(path))
    scenario = load_typed(PickPlaceScenario, data=text, where=str(path))
    if scene_file is not None:
        scenario.scene = load_typed(SceneFile, filename=scene_file)
    elif scenario.scene is None:
        scene_path = path.parent / scenario.scene_file
        scenario.scene = load_typed(SceneFile, filename=scene_path)
    for item in overrides:
        item = item[1] if isinstance(item, tuple) else item  # (label, KEY=VALUE) from a flag
        key = item.partition("=")[0]
        if key in _FILLED or any(key.startswith((k + ".", k + "[")) for k in _FILLED):
            raise ConfigError(f"--set {item!r}: {key} is set by {_filled_by(key)}")
    scenario = apply_overrides(PickPlaceScenario, scenario, overrides)
    check_scenario(scenario, str(path))
    return scenario


def dump_pickplace_scenario(scenario: PickPlaceScenario) -> str:
    """The whole scenario as YAML that ``load_pickplace_scenario`` reads back: every value, the
    scene inline, and none of the keys the scenario fills in itself."""
    data = yaml.safe_load(yaml_dump_typed(scenario))
    data.pop("scene_file", None)
    for key in _FILLED:
        section, name = key.split(".")
        data[section].pop(name, None)
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=None)


def check_scenario(scenario: PickPlaceScenario, where: str = "scenario") -> None:
    """Raises ConfigError for values no section can use (ranges, sizes, names), and for a
    scene without the ``object`` to pick or the ``place`` to put it (a malformed file, not an
    impossible task)."""
    for key, what in (("object", "the box to pick"), ("place", "where to put the object")):
        if scenario.scene is not None and getattr(scenario.scene, key) is None:
            raise ConfigError(f"{where}: the scene has no '{key}' key ({what})")
    if scenario.mode not in MODES:
        raise ConfigError(f"{where}: 'mode' must be one of {', '.join(MODES)}")
    check_planning_config(scenario.robot, where)
    try:
        scenario.planner.check()
    except ValueError as e:
        raise ConfigError(f"{where}: planner: {e}") from None
    try:
        scenario.task.check("task.")
    except ValueError as e:
        raise ConfigError(f"{where}: {e}") from None
    for field in dc.fields(scenario.interface):
        if not getattr(scenario.interface, field.name) >= 0.0:
            raise ConfigError(f"{where}: 'interface.{field.name}' must be >= 0")
    station = scenario.station_config()
    layout = station_layout(station)
    if scenario.mode == "physics" and not layout.num_fingers:
        raise ConfigError(
            f"{where}: {layout.robot} has no finger joints below its attach link: it grasps "
            "in the kinematic mode only (mode: kinematic)"
        )
    validate_station_config(station, scenario.mode)


def _refuse_filled_keys(tree, where: str) -> None:
    if not isinstance(tree, dict):
        return  # load_typed names the problem
    check_tree(PickPlaceScenario, tree, where)
    for key in _FILLED:
        section, name = key.split(".")
        if isinstance(tree.get(section), dict) and name in tree[section]:
            raise ConfigError(f"{where}: '{key}' is set by {_filled_by(key)}, in one place")


def _filled_by(key: str) -> str:
    for filled, place in _FILLED.items():
        if key == filled or key.startswith((filled + ".", filled + "[")):
            return place
    return "the scenario"
