"""One mapping run of the lidar robot, for ``python -m drake_sim.mapping``, notebooks and
benchmarks: build the diagram, drive the route (or teleop) until it is done, save the map and
score it against the arena's ground truth.

The report's keys are DESIGN.md's (``python -m drake_sim.mapping``): ``map_iou`` compares the
map's occupied cells with the arena's at the lidar's scan height, one cell of tolerance
(``occupancy_iou``); ``known_fraction`` is the share of the arena's cells the map knows;
``pose_rmse_m`` is the RMS distance between the SLAM pose at each scan and the true pose at
that instant; ``odometry_final_error_m`` is the raw wheel odometry's final error, to show what
the SLAM corrected.
"""

import dataclasses as dc
import math
import time
from pathlib import Path

import numpy as np
from pydrake.geometry import Meshcat

from diagrams.mapping import make_mapping_diagram
from diagrams.mapping_scenario import MappingScenario
from drake_sim.base import cli
from drake_sim.base.map_files import OccupancyMap, save_map
from drake_sim.base.report import RunReport, run_times
from drake_sim.base.simulation import start_simulator
from drake_sim.robots.turtlebot3_params import Turtlebot3Params
from drake_sim.systems.estimation.occupancy_grid import known_fraction, occupancy_iou
from drake_sim.worlds.arena import Arena, arena_grid

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


class MappingRun:
    """Builds the mapping diagram and a simulator for one run; ``run`` drives, ``save_map``
    writes map_server files and ``report`` scores the map and the poses. ``keyframes``: keep
    the growing map and the scans in a Meshcat recording (``make_mapping_diagram``)."""

    def __init__(
        self,
        scenario: MappingScenario,
        robot: Turtlebot3Params,
        arena: Arena,
        waypoints,
        *,
        seed: int | None = None,
        meshcat: Meshcat | None = None,
        realtime: bool = False,
        teleop: bool = False,
        keyframes: bool = False,
    ):
        self.scenario = scenario
        self.robot = robot
        self.arena = arena
        self.waypoints = np.asarray(waypoints, dtype=float).reshape(-1, 2)
        self.teleop = teleop
        self.seed = scenario.random_seed if seed is None else seed
        scenario = dc.replace(scenario, random_seed=self.seed)
        self.diagram = make_mapping_diagram(
            scenario,
            robot,
            arena,
            self.waypoints,
            meshcat=meshcat,
            teleop=teleop,
            keyframes=keyframes,
        )
        self.simulator, self.context = start_simulator(
            self.diagram, self.seed, lambda s: s.set_target_realtime_rate(1.0 if realtime else 0.0)
        )
        self._slam = self.diagram.GetSubsystemByName("slam")
        self._truth_log = self.diagram.GetSubsystemByName("log_true_pose")
        self._route = self.diagram.GetSubsystemByName("route_follower") if not teleop else None
        self.end = "duration"
        self.failure = ""
        self.wall_time = 0.0
        self.map_files: list[str] | None = None

    def default_duration(self, *, viewer: bool = False) -> float:
        """Simulated seconds for the route at the follower's speed, with the scenario's factor
        and margin; teleop runs until Ctrl-C with a viewer."""
        if self.teleop:
            return math.inf if viewer else self.scenario.duration_margin
        start = self.arena.start_pose()
        length = route_length(start, self.waypoints)
        speed = self.scenario.route_follower.speed
        return length / speed * self.scenario.duration_factor + self.scenario.duration_margin

    def run(self, duration: float) -> str:
        """Simulates until ``duration`` (s) or the route's end; returns why it ended (one of
        ``ENDS``, also in ``end``). A simulation error ends it as "failed", its first line kept
        in ``failure``."""
        start = time.perf_counter()
        try:
            t = self.context.get_time()
            while t < duration and self.end == "duration":
                t = min(duration, t + CHECK_PERIOD)
                self.simulator.AdvanceTo(t)
                if self._route_done():
                    self.end = "route_done"
        except BaseException as e:
            self.end, self.failure = cli.run_ending(e)
        finally:
            self.wall_time += time.perf_counter() - start
        return self.end

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
        """Per processed scan: ``time`` (n,), and ``slam``, ``odometry``, ``truth`` (n, 3)
        poses ``[x, y, yaw]`` at that instant."""
        history = self._slam.history(self._slam.GetMyContextFromRoot(self.context))
        log = self._truth_log.FindLog(self.context)
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

    def report(self) -> MappingReport:
        """Scores the run so far (see the module docstring)."""
        paths = self.trajectories()
        truth_grid = arena_grid(
            self.arena, self.scenario.slam.resolution, height=self.robot.lidar.z
        )
        occupancy_map = self.occupancy_map()
        slam_error = np.hypot(*(paths["slam"][:, :2] - paths["truth"][:, :2]).T)
        odom_error = np.hypot(*(paths["odometry"][:, :2] - paths["truth"][:, :2]).T)
        nan = math.nan
        return MappingReport(
            end=self.end,
            map_iou=occupancy_iou(occupancy_map, truth_grid, tolerance_cells=1),
            known_fraction=known_fraction(occupancy_map, truth_grid),
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


def _yaw_error_deg(estimate: np.ndarray, truth: np.ndarray) -> float:
    if len(estimate) == 0:
        return math.nan
    error = (estimate[-1, 2] - truth[-1, 2] + math.pi) % (2 * math.pi) - math.pi
    return abs(math.degrees(error))
