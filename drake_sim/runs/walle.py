"""Wall-E's app (``python -m drake_sim.walle``): its recipe, its run on a course and what the
run did (the report).

A run ends when its duration is reached, a closed course's lap is complete, an open course's
end is reached (within ``scenario.finish_margin``: the camera loses the line's end before the
robot is over it), the robot fell, or the line follower gave up searching for the line.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.geometry import Meshcat

from diagrams.walle import expected_duration, make_walle_course_diagram
from diagrams.walle_balance import ROBOT_NAME
from diagrams.walle_scenario import (
    MODES,
    WalleScenario,
    check_walle_scenario,
    course_path,
    default_scenario_file,
)
from drake_sim.base.errors import ConfigError
from drake_sim.base.report import RunReport, run_times
from drake_sim.robots.walle import BODY_LINK, default_robot_file
from drake_sim.robots.walle_params import WalleParams, load_walle_params, validate
from drake_sim.runs import recipe
from drake_sim.runs.loop import SimulationRun
from drake_sim.runs.recipe import AppRecipe, CliText, Flag, InputFile, Inputs
from drake_sim.runs.walle_track import walle_track
from drake_sim.systems.axle import axle_yaw_and_pitch
from drake_sim.systems.control.line_follower import STOPPED
from drake_sim.systems.viewer.teleop import BUTTONS
from drake_sim.worlds.course import Course, centreline, load_course

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


class WalleCourseRun(SimulationRun):
    """Wall-E's course diagram and simulator, ready to run.

    Args:
        scenario: the mode, sensors and controllers; ``walle.random_seed`` seeds the IMU noise.
        robot: the robot's dimensions.
        course: the course (checked).
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
        meshcat: Meshcat | None = None,
        realtime: bool | None = None,
        teleop: bool = False,
    ):
        self.scenario, self.robot, self.course = scenario, robot, course
        self.teleop = teleop
        self.line = centreline(course)
        diagram = make_walle_course_diagram(scenario, robot, course, meshcat=meshcat, teleop=teleop)
        pacing = {"realtime": realtime, "config": scenario.walle.simulator, "meshcat": meshcat}
        super().__init__(diagram, scenario.walle.random_seed, **pacing)
        self.check_period = CHECK_PERIOD
        self.progress = 0.0  # m passed in order, checked every CHECK_PERIOD.
        self._s = self.line.project(course_start(course)).s

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

    def set_up_viewer(self, meshcat) -> None:
        """Points Meshcat's camera at the course's start from behind and above; hides the grid
        (the course is the floor)."""
        x, y = self.course.start.x, self.course.start.y
        meshcat.SetCameraPose([x - 1.0, y - 2.0, 1.5], [x + 0.5, y + 0.5, 0.0])
        meshcat.SetProperty("/Grid", "visible", False)
        if self.teleop:
            print(f"teleop: in the Meshcat page, {', '.join(b[0] for b in BUTTONS)}")

    def check(self) -> str | None:
        """Updates the progress and returns the end condition met, or None."""
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
        return None

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

    def summary(self, report: WalleReport) -> str:
        return (
            f"{self.scenario.mode} on {course_path(self.scenario).name}: ended by {report.end}, "
            f"course {100 * report.course_fraction:.0f} %, laps {report.laps}, line offset mean "
            f"{report.mean_line_offset_m:.4f} m max {report.max_line_offset_m:.4f} m, "
            f"max pitch {report.max_abs_pitch_deg:.1f} deg, {report.sim_time_s:.1f} s simulated "
            f"at {report.real_time_factor:.1f}x real time"
        )

    def error(self, report: WalleReport) -> str | None:
        if report.end == "fell":
            return f"the robot fell at t = {report.time_upright_s:.2f} s"
        if report.end == "lost_line":
            return f"the robot lost the line for good at t = {report.sim_time_s:.2f} s"
        return super().error(report)

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


def make_run(inputs: Inputs, options, *, meshcat=None, realtime=None) -> WalleCourseRun:
    """The recipe's run on the scenario's course; ``options.teleop`` drives with Meshcat's
    keys (balance mode only)."""
    teleop = bool(recipe.option(options, "teleop", False))
    if teleop and inputs.scenario.mode != "balance":
        raise ConfigError("--teleop drives the balancing robot: use it with --mode balance")
    course = load_course(course_path(inputs.scenario))
    return WalleCourseRun(
        inputs.scenario, inputs.robot, course, meshcat=meshcat, realtime=realtime, teleop=teleop
    )


RECIPE = AppRecipe(
    name="walle",
    robot=InputFile(
        WalleParams, default_robot_file, validate, what="robot file", load=load_walle_params
    ),
    scenario=InputFile(WalleScenario, default_scenario_file, check_walle_scenario),
    seed_key="walle.random_seed",
    make_run=make_run,
    flags=(
        Flag(
            "--mode",
            "mode",
            {"choices": MODES, "help": "what the robot does (default: the scenario's)"},
        ),
        recipe.file_flag("--course", "course file", "course YAML", key="course"),
        recipe.switch("--teleop", "balance mode: drive with Meshcat keys"),
    ),
    cli=CliText(
        seed="random seed (IMU noise)",
        set_example="line_follower.speed=0.2",
        duration="simulated seconds (default: the scenario's, else one lap; balance mode: "
        "until Ctrl-C with a viewer, 10 s headless)",
    ),
)
"""``python -m drake_sim.walle``: robot ``config/walle.yaml``, scenario
``config/walle_scenario.yaml``."""


def report_keys() -> tuple[str, ...]:
    """The keys of the run's report (a sweep's metrics)."""
    return tuple(f.name for f in dc.fields(WalleReport))
