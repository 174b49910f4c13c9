"""Run Wall-E on a course and summarise what it did (the report of ``python -m drake_sim.walle``).

A run ends when its duration is reached, a closed course's lap is complete, an open course's
end is reached (within ``scenario.finish_margin``: the camera loses the line's end before the
robot is over it), the robot fell, or the line follower gave up searching for the line.
"""

import dataclasses as dc
import math
import time

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import ApplySimulatorConfig

from diagrams.walle import expected_duration, make_walle_course_diagram
from diagrams.walle_balance import ROBOT_NAME, walle_track
from diagrams.walle_scenario import WalleScenario
from drake_sim.base import cli
from drake_sim.base.report import RunReport, run_times
from drake_sim.base.simulation import start_simulator
from drake_sim.robots.walle import BODY_LINK
from drake_sim.robots.walle_params import WalleParams
from drake_sim.systems.axle import axle_yaw_and_pitch
from drake_sim.systems.control.line_follower import STOPPED
from drake_sim.worlds.course import Course, centreline

CHECK_PERIOD = 0.05  # s simulated between checks of the end conditions.
BALANCE_DURATION = 10.0  # s, the default headless run in balance mode.
ENDS = ("duration", "lap", "finish", "fell", "lost_line", "stopped", "failed")
"""Why a run ended: its duration reached, a loop's lap or an open course completed, the robot
fell, the follower gave up searching for the line, a user stop, or a simulation error."""


@dc.dataclass(kw_only=True)
class WalleReport(RunReport):
    """What a run did. Distances in m, times in s, angles in degrees (docs/walle.md)."""

    fell: bool  # The lean passed the balance controller's fallen pitch.
    time_upright_s: float  # Until the fall, or the whole run.
    max_abs_pitch_deg: float  # Of the true lean, over the run.
    course_fraction: float  # Share of the course passed in order, 0 to 1.
    laps: int  # Completed laps (a finished open course counts one).
    lap_time_s: float | None  # When the first lap (or the open course) was completed.
    mean_line_offset_m: float  # Mean distance of the axle's midpoint from the centreline.
    max_line_offset_m: float  # Largest such distance.
    mode: str
    progress_m: float  # Arc length passed in order (a loop's laps add up).
    lost_line: bool  # The follower gave up searching for the line (mode STOPPED).
    end: str  # Why the run ended: one of ENDS.


