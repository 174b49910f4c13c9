"""The Panda station with a ``MotionPlanningInterface`` joined to it, ready to use.

``make_planning_station`` is what a script or a notebook calls, with a pick-and-place scenario
(``diagrams.pickplace_scenario``); a user who builds their own diagram adds the station with
``make_arm_station_diagram`` and joins the interface with
``MotionPlanningInterface.add_to_builder`` themselves (see its docstring).
"""

import dataclasses as dc

from pydrake.systems.framework import DiagramBuilder

from diagrams.arm_station import make_arm_station_diagram
from diagrams.pickplace_scenario import PickPlaceScenario
from planning.interface import MotionPlanningInterface
from planning.io.scene_files import apply_scene_file
from planning.planning_scene import PlanningScene


def make_planning_scene(scenario: PickPlaceScenario, *, meshcat=None) -> PlanningScene:
    """A ``PlanningScene`` of the scenario's robot holding its scene's objects (table, object,
    obstacle, extra objects) and ``place_position``."""
    scene = PlanningScene(scenario.robot, meshcat=meshcat)
    apply_scene_file(scene, scenario.scene)
    return scene


def make_planning_station(
    scenario: PickPlaceScenario,
    *,
    mode: str | None = None,
    meshcat=None,
    realtime_rate: float = 0.0,
) -> MotionPlanningInterface:
    """Builds the station of ``scenario`` (in ``mode``, default the scenario's), joins a new
    interface on a planning scene of the same robot and scene, and starts its simulator.

    Returns:
        The started interface: ``interface.simulator`` runs the diagram.

    Raises:
        ConfigError: bad station values or mode.
        PlanningError: INVALID_SCENE for scene values planning cannot use.
    """
    if mode is not None:
        scenario = dc.replace(scenario, mode=mode)
    station_config = scenario.station_config()
    scene = make_planning_scene(scenario)
    interface = MotionPlanningInterface(scene, scenario.planner, options=scenario.interface)
    interface.state.set_q(station_config.initial_q)
    builder = DiagramBuilder()
    station = builder.AddSystem(
        make_arm_station_diagram(station_config, meshcat=meshcat, mode=scenario.mode)
    )
    station.set_name("station")
    interface.add_to_builder(builder, station)
    diagram = builder.Build()
    diagram.set_name(f"planning_station_{scenario.mode}")
    interface.start(diagram, realtime_rate=realtime_rate)
    return interface
