"""The explore app's recipe and run (``python -m drake_sim.explore``): the lidar robot maps a
place it knows nothing of, by itself, as explore_lite does on top of a SLAM and move_base.

The robot starts at the arena's start (or ``--start`` in a map's world) with the live SLAM
and the navigator of ``navigate`` without a map (costmaps filled from the lidar, the global
planner through unknown space). Every ``exploration.replan_period`` the run looks for frontiers
on the SLAM's map (``drake_sim.navigation.frontiers``) and sends the cheapest one's goal to the
navigator, keeping the current goal while its frontier is still there and the robot gets
closer. A goal the navigator fails, or one reached without its frontier going away, or one
it gets no closer to for ``exploration.progress_timeout``, goes on the blacklist. The run ends
"explored" when no frontier is left that the robot can reach, or at ``time_limit``; the map is
saved as map_server files (``--out``, default ``maps/<place>_explored``; beside it as
``NAME.partial`` when the run did not finish exploring). "Explored" needs no frontier at two
choices in a row (a frontier can vanish for a moment as the map is redrawn) and a map with
free cells (not before the first scan).

The report's keys (``docs/exploration.md``): ``end`` ("explored",
"time_limit", "stopped", "sim_failed"), ``known_fraction`` and ``map_iou`` (as mapping reports
them), ``pose_rmse_m`` (the SLAM's position against the truth at each scan), ``distance_m``
(the true path's length), ``collisions`` and ``min_clearance_m`` (as navigate's),
``frontiers_visited`` (goals reached), the run's times and the map files.
"""

import dataclasses as dc
import math
from pathlib import Path

import numpy as np
from pydrake.geometry import Rgba, Sphere
from pydrake.math import RigidTransform
from pydrake.perception import BaseField, Fields, PointCloud

from diagrams.explore_scenario import (
    ExploreScenario,
    check_explore_scenario,
    default_scenario_file,
    load_explore_scenario,
)
from drake_sim.base import cli
from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.report import RunReport, run_times
from drake_sim.navigation.frontiers import Frontier, find_frontiers
from drake_sim.runs import recipe
from drake_sim.runs.lidar_robot import (
    ARENA_FLAG,
    LIDAR_FLAG,
    ROBOT_FILE,
    START_FLAG,
    WORLD_FLAG,
    load_world,
)
from drake_sim.runs.mapping import map_scores, save_run_map, slam_paths
from drake_sim.runs.navigation import NavigationRun
from drake_sim.runs.recipe import AppRecipe, CliText, Flag, InputFile, Inputs
from drake_sim.runs.ros_recording import RECORD_LOG_FLAG, open_ros_log

DEFAULT_OUT = "maps"
"""The folder of the map files when ``--out`` is not given: ``maps/<place>_explored``."""

PLACE_MARGIN = 1.0
"""m: how far the map the robot starts with (all unknown) reaches beyond the place's bounds:
a canvas (the SLAM's is at least its ``map_size``), not knowledge of what is there. Twenty
metres, ``navigate``'s margin for goals it has not seen, made the warehouse's explorer copy
52 m maps in every step, and run at 2.5x real time."""

KEEP_RADIUS = 0.5
"""m: a frontier whose goal is this close to the current one is the same frontier (its goal
moves as it recedes): the current goal is kept."""

PROGRESS_STEP = 0.1
"""m: getting this much closer to the goal (along the navigator's path) counts as progress."""

ENDS = ("explored", "time_limit", "stopped", "sim_failed")
"""Why a run ended: no reachable frontier left, the time limit, Ctrl-C or SIGTERM, the
simulation failed."""


