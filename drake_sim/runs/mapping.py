"""The lidar robot's mapping app (``python -m drake_sim.mapping``): its recipe, its run (build
the diagram, drive the route or teleop until it is done, save the map) and the report that
scores the map against the arena's ground truth.

The report's keys are DESIGN.md's (``python -m drake_sim.mapping``): ``map_iou`` compares the
map's occupied cells with the arena's at the lidar's scan height, one cell of tolerance
(``occupancy_iou``); ``known_fraction`` is the share of the arena's cells the map knows;
``pose_rmse_m`` is the RMS distance between the SLAM pose at each scan and the true pose at
that instant; ``odometry_final_error_m`` is the raw wheel odometry's final error, to show what
the SLAM corrected.
"""

import dataclasses as dc
import math
from pathlib import Path

import numpy as np

from diagrams.mapping import make_mapping_diagram
from diagrams.mapping_scenario import (
    MappingScenario,
    check_mapping_scenario,
    config_path,
    default_scenario_file,
)
from drake_sim.base import cli
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap, save_map
from drake_sim.base.mcap_files import McapLogWriter
from drake_sim.base.planar import wrap_angle
from drake_sim.base.report import RunReport, run_times
from drake_sim.robots.turtlebot3_params import Turtlebot3Params
from drake_sim.runs import recipe
from drake_sim.runs.lidar_robot import (
    ARENA_FLAG,
    LIDAR_FLAG,
    ROBOT_FILE,
    START_FLAG,
    WORLD_FLAG,
    load_world,
)
from drake_sim.runs.loop import SimulationRun
from drake_sim.runs.recipe import AppRecipe, CliText, Flag, InputFile, Inputs
from drake_sim.runs.ros_recording import (
    RECORD_LOG_FLAG,
    close_ros_log,
    dropped_on_error,
    open_ros_log,
)
from drake_sim.systems.estimation.occupancy_grid import known_fraction, occupancy_iou
from drake_sim.systems.viewer.teleop import BUTTONS
from drake_sim.worlds.arena import Arena, arena_grid
from drake_sim.worlds.map_world import known_truth
from drake_sim.worlds.route import default_route_file, load_route

DEFAULT_OUT = "maps"
"""The folder of the map files when ``--out`` is not given: ``maps/<arena's name>``."""

CHECK_PERIOD = 0.5
"""s of simulated time between checks of the run's end conditions."""

ENDS = ("route_done", "duration", "stopped", "failed")
"""Why a run ended: the route was driven to its end, the time ran out, Ctrl-C or SIGTERM
(``stopped``), or the simulation failed."""


@dc.dataclass(kw_only=True)
class MappingReport(RunReport):
    """What a mapping run did (DESIGN.md, ``python -m drake_sim.mapping``)."""

    end: str  # One of ENDS.
    map_iou: float  # Occupied cells against the ground truth's, one cell of tolerance.
    known_fraction: float  # The arena's free and occupied cells that the map knows.
    pose_rmse_m: float  # SLAM position against the truth at each scan, RMS.
    final_pose_error_m: float  # SLAM position error at the last scan.
    final_yaw_error_deg: float  # |SLAM yaw error| at the last scan.
    odometry_final_error_m: float  # The raw wheel odometry's position error at the last scan.
    odometry_final_yaw_error_deg: float  # |its yaw error| there.
    scans: int  # Scans the SLAM processed.
    route_fraction: float  # Waypoints reached over the route's waypoints (1 for teleop).
    map_files: list[str] | None = None  # The .pgm and .yaml written, if any.


def route_length(start, waypoints) -> float:
    """The length (m) of the polyline from ``start`` ([x, y, ...]) through ``waypoints``."""
    points = np.vstack([np.asarray(start, dtype=float)[:2], np.reshape(waypoints, (-1, 2))])
    return float(np.sum(np.hypot(*np.diff(points, axis=0).T)))


