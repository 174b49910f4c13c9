"""The lidar robot's navigation app (``python -m drake_sim.navigate``): its recipe, its run
(build the diagram, let AMCL localise and the navigator drive to each goal) and the report that
scores the run against the simulator's truth.

The report's keys are DESIGN.md's (``python -m drake_sim.navigate``). Per goal: ``reached``,
``position_error_m`` and ``yaw_error_deg`` (the true pose when the navigator reported it
arrived, against the goal; an arrival further than ``LOST_M`` beyond the goal tolerance is no
arrival), ``time_s`` (from the goal's start to its end) and
``path_length_m`` (the distance the robot drove for it, by its estimated pose).
``collisions`` counts the checks (every ``CHECK_PERIOD``) at which a robot geometry touched
anything but the floor;
``min_clearance_m`` is the smallest distance seen between the robot's geometry and the
arena's walls and obstacles. Localisation is converged from the first log sample whose AMCL
error is under ``CONVERGED_M`` and ``CONVERGED_DEG``; the error's mean and max are taken from
then on.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.geometry import Meshcat

from diagrams.lidar_robot import ROBOT_NAME
from diagrams.navigation import UNKNOWN_MAP_MARGIN, make_navigation_diagram
from diagrams.navigation_scenario import NavigationScenario
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.mcap_files import McapLogWriter
from drake_sim.base.planar import wrap_angle, wrap_angle_exact
from drake_sim.base.report import RunReport, run_times
from drake_sim.robots.turtlebot3_params import Turtlebot3Params
from drake_sim.runs.loop import SimulationRun
from drake_sim.runs.ros_recording import close_ros_log, dropped_on_error
from drake_sim.worlds.arena import Arena

CHECK_PERIOD = 0.1
"""s of simulated time between checks of the goals, contacts and clearance."""

LOST_M = 0.5
"""m: a goal the navigator says it reached, truly further than its ``xy_goal_tolerance`` plus
this, is not reached ("lost": the localisation settled on a wrong pose)."""
CONVERGED_M = 0.05
"""m: AMCL's position error under which (with ``CONVERGED_DEG``) it has converged."""

CONVERGED_DEG = 3.0
"""degrees: AMCL's heading error under which (with ``CONVERGED_M``) it has converged."""

ARENA_NAME, FLOOR_LINK = "arena", "ground"
"""The arena's model instance and its floor's link (``add_arena``): the floor is no collision."""

CLEARANCE_RANGE = 1.0
"""m: distances beyond this are not computed (``min_clearance_m`` is capped at it)."""

ENDS = ("done", "failed", "duration", "stopped", "sim_failed")
"""Why a run ended: every goal reached, a goal failed, the time ran out, Ctrl-C or SIGTERM,
the simulation failed."""


@dc.dataclass
class GoalReport:
    """One goal's outcome."""

    goal: list[float]  # [x, y, yaw_deg] as given.
    reached: bool
    position_error_m: float | None  # None when not reached.
    yaw_error_deg: float | None
    time_s: float  # s from the goal's start to its end.
    path_length_m: float  # m the robot drove for it.
    message: str  # The navigator's last word on it ("arrived", "unreachable", ...).


@dc.dataclass(kw_only=True)
class NavigationReport(RunReport):
    """What a navigation run did (DESIGN.md, ``python -m drake_sim.navigate``)."""

    end: str  # One of ENDS.
    goals: list[GoalReport]
    reached_all: bool
    collisions: int
    min_clearance_m: float
    localization_error_mean_m: float | None
    localization_error_max_m: float | None
    converged_after_s: float | None  # None: never converged.