@dc.dataclass(kw_only=True)
class ExploreReport(RunReport):
    """What an exploring run did (``docs/exploration.md``)."""

    end: str  # One of ENDS.
    known_fraction: float  # The place's free and occupied cells that the map knows.
    map_iou: float  # Occupied cells against the ground truth's, one cell of tolerance.
    pose_rmse_m: float  # SLAM position against the truth at each scan, RMS.
    distance_m: float  # m the robot truly drove.
    collisions: int  # Checks at which the robot touched anything but the floor.
    min_clearance_m: float  # Least distance between the robot and the walls or obstacles.
    frontiers_visited: int  # Frontier goals reached.
    frontiers_left: int  # Frontiers reachable and not blacklisted when the run ended.
    map_files: list[str] | None = None  # The .pgm and .yaml written.


class ExploreRun(NavigationRun):
    """A navigation run with no map whose goals are the frontiers (module docstring)."""

    doing = "exploring"

    def __init__(
        self,
        scenario: ExploreScenario,
        robot,
        world,
        *,
        start,
        place: Path,
        world_map: OccupancyMap | None = None,
        out: Path | str | None = None,
        **kw,
    ):
        lower, upper = np.array(world.size) / -2.0, np.array(world.size) / 2.0
        corners = [lower, upper] if world_map is None else _map_corners(world_map)
        super().__init__(
            scenario, robot, world, None, start=start, map_extent=corners,
            map_margin=PLACE_MARGIN, **kw,
        )  # fmt: skip
        self.world = world
        self.world_map = world_map
        self.place = Path(place)
        self.out = (
            Path(out) if out is not None else Path(DEFAULT_OUT) / f"{self.place.stem}_explored"
        )
        self.config = scenario.exploration
        self._slam = self.diagram.GetSubsystemByName("slam")
        self._truth_log = self.diagram.GetSubsystemByName("log_true_pose")
        self.blacklist: list[np.ndarray] = []
        self.frontiers: list[Frontier] = []
        self.frontiers_visited = 0
        self.target: np.ndarray | None = None  # the goal sent
        self._chosen: Frontier | None = None  # the frontier it was chosen for
        self._handle = None
        self._next_choice = 0.0
        self._empty = 0  # choices in a row that found no frontier
        self._closest = math.inf  # m left to the goal, the least so far
        self._closer_at = 0.0  # s: when the robot last got PROGRESS_STEP closer
        self._meshcat = kw.get("meshcat")
        self.map_files: list[str] | None = None

    def default_duration(self, *, viewer: bool = False) -> float:
        return self.scenario.time_limit

    def set_up_viewer(self, meshcat) -> None:
        """Looks down on the whole place from above its south side; hides the grid."""
        width, depth = np.array(self.world.size, dtype=float)
        centre = np.zeros(2) if self.world_map is None else np.mean(_map_corners(self.world_map), 0)
        if self.world_map is not None:
            width, depth = self.world_map.width_m, self.world_map.height_m
        meshcat.SetCameraPose(
            [centre[0], centre[1] - 0.6 * depth, 0.9 * max(width, depth)], [*centre, 0.0]
        )
        meshcat.SetProperty("/Grid", "visible", False)

    def occupancy_map(self) -> OccupancyMap:
        """The SLAM's map so far."""
        return self._slam.slam(self._slam.GetMyContextFromRoot(self.context)).map()

    def check(self) -> str | None:
        """Records contacts and finished goals; every ``replan_period`` chooses the goal;
        "explored" once no reachable frontier is left."""
        self._check_contacts()
        status = self.status()
        while len(self.results) < len(status.results):
            result = status.results[len(self.results)]
            self.results.append(result)
            self.frontiers_visited += int(bool(result.reached))
            if result.message not in ("preempted", "canceled") and self._chosen is not None:
                # Reached (what is left of its frontier is not seen from there) or failed.
                self._give_up()
        now = self.context.get_time()
        if now < self._next_choice:
            return None
        self._next_choice = now + self.config.replan_period
        return self._choose(now)

    def _choose(self, now: float) -> str | None:
        pose = self.diagram.GetOutputPort("estimated_pose").Eval(self.context)
        grid = self.occupancy_map()
        self.frontiers = find_frontiers(grid, pose[:2], self.config, self.blacklist)
        ended = self._steer(pose, now, mapped=bool(grid.free().any()))
        self._draw()
        return ended

    def _steer(self, pose, now: float, mapped: bool) -> str | None:
        """Keeps the goal, or sends the cheapest frontier's; "explored" when none is left
        (``mapped``: the map has free cells, the first scan is in)."""
        active = self._handle is not None and not self._handle.done()
        if not self.frontiers:
            # Explored when no frontier is left at two choices in a row and the map has free
            # cells (the first scan is in); a goal still being driven to has lost its frontier.
            if active:
                self._handle.cancel()
            self.target = None
            self._empty += 1
            explored = self._empty >= 2 and mapped
            return "explored" if explored else None
        self._empty = 0
        if active:
            left = self._handle.distance_left_m
            if left < self._closest - PROGRESS_STEP:
                self._closest, self._closer_at = left, now
            if now - self._closer_at > self.config.progress_timeout:
                self._give_up()
                self._handle.cancel()
            elif any(np.linalg.norm(f.goal - self.target) < KEEP_RADIUS for f in self.frontiers):
                return None
            else:
                self._handle.cancel()  # its frontier is gone: on to the next
        self._chosen = self.frontiers[0]
        goal = self._chosen.goal
        heading = math.atan2(goal[1] - pose[1], goal[0] - pose[0])
        self.target = goal.copy()
        self._handle = self.send_goal([goal[0], goal[1], heading])
        self._closest, self._closer_at = math.inf, now
        return None

    def _give_up(self) -> None:
        """Blacklists what the current goal was to reveal (``Frontier.seen_from_goal``)."""
        self.blacklist.extend(self._chosen.seen_from_goal(self.config))
        self._chosen = None

    def _draw(self) -> None:
        """The frontiers (orange dots) and the goal being driven to (a green ball) in Meshcat."""
        if self._meshcat is None:
            return
        cells = [f.cells for f in self.frontiers]
        xy = np.vstack(cells) if cells else np.zeros((0, 2))
        cloud = PointCloud(len(xy), Fields(BaseField.kXYZs))
        cloud.mutable_xyzs()[:] = np.vstack([xy.T, np.full(len(xy), 0.03)])
        self._meshcat.SetObject("/exploration/frontiers", cloud, 0.05, Rgba(1.0, 0.5, 0.0, 1.0))
        self._meshcat.SetProperty("/exploration/goal", "visible", self.target is not None)
        if self.target is not None:
            self._meshcat.SetObject("/exploration/goal", Sphere(0.08), Rgba(0.1, 0.8, 0.2, 0.9))
            self._meshcat.SetTransform("/exploration/goal", RigidTransform([*self.target, 0.08]))

    # --- the report ----------------------------------------------------------------------

    def finish(self) -> ExploreReport:
        """Saves the map at ``out`` when the place was explored, else beside it as
        ``NAME.partial`` (a map that was there is kept), then closes the ROS 2 log and
        returns the report."""
        complete = self.end == "explored"
        try:
            files = save_run_map(self.occupancy_map(), self.out, complete, self._end())
            self.map_files = [str(f) for f in files]
        finally:  # the log is closed whatever became of the map
            report = super().finish()
        return report

    def log_complete(self) -> bool:
        return self.end == "explored"

    def _end(self) -> str:
        return "time_limit" if self.end == "duration" else self.end

    def report(self) -> ExploreReport:
        """Scores the run so far (module docstring)."""
        paths = slam_paths(self._slam, self._truth_log, self.context)
        iou, known = map_scores(
            self.occupancy_map(), self.world, self.robot, self.scenario.slam, self.world_map
        )
        error = np.hypot(*(paths["slam"][:, :2] - paths["truth"][:, :2]).T)
        truth = self._truth_log.FindLog(self.context).data()
        return ExploreReport(
            end=self._end(),
            known_fraction=known,
            map_iou=iou,
            pose_rmse_m=float(np.sqrt(np.mean(error**2))) if len(error) else math.nan,
            distance_m=float(np.sum(np.hypot(*np.diff(truth[:2], axis=1)))),
            collisions=self.collisions,
            min_clearance_m=float(self.min_clearance),
            frontiers_visited=self.frontiers_visited,
            frontiers_left=len(self.frontiers),
            map_files=self.map_files,
            **run_times(self.context.get_time(), self.wall_time, self.seed),
        )

    def summary(self, report: ExploreReport) -> str:
        files = f"; map {self.map_files[1]}" if self.map_files else ""
        return (
            f"{self.place.name}: ended by {report.end}, known {100 * report.known_fraction:.1f} "
            f"%, map IoU {report.map_iou:.3f}, pose RMSE {report.pose_rmse_m:.3f} m, "
            f"{report.frontiers_visited} frontiers visited, {report.distance_m:.1f} m driven, "
            f"collisions {report.collisions}, min clearance {report.min_clearance_m:.3f} m; "
            f"{report.sim_time_s:.1f} s simulated at {report.real_time_factor:.1f}x real time"
            f"{files}"
        )

    def error(self, report: ExploreReport) -> str | None:
        """One line when the place was not explored (None when it was, or stopped)."""
        if report.end in ("explored", "stopped"):
            return None
        if report.end == "sim_failed":
            return f"simulation failed at t = {report.sim_time_s:.3f} s: {self.failure}"
        return (
            f"not explored in the time limit ({report.sim_time_s:.0f} s): known "
            f"{100 * report.known_fraction:.1f} %, {report.frontiers_left} frontiers left"
        )