class MappingRun(SimulationRun):
    """Builds the mapping diagram and a simulator for one run; ``run`` drives, ``save_map``
    writes map_server files and ``report`` scores the map and the poses. ``diagram``:
    ``make_mapping_diagram``'s keywords (``meshcat``, ``teleop``: the Meshcat keys drive
    instead of the route, ``keyframes``: keep the growing map in a Meshcat recording);
    ``out``: where ``finish`` saves the map (``maps/<arena>`` when None); ``world_map``: the
    map the arena was made from, whose known cells the map is scored on; ``log_writer``:
    the ROS 2 log to write the run to (``drake_sim.runs.ros_recording``). The scenario's
    ``random_seed`` seeds the odometry errors and the lidar noise."""

    check_period = CHECK_PERIOD
    doing = "mapping"

    def __init__(
        self,
        scenario: MappingScenario,
        robot: Turtlebot3Params,
        arena: Arena,
        waypoints,
        *,
        realtime: bool = False,
        out: Path | str | None = None,
        arena_file: Path | str = "arena",
        world_map: OccupancyMap | None = None,
        log_writer: McapLogWriter | None = None,
        **diagram,
    ):
        self.scenario = scenario
        self.world_map = world_map  # the map the arena was made from (--world), or None
        self.robot = robot
        self.arena = arena
        self.waypoints = np.asarray(waypoints, dtype=float).reshape(-1, 2)
        self.teleop = diagram.get("teleop", False)
        self._log = log_writer
        with dropped_on_error(log_writer):
            diagram = make_mapping_diagram(
                scenario, robot, arena, self.waypoints, log_writer=log_writer, **diagram
            )
            super().__init__(diagram, scenario.random_seed, realtime=realtime)
        self._slam = self.diagram.GetSubsystemByName("slam")
        self._truth_log = self.diagram.GetSubsystemByName("log_true_pose")
        self._route = self.diagram.GetSubsystemByName("route_follower") if not self.teleop else None
        self.map_files: list[str] | None = None
        self.arena_file = Path(arena_file)  # named in the summary line
        self.out = Path(out) if out is not None else Path(DEFAULT_OUT) / self.arena_file.stem
        self.files: tuple[Path, Path] | None = None

    def default_duration(self, *, viewer: bool = False) -> float:
        """Simulated seconds for the route at the follower's speed, with the scenario's factor
        and margin; teleop runs until Ctrl-C with a viewer."""
        if self.teleop:
            return math.inf if viewer else self.scenario.duration_margin
        start = self.arena.start_pose()
        length = route_length(start, self.waypoints)
        speed = self.scenario.route_follower.speed
        return length / speed * self.scenario.duration_factor + self.scenario.duration_margin

    def set_up_viewer(self, meshcat) -> None:
        """Points Meshcat's camera at the arena and hides the grid (the arena has a floor)."""
        x, y, _ = self.arena.start_pose()
        meshcat.SetCameraPose([x - 2.0, y - 3.0, 4.0], [0.0, 0.0, 0.0])
        meshcat.SetProperty("/Grid", "visible", False)
        if self.teleop:
            print(f"teleop: in the Meshcat page, {', '.join(b[0] for b in BUTTONS)}")

    def check(self) -> str | None:
        """ "route_done" once the route follower has driven the route to its end."""
        return "route_done" if self._route_done() else None

    def _route_done(self) -> bool:
        if self._route is None:
            return False
        context = self._route.GetMyContextFromRoot(self.context)
        return self._route.GetOutputPort("done").Eval(context)[0] > 0.5

    def route_fraction(self) -> float:
        """Waypoints reached over the route's waypoints (1 for teleop or an empty route)."""
        if self._route is None or len(self.waypoints) == 0:
            return 1.0
        context = self._route.GetMyContextFromRoot(self.context)
        return self._route.waypoint_index(context) / len(self.waypoints)

    def occupancy_map(self) -> OccupancyMap:
        """The SLAM's map so far."""
        return self._slam.slam(self._slam.GetMyContextFromRoot(self.context)).map()

    def save_map(self, stem: Path | str) -> tuple[Path, Path]:
        """Writes the map as map_server's ``stem.pgm`` and ``stem.yaml``; returns their paths."""
        files = save_map(self.occupancy_map(), stem)
        self.map_files = [str(f) for f in files]
        return files

    def trajectories(self) -> dict[str, np.ndarray]:
        """``slam_paths`` of this run."""
        return slam_paths(self._slam, self._truth_log, self.context)

    def report(self) -> MappingReport:
        """Scores the run so far (see the module docstring)."""
        paths = self.trajectories()
        iou, known = map_scores(
            self.occupancy_map(), self.arena, self.robot, self.scenario.slam, self.world_map
        )
        slam_error = np.hypot(*(paths["slam"][:, :2] - paths["truth"][:, :2]).T)
        odom_error = np.hypot(*(paths["odometry"][:, :2] - paths["truth"][:, :2]).T)
        nan = math.nan
        return MappingReport(
            end=self.end,
            map_iou=iou,
            known_fraction=known,
            pose_rmse_m=float(np.sqrt(np.mean(slam_error**2))) if len(slam_error) else nan,
            final_pose_error_m=float(slam_error[-1]) if len(slam_error) else nan,
            final_yaw_error_deg=_yaw_error_deg(paths["slam"], paths["truth"]),
            odometry_final_error_m=float(odom_error[-1]) if len(odom_error) else nan,
            odometry_final_yaw_error_deg=_yaw_error_deg(paths["odometry"], paths["truth"]),
            scans=len(paths["time"]),
            route_fraction=self.route_fraction(),
            map_files=self.map_files,
            **run_times(self.context.get_time(), self.wall_time, self.seed),
        )

    def finish(self) -> MappingReport:
        """Saves the map at ``out`` when the run is complete (the route driven to its end, or a
        teleop run, which Ctrl-C ends), else beside it as ``NAME.partial``: a run stopped or
        failed early never replaces a map that was there; the ROS 2 log likewise. Returns the
        report."""
        complete = self.end == "route_done" or self.teleop
        try:
            self.files = save_run_map(self.occupancy_map(), self.out, complete, self.end)
            self.map_files = [str(f) for f in self.files]
        finally:  # the log is written whatever became of the map
            close_ros_log(
                self._log,
                complete=complete,
                seconds=self.context.get_time(),
                final_map=self.occupancy_map(),
            )
        return self.report()

    def summary(self, report: MappingReport) -> str:
        return (
            f"{self.arena_file.name}: ended by {report.end}, {report.scans} scans, map IoU "
            f"{report.map_iou:.3f}, known {100 * report.known_fraction:.1f} %, pose RMSE "
            f"{report.pose_rmse_m:.3f} m (final {report.final_pose_error_m:.3f} m, "
            f"{report.final_yaw_error_deg:.1f} deg; odometry "
            f"{report.odometry_final_error_m:.3f} m), {report.sim_time_s:.1f} s simulated at "
            f"{report.real_time_factor:.1f}x real time; map {self.files[1]}"
        )

    def error(self, report: MappingReport) -> str | None:
        if report.end == "duration" and not self.teleop:
            return (
                f"the route was not completed in {report.sim_time_s:.1f} s "
                f"({100 * report.route_fraction:.0f} % of its waypoints)"
            )
        return super().error(report)