class NavigationHandle:
    """A goal sent with ``NavigationRun.send_goal``, like an action goal handle: ``done()``,
    ``result()``, ``cancel()`` and ``distance_left_m``. It does not advance the simulation."""

    def __init__(self, run: "NavigationRun", index: int):
        self._run = run
        self._index = index  # its place among the navigator's finished goals

    def done(self) -> bool:
        """True once the navigator has finished with the goal (reached, failed, cancelled)."""
        return len(self._run.results) > self._index

    def result(self) -> GoalReport | None:
        """The goal's report once ``done()``, else None."""
        return self._run.results[self._index] if self.done() else None

    def cancel(self) -> None:
        """Stops the robot and ends the goal (not reached, "canceled")."""
        if not self.done():
            self._run.navigator.cancel(self._run.navigator.GetMyContextFromRoot(self._run.context))

    @property
    def distance_left_m(self) -> float:
        """m along the current global path (0 when done)."""
        return 0.0 if self.done() else float(self._run.status().path_length_m)


class NavigationRun(SimulationRun):
    """Builds the navigation diagram and a simulator for one run. ``run`` drives the goals
    given at construction; ``navigate_to`` sends one more and waits for it.

    AMCL starts from ``initial_estimate`` (``[x, y, yaw]``, with ``initial_covariance`` or
    the AMCL config's), by default the true ``start``; with ``global_localization`` from
    particles over the whole map instead. With no ``occupancy_map`` there is no AMCL: the
    robot localises with the live SLAM (or its odometry) and plans on what its lidar has seen
    (``diagrams.navigation``; ``map_extent``: more points its map covers, ``map_margin`` how
    far beyond). The scenario's ``random_seed`` seeds the odometry errors, the lidar noise and
    AMCL. With a ``log_writer`` the run is written as a ROS 2 log, closed by
    ``finish`` (``drake_sim.runs.ros_recording``).
    """

    check_period = CHECK_PERIOD
    failed_end = "sim_failed"
    doing = "navigating"

    def __init__(
        self,
        scenario: NavigationScenario,
        robot: Turtlebot3Params,
        world: Arena,
        occupancy_map: OccupancyMap | None,
        *,
        start,
        goals=(),
        initial_estimate=None,
        initial_covariance=None,
        global_localization: bool = False,
        meshcat: Meshcat | None = None,
        realtime: bool = False,
        log_writer: McapLogWriter | None = None,
        map_extent=(),
        map_margin: float = UNKNOWN_MAP_MARGIN,
    ):
        self.scenario = scenario
        self.robot = robot
        self.goals = [np.asarray(g, dtype=float) for g in goals]  # [x, y, yaw rad]
        if initial_estimate is None and not global_localization:
            initial_estimate = start  # RViz's "2D Pose Estimate" on the robot
        self._log = log_writer
        with dropped_on_error(log_writer):
            diagram = make_navigation_diagram(
                scenario,
                robot,
                world,
                occupancy_map,
                start=start,
                initial_estimate=initial_estimate,
                initial_covariance=initial_covariance,
                global_localization=global_localization,
                goals=self.goals,
                meshcat=meshcat,
                log_writer=log_writer,
                map_extent=map_extent,
                map_margin=map_margin,
            )
            super().__init__(diagram, scenario.random_seed, realtime=realtime)
        self.navigator = self.diagram.GetSubsystemByName("navigator")
        self.amcl = None if occupancy_map is None else self.diagram.GetSubsystemByName("amcl")
        self._plant = self.diagram.GetSubsystemByName("plant")
        self._scene_graph = self.diagram.GetSubsystemByName("scene_graph")
        self._robot_geometries = self._geometries_of(ROBOT_NAME)
        self._floor = self._geometries_of(ARENA_NAME, FLOOR_LINK)
        self.collisions = 0
        self.min_clearance = CLEARANCE_RANGE
        self.results: list[GoalReport] = []
        self._start_xy = np.asarray(start, dtype=float)[:2]

    # --- what the caller drives ----------------------------------------------------------

    def goal_timeout(self, goal, start_xy) -> float:
        """s allowed for ``goal`` from ``start_xy``: the straight distance over the top speed,
        times the scenario's factor, plus its margin (a path is rarely straight; the margin
        covers it, the turns and the recoveries)."""
        speed = self.scenario.navigator.controller.max_vel_x
        distance = math.dist(goal[:2], start_xy)
        return self.scenario.goal_time_factor * distance / speed + self.scenario.goal_time_margin

    def default_duration(self, *, viewer: bool = False) -> float:
        """Simulated s for every goal in turn (``goal_timeout`` each, from the one before)."""
        total, xy = 0.0, self._start_xy
        for goal in self.goals:
            total += self.goal_timeout(goal, xy)
            xy = goal[:2]
        return max(total, self.scenario.goal_time_margin)

    def status(self):
        """The navigator's ``NavigationStatus`` now."""
        return self.diagram.GetOutputPort("navigation_status").Eval(self.context)

    def send_goal(self, goal) -> "NavigationHandle":
        """Drives to ``goal`` ``[x, y, yaw]`` (m, m, rad) from now on, preempting the current
        goal (RViz's "2D Nav Goal"); returns its handle. The run moves on with ``advance``."""
        status = self.status()
        active = status.state not in ("idle", "arrived", "failed")
        navigator_context = self.navigator.GetMyContextFromRoot(self.context)
        self.navigator.set_goal(navigator_context, np.asarray(goal, dtype=float))
        self.goals.append(np.asarray(goal, dtype=float))
        return NavigationHandle(self, len(status.results) + int(active))

    def navigate_to(self, goal, timeout: float | None = None) -> GoalReport:
        """Drives to ``goal`` ``[x, y, yaw]`` and returns its ``GoalReport`` once the navigator
        has finished with it, or after ``timeout`` simulated seconds (default
        ``goal_timeout``; the goal is then cancelled and reported not reached)."""
        pose = self.diagram.GetOutputPort("estimated_pose").Eval(self.context)
        handle = self.send_goal(goal)
        limit = self.goal_timeout(np.asarray(goal, dtype=float), pose[:2])
        deadline = self.context.get_time() + (limit if timeout is None else timeout)
        while not handle.done() and self.context.get_time() < deadline:
            self.advance(CHECK_PERIOD)
        if not handle.done():
            handle.cancel()
            self.advance(CHECK_PERIOD)
        return handle.result()

    def set_pose_estimate(self, pose, covariance=None) -> None:
        """Restarts AMCL around ``pose`` ``[x, y, yaw]`` (RViz's "2D Pose Estimate"), with
        ``covariance`` (3 x 3) or the AMCL config's initial one."""
        config = self.scenario.amcl
        covariance = config.initial_covariance() if covariance is None else covariance
        amcl_context = self._amcl_context()
        self.amcl.set_pose(amcl_context, np.asarray(pose, dtype=float), np.asarray(covariance))

    def _amcl_context(self):
        if self.amcl is None:
            raise ConfigError("no AMCL without a map: the live SLAM (or odometry) localises")
        return self.amcl.GetMyContextFromRoot(self.context)

    def start_global_localization(self) -> None:
        """Spreads AMCL's particles over the map's free space (ROS's global_localization)."""
        self.amcl.start_global_localization(self._amcl_context())

    # --- bookkeeping ---------------------------------------------------------------------

    def check(self) -> str | None:
        """Records the goals the navigator has finished and the contacts; "done" once every
        goal is reached, "failed" once one is not."""
        truth = self.diagram.GetOutputPort("true_pose").Eval(self.context)
        self._check_contacts()
        status = self.status()
        while len(self.results) < len(status.results):
            self._record_goal(status.results[len(self.results)], truth)
        if self.goals and len(self.results) >= len(self.goals):
            return "done" if all(r.reached for r in self.results) else "failed"
        if self.results and not self.results[-1].reached:
            return "failed"
        return None

    def _record_goal(self, result, truth) -> None:
        """A goal the navigator has finished, scored against the true pose now (checked every
        ``CHECK_PERIOD``: the robot has barely moved since it arrived)."""
        goal = np.asarray(result.goal, dtype=float)
        error = math.dist(truth[:2], goal[:2])
        yaw_error = abs(math.degrees(wrap_angle_exact(truth[2] - goal[2])))
        reached, message = bool(result.reached), "arrived" if result.reached else result.message
        if reached and error > self.scenario.navigator.controller.xy_goal_tolerance + LOST_M:
            reached = False
            message = f"arrived by its own estimate only, {error:.2f} m from the goal (lost)"
        self.results.append(
            GoalReport(
                goal=[float(goal[0]), float(goal[1]), math.degrees(goal[2])],
                reached=reached,
                position_error_m=error if reached else None,
                yaw_error_deg=yaw_error if reached else None,
                time_s=float(result.time_s),
                path_length_m=float(result.driven_m),
                message=str(message),
            )
        )

    def _geometries_of(self, model_name: str, body_name: str | None = None) -> set:
        """The geometry ids of a model instance's bodies (or of its body ``body_name``)."""
        instance = self._plant.GetModelInstanceByName(model_name)
        inspector = self._scene_graph.model_inspector()
        ids = set()
        for body_index in self._plant.GetBodyIndices(instance):
            if body_name is not None and self._plant.get_body(body_index).name() != body_name:
                continue
            frame = self._plant.GetBodyFrameIdOrThrow(body_index)
            ids.update(inspector.GetGeometries(frame))
        return ids

    def _check_contacts(self) -> None:
        sg_context = self._scene_graph.GetMyContextFromRoot(self.context)
        query = self._scene_graph.get_query_output_port().Eval(sg_context)
        touching = False
        for pair in query.ComputeSignedDistancePairwiseClosestPoints(CLEARANCE_RANGE):
            a, b = pair.id_A, pair.id_B
            if (a in self._robot_geometries) == (b in self._robot_geometries):
                continue
            if (b if a in self._robot_geometries else a) in self._floor:
                continue
            self.min_clearance = min(self.min_clearance, pair.distance)
            touching |= pair.distance <= 0.0
        self.collisions += int(touching)

    # --- the report ----------------------------------------------------------------------

    def log_complete(self) -> bool:
        """Whether the run went to its end (its log is then complete): not stopped, not
        failed."""
        return self.end not in ("stopped", self.failed_end)

    def finish(self) -> NavigationReport:
        """Closes the ROS 2 log (if any: ``NAME.partial.mcap`` unless ``log_complete``, with
        the live SLAM's final map when it has one) and returns the report."""
        final_map = None
        if self._log is not None and self.diagram.HasSubsystemNamed("slam"):
            slam = self.diagram.GetSubsystemByName("slam")
            final_map = slam.slam(slam.GetMyContextFromRoot(self.context)).map()
        close_ros_log(
            self._log,
            complete=self.log_complete(),
            seconds=self.context.get_time(),
            final_map=final_map,
        )
        return self.report()

    def localization_errors(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(times, position errors m, heading errors deg)`` of AMCL against the truth, at
        every log sample."""
        truth = self.diagram.GetSubsystemByName("log_true_pose").FindLog(self.context)
        estimate = self.diagram.GetSubsystemByName("log_estimated_pose").FindLog(self.context)
        n = min(truth.num_samples(), estimate.num_samples())
        a, b = truth.data()[:, :n], estimate.data()[:, :n]
        position = np.hypot(a[0] - b[0], a[1] - b[1])
        heading = np.degrees(np.abs(wrap_angle(b[2] - a[2])))
        return truth.sample_times()[:n], position, heading

    def report(self) -> NavigationReport:
        """Scores the run so far (see the module docstring)."""
        times, position, heading = self.localization_errors()
        ok = np.nonzero((position < CONVERGED_M) & (heading < CONVERGED_DEG))[0]
        converged = float(times[ok[0]]) if len(ok) else None
        after = position[ok[0] :] if len(ok) else np.zeros(0)
        return NavigationReport(
            end=self.end,
            goals=self.results,
            reached_all=bool(self.goals)
            and len(self.results) == len(self.goals)
            and all(r.reached for r in self.results),
            collisions=self.collisions,
            min_clearance_m=float(self.min_clearance),
            localization_error_mean_m=float(after.mean()) if len(after) else None,
            localization_error_max_m=float(after.max()) if len(after) else None,
            converged_after_s=converged,
            **run_times(self.context.get_time(), self.wall_time, self.seed),
        )
