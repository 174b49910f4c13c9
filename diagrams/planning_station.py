"""The Panda station with a ``MotionPlanningInterface`` joined to it, ready to use.

``make_planning_station`` is what a script or a notebook calls; a user who builds their own
diagram adds the station with ``make_panda_station_diagram`` and joins the interface with
``MotionPlanningInterface.add_to_builder`` themselves (see its docstring).
"""

from pydrake.systems.framework import DiagramBuilder

from diagrams.panda_station import PandaStationConfig, make_panda_station_diagram
from planning.config import load_panda_config
from planning.interface import InterfaceOptions, MotionPlanningInterface
from planning.io.scene_files import apply_scene_file
from planning.motion_planner import MotionPlannerOptions
from planning.planning_scene import PlanningScene


def make_planning_scene(config: PandaStationConfig, *, meshcat=None) -> PlanningScene:
    """A ``PlanningScene`` (the planning model of ``config/panda.yaml``) holding the station
    scene's objects: table, object, obstacle, extra objects; ``place_position``."""
    scene = PlanningScene(load_panda_config(), meshcat=meshcat)
    apply_scene_file(scene, config.scene)
    return scene


def make_planning_station(
    config: PandaStationConfig,
    *,
    mode: str = "physics",
    meshcat=None,
    planner_options: MotionPlannerOptions | None = None,
    options: InterfaceOptions | None = None,
    realtime_rate: float = 0.0,
) -> MotionPlanningInterface:
    """Builds the station (``mode`` "physics" or "kinematic"), joins a new interface on a
    planning scene of the same scene, and starts its simulator.

    Returns:
        The started interface: ``interface.simulator`` runs the diagram.

    Raises:
        ConfigError: bad station values or mode.
        PlanningError: INVALID_SCENE for scene values planning cannot use.
    """
    scene = make_planning_scene(config)
    interface = MotionPlanningInterface(scene, planner_options, options=options)
    interface.state.set_q(config.initial_q)
    builder = DiagramBuilder()
    station = builder.AddSystem(make_panda_station_diagram(config, meshcat=meshcat, mode=mode))
    station.set_name("station")
    interface.add_to_builder(builder, station)
    diagram = builder.Build()
    diagram.set_name(f"planning_station_{mode}")
    interface.start(diagram, realtime_rate=realtime_rate)
    return interface