def save_run_map(occupancy_map, out: Path, complete: bool, end: str) -> tuple[Path, Path]:
    """Writes a run's map as map_server files at ``out`` when the run is ``complete``, else
    beside it as ``NAME.partial`` and says so (ended by ``end``): a run stopped or failed early
    never replaces a map that was there. Returns the ``.pgm`` and ``.yaml`` paths."""
    if complete:
        return save_map(occupancy_map, out)
    files = save_map(occupancy_map, out.with_name(f"{out.name}.partial"))
    old = Path(f"{out}.yaml")
    kept = f"; {old} is kept as it was" if old.exists() else ""
    print(f"the run ended early ({end}): its partial map is {files[1]}{kept}")
    return files


def slam_paths(slam_system, truth_log, context) -> dict[str, np.ndarray]:
    """Per scan the live SLAM (``slam_system``, a ``SlamSystem``) processed: ``time`` (n,),
    and ``slam``, ``odometry``, ``truth`` (n, 3) poses ``[x, y, yaw]`` at that instant
    (``truth_log``: the true pose's ``VectorLogSink``; ``context``: the root context)."""
    history = slam_system.history(slam_system.GetMyContextFromRoot(context))
    log = truth_log.FindLog(context)
    times, samples = log.sample_times(), log.data()
    truth = np.zeros((len(history), 3))
    if len(times) and len(history):
        yaw = np.unwrap(samples[2])
        for k, series in enumerate((samples[0], samples[1], yaw)):
            truth[:, k] = np.interp(history[:, 0], times, series)
    return {
        "time": history[:, 0],
        "slam": history[:, 1:4],
        "odometry": history[:, 4:7],
        "truth": truth,
    }