class WalleCourseRun:
    """Wall-E's course diagram and simulator, ready to run.

    Args:
        scenario: the mode, sensors and controllers.
        robot: the robot's dimensions.
        course: the course (checked).
        seed: the random seed (IMU noise); ``scenario.walle.random_seed`` when None.
        meshcat: draw there, or None to run headless.
        realtime: pace the run with ``scenario.walle.simulator``; by default when there is a
            ``meshcat``, otherwise it runs flat out.
        teleop: drive with Meshcat keys in balance mode (needs ``meshcat``).
    """

    def __init__(
        self,
        scenario: WalleScenario,
        robot: WalleParams,
        course: Course,
        *,
        seed: int | None = None,
        meshcat: Meshcat | None = None,
        realtime: bool | None = None,
        teleop: bool = False,
    ):
        self.scenario, self.robot = scenario, robot
        self.seed = scenario.walle.random_seed if seed is None else seed
        self.line = centreline(course)
        self.diagram = make_walle_course_diagram(
            scenario, robot, course, meshcat=meshcat, teleop=teleop
        )
        if realtime is None:
            realtime = meshcat is not None
        config = scenario.walle.simulator
        self.simulator, self.context = start_simulator(
            self.diagram,
            self.seed,
            (lambda s: ApplySimulatorConfig(config, s)) if realtime else None,
        )
        self.wall_time = 0.0
        self.progress = 0.0  # m passed in order, checked every CHECK_PERIOD.
        self._s = self.line.project(course_start(course)).s
        self.end = "duration"
        self.failure = ""  # The simulation's error when it failed.

    @property
    def goal(self) -> float:
        """Arc length (m) that completes the course: a lap, or an open course to its finish."""
        if self.line.closed:
            return self.line.length
        return max(self.line.length - self.scenario.finish_margin, 1e-9)

    def default_duration(self, *, viewer: bool) -> float:
        """``scenario.duration``, or one lap's worth (``expected_duration``) when following;
        in balance mode ``BALANCE_DURATION`` headless and until stopped with a viewer."""
        if self.scenario.duration > 0:
            return self.scenario.duration
        if self.scenario.mode == "balance":
            return math.inf if viewer else BALANCE_DURATION
        return expected_duration(self.scenario, self.line.length)

    def run(self, duration: float) -> str:
        """Simulates until ``duration`` (s) or an end condition; returns why it ended (also
        in ``end``): one of ``ENDS``. Ctrl-C (or SIGTERM) ends it as "stopped"; a simulation
        error as "failed", its first line kept in ``failure``."""
        start = time.perf_counter()
        try:
            t = self.context.get_time()
            while t < duration and self.end == "duration":
                t = min(duration, t + CHECK_PERIOD)
                self.simulator.AdvanceTo(t)
                self.end = self._check()
        except BaseException as e:
            self.end, self.failure = cli.run_ending(e)
        finally:
            self.wall_time += time.perf_counter() - start
        return self.end

    def _check(self) -> str:
        """Updates the progress and returns the end condition met, or "duration"."""
        track = self._now()
        s = self.line.project(track[0]).s
        self.progress += self.line.advance(self._s, s)
        self._s = s
        fallen = math.radians(self.scenario.walle.balance.fallen_pitch)
        if abs(track[1]) > fallen:
            return "fell"
        if self.scenario.mode != "balance":
            if self.progress >= self.goal:
                return "lap" if self.line.closed else "finish"
            mode = self.diagram.GetOutputPort("follower_mode").Eval(self.context)[0]
            if mode == STOPPED:
                return "lost_line"
        return "duration"

    def _now(self) -> tuple[np.ndarray, float]:
        """The axle's midpoint (m, world x, y) and the true pitch (rad) now."""
        plant = self.diagram.GetSubsystemByName("plant")
        body = plant.GetBodyByName(BODY_LINK, plant.GetModelInstanceByName(ROBOT_NAME))
        X_WB = plant.EvalBodyPoseInWorld(plant.GetMyContextFromRoot(self.context), body)
        p_WA = X_WB.translation() + X_WB.rotation().matrix() @ np.array(
            [0.0, 0.0, self.robot.axle_z]
        )
        _, pitch = axle_yaw_and_pitch(X_WB.rotation().matrix())
        return p_WA[:2], pitch

    def report(self) -> WalleReport:
        """Summarises the run so far (on the logged ground truth)."""
        track = walle_track(self.diagram, self.context, self.robot)
        fallen = math.radians(self.scenario.walle.balance.fallen_pitch)
        over = np.flatnonzero(np.abs(track.pitch) > fallen)
        sim_time = self.context.get_time()
        offsets = self.line.distances(track.p_WA.T) if track.t.size else np.zeros(1)
        laps, lap_time = self._laps(track)
        return WalleReport(
            fell=bool(over.size),
            time_upright_s=float(track.t[over[0]]) if over.size else sim_time,
            max_abs_pitch_deg=float(np.degrees(np.max(np.abs(track.pitch), initial=0.0))),
            course_fraction=float(min(1.0, max(0.0, self.progress / self.goal))),
            laps=laps,
            lap_time_s=lap_time,
            mean_line_offset_m=float(np.mean(offsets)),
            max_line_offset_m=float(np.max(offsets)),
            progress_m=float(self.progress),
            lost_line=self.end == "lost_line",
            end=self.end,
            mode=self.scenario.mode,
            **run_times(sim_time, self.wall_time, self.seed),
        )

    def _laps(self, track) -> tuple[int, float | None]:
        """Completed laps and the time of the first, from the logged track."""
        if self.scenario.mode == "balance" or not track.t.size:
            return 0, None
        s = np.array([self.line.project(p).s for p in track.p_WA.T])
        steps = [self.line.advance(a, b) for a, b in zip(s[:-1], s[1:], strict=True)]
        progress = np.concatenate([[0.0], np.cumsum(steps)])
        done = np.flatnonzero(progress >= self.goal)
        if not done.size and self.end not in ("lap", "finish"):
            return 0, None
        first = float(track.t[done[0]]) if done.size else self.context.get_time()
        laps = int(max(progress[-1], self.progress) // self.goal) if self.line.closed else 1
        return max(laps, 1), first


def course_start(course: Course) -> np.ndarray:
    """The course's start point (m, world x, y)."""
    return np.array([course.start.x, course.start.y])