def _map_corners(world_map: OccupancyMap) -> list[np.ndarray]:
    rows, cols = world_map.shape
    corners = np.array([[0, 0], [0, cols], [rows, 0], [rows, cols]], dtype=float)
    return list(world_map.to_world(corners))


def make_run(inputs: Inputs, options, *, meshcat=None, realtime=False) -> ExploreRun:
    """The recipe's run: the scenario's arena (or its ``world``, a map's world, from its
    ``start``); ``options``: ``out`` (the map files, default ``maps/<place>_explored``),
    ``record_log`` (a ROS 2 log, ``FILE.mcap``, of the run)."""
    scenario = inputs.scenario
    place, arena, world_map = load_world(scenario)
    return ExploreRun(
        scenario,
        inputs.robot,
        arena,
        start=np.array(arena.start_pose()),
        place=place,
        world_map=world_map,
        out=recipe.option(options, "out", None),
        meshcat=meshcat,
        realtime=realtime,
        log_writer=open_ros_log(options),
    )


RECIPE = AppRecipe(
    name="explore",
    robot=ROBOT_FILE,
    scenario=InputFile(
        ExploreScenario,
        default_scenario_file,
        check_explore_scenario,
        load_overridden=load_explore_scenario,
    ),
    seed_key="random_seed",
    make_run=make_run,
    flags=(
        ARENA_FLAG,
        WORLD_FLAG,
        START_FLAG,
        LIDAR_FLAG,
        Flag(
            "--time-limit",
            key="time_limit",
            kwargs={"type": cli.positive_float, "help": "simulated seconds at most (default 600)"},
        ),
        Flag(
            "--out",
            kwargs={
                "type": cli.output_file("map"),
                "help": f"map files to write, without extension (default {DEFAULT_OUT}/"
                "<place>_explored)",
            },
        ),
        RECORD_LOG_FLAG,
    ),
    cli=CliText(seed="random seed (odometry, lidar)", set_example="exploration.gain_scale=1.0"),
)
"""``python -m drake_sim.explore``: robot ``config/turtlebot3.yaml``, scenario
``config/explore_scenario.yaml``."""


def report_keys() -> tuple[str, ...]:
    """The keys of the run's report (a sweep's row)."""
    return tuple(f.name for f in dc.fields(ExploreReport))