def map_scores(occupancy_map, arena, robot, slam_config, world_map=None) -> tuple[float, float]:
    """``(map_iou, known_fraction)`` of ``occupancy_map`` against ``arena``'s ground truth at
    the lidar's height, in cells of the SLAM's resolution (a map's world, ``world_map``: its
    known cells are the place)."""
    truth_grid = arena_grid(arena, slam_config.resolution, height=robot.lidar.z)
    if world_map is not None:
        truth_grid = known_truth(truth_grid, world_map)
    return (
        occupancy_iou(occupancy_map, truth_grid, tolerance_cells=1),
        known_fraction(occupancy_map, truth_grid),
    )


def _yaw_error_deg(estimate: np.ndarray, truth: np.ndarray) -> float:
    if len(estimate) == 0:
        return math.nan
    return abs(math.degrees(wrap_angle(estimate[-1, 2] - truth[-1, 2])))


def route_file(scenario: MappingScenario, arena_file: Path) -> Path:
    """The scenario's route, else the arena's default route (``config/routes/<arena>.yaml``).

    Raises:
        ConfigError: the arena has no default route.
    """
    if scenario.route:
        return config_path(scenario.route)
    route = default_route_file(arena_file)
    if not route.is_file():
        raise ConfigError(f"{arena_file}: no default route ({route} is missing); give --route")
    return route


def make_run(inputs: Inputs, options, *, meshcat=None, realtime=False) -> MappingRun:
    """The recipe's run: the scenario's arena (or ``world``, a map's world, from ``start``) and
    route; ``options``: ``teleop`` (drive with
    the Meshcat keys instead of the route), ``out`` (the map files, default
    ``maps/<arena>``), ``record`` (keep the map's drawings in the recording), ``record_log``
    (a ROS 2 log, ``FILE.mcap``, of the run)."""
    scenario = inputs.scenario
    teleop = bool(recipe.option(options, "teleop", False))
    arena_file, arena, world_map = load_world(scenario)
    if world_map is not None and not teleop and not scenario.route:
        raise ConfigError(f"--world {arena_file}: a map's world has no default route; give --route")
    waypoints = [] if teleop else load_route(route_file(scenario, arena_file), arena).waypoints
    return MappingRun(
        scenario,
        inputs.robot,
        arena,
        waypoints,
        meshcat=meshcat,
        realtime=realtime,
        teleop=teleop,
        keyframes=recipe.option(options, "record", None) is not None,
        out=recipe.option(options, "out", None),
        arena_file=arena_file,
        world_map=world_map,
        log_writer=open_ros_log(options),
    )


RECIPE = AppRecipe(
    name="mapping",
    robot=ROBOT_FILE,
    scenario=InputFile(MappingScenario, default_scenario_file, check_mapping_scenario),
    seed_key="random_seed",
    make_run=make_run,
    flags=(
        ARENA_FLAG,
        WORLD_FLAG,
        START_FLAG,
        LIDAR_FLAG,
        recipe.file_flag(
            "--route", "route file", "route YAML (waypoints to drive)", key="route", group="drive"
        ),
        recipe.switch("--teleop", "drive with the Meshcat keys", "drive"),
        Flag(
            "--out",
            kwargs={
                "type": cli.output_file("map"),
                "help": f"map files to write, without extension (default {DEFAULT_OUT}/<arena>)",
            },
        ),
        RECORD_LOG_FLAG,
    ),
    cli=CliText(
        seed="random seed (odometry, lidar)",
        set_example="lidar.noise_sigma=0.02",
        duration="simulated seconds at most (default: enough for the route; teleop: until Ctrl-C)",
    ),
)
"""``python -m drake_sim.mapping``: robot ``config/turtlebot3.yaml``, scenario
``config/mapping_scenario.yaml``."""


def report_keys() -> tuple[str, ...]:
    """The keys of the run's report."""
    return tuple(f.name for f in dc.fields(MappingReport))
