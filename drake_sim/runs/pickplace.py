"""The Panda's pick-and-place app (``python -m drake_sim.pickplace``): its recipe and its run (the
station, the Pick button, the task) with the report of ``--report``.

Its scenario (``diagrams.pickplace_scenario``) holds the robot, the scene, the planner and the
task in one file; ``--scene FILE`` replaces the scene and ``--station FILE`` the station
section. The seed is the planner's.
"""

import dataclasses as dc
import time

import numpy as np

from diagrams.arm_station_config import MODES, ArmStationConfig
from diagrams.pickplace_scenario import (
    PickPlaceScenario,
    check_scenario,
    load_pickplace_scenario,
)
from diagrams.planning_station import make_planning_station
from drake_sim.base import cli
from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from drake_sim.runs import recipe
from drake_sim.runs.recipe import AppRecipe, CliText, Flag, InputFile, Inputs
from planning.errors import ErrorCode, PlanningError
from planning.task.pick_place import STEPS, PickPlaceTask, StepReport, TaskReport
from planning.task.scene_generator import random_scene

BUTTON = "Pick"
"""The Meshcat button that starts the task."""


@dc.dataclass
class PickPlaceReport:
    """The report of ``--report``: how the run ended, the mode, the set-up time and the task's
    report (docs/pickplace.md, The report)."""

    end: str  # done, failed or stopped.
    mode: str
    setup_time_s: float  # s to build the station (the planner's kernels compiled or loaded).
    task: TaskReport

    def to_dict(self) -> dict:
        return {
            "end": self.end,
            "mode": self.mode,
            "setup_time_s": self.setup_time_s,
            **self.task.to_dict(),
        }


class PickPlaceRun:
    """The station of a pick-and-place scenario, ready for its task.

    Args:
        scenario: the whole scenario (robot, scene, planner, task, mode).
        meshcat: draw there, or None to run headless.
        realtime: pace the simulation at real time.
        wait: with a viewer, wait for the page's Pick button before the task.

    Raises:
        ConfigError: the scene is invalid (e.g. the robot starts in collision).
    """

    def __init__(self, scenario: PickPlaceScenario, *, meshcat=None, realtime=False, wait=True):
        self.scenario = scenario
        self.wait = wait
        self.end = "duration"
        start = time.perf_counter()
        try:
            self.mpi = make_planning_station(
                scenario, meshcat=meshcat, realtime_rate=1.0 if realtime else 0.0
            )
        except PlanningError as e:
            if e.code is ErrorCode.INVALID_SCENE:
                raise ConfigError(e.message) from None
            raise
        self.setup_time_s = time.perf_counter() - start
        self.task_report: TaskReport | None = None

    def default_duration(self, *, viewer: bool = False) -> float:
        """The task takes the time it takes."""
        return float("inf")

    def set_up_viewer(self, meshcat) -> None:
        meshcat.SetCameraPose([1.6, -1.2, 0.9], [0.4, 0.0, 0.15])

    def drive(
        self, duration: float, *, meshcat=None, headless: bool = True, echo: bool = True
    ) -> None:
        """Waits for the Pick button (with a viewer, when ``wait``) and runs the task; a stop
        keeps the steps done. With ``echo`` (the CLI) each step is a line as it ends, and a
        stop one line saying how far it got."""
        steps = []

        def on_step(step: StepReport) -> None:
            steps.append(step)
            if echo:
                _print_step(step)

        wall_start = time.perf_counter()
        try:
            if meshcat is not None:
                if self.wait:
                    self._wait_for_button(meshcat)
                else:
                    cli.announce(meshcat, "running the task")
            self.task_report = PickPlaceTask(self.mpi, self.scenario.task, on_step=on_step).run()
            self.end = "done" if self.task_report.success else "failed"
        except BaseException as e:  # a stop may surface as another error: see cli.is_stop
            if not cli.is_stop(e):
                raise
            wall = time.perf_counter() - wall_start
            if echo:
                print(
                    f"stopped: {len(steps)} of {len(STEPS)} steps done, {self.mpi.time:.1f} s "
                    f"simulated in {wall:.1f} s"
                )
            report = TaskReport(reason="stopped by the user", steps=steps, sim_time_s=self.mpi.time)
            report.wall_time_s = wall
            self.task_report, self.end = report, "stopped"

    failed_end = "sim_failed"  # never: the task reports its own failures

    def run(self, duration: float = float("inf"), *, progress: bool = False) -> str:
        """Runs the task headless and quietly; returns how it ended (done, failed or
        stopped)."""
        self.drive(duration, echo=False)
        return self.end

    def _wait_for_button(self, meshcat) -> None:
        meshcat.AddButton(BUTTON)
        print(f"open {meshcat.web_url()} and press {BUTTON!r} (Ctrl-C quits)", flush=True)
        while meshcat.GetButtonClicks(BUTTON) == 0:
            self.mpi.advance(0.05)
        meshcat.DeleteButton(BUTTON)

    def finish(self) -> PickPlaceReport:
        return self.report()

    def report(self) -> PickPlaceReport:
        task = self.task_report
        if task is None:  # stopped before the task began
            task = TaskReport(reason="stopped by the user", sim_time_s=self.mpi.time)
            self.end = "stopped"
        return PickPlaceReport(
            end=self.end, mode=self.scenario.mode, setup_time_s=self.setup_time_s, task=task
        )

    def summary(self, report: PickPlaceReport) -> str | None:
        if report.end == "stopped":
            return None
        task = report.task
        error = "n/a" if task.place_error_m is None else f"{task.place_error_m:.4f} m"
        return (
            f"{'success' if task.success else 'failure'}: place error {error}, planning "
            f"{task.planning_time_s:.2f} s, {task.sim_time_s:.1f} s simulated in "
            f"{task.wall_time_s:.1f} s; set-up {report.setup_time_s:.1f} s (the planner's "
            "kernels compiled or loaded)"
        )

    def error(self, report: PickPlaceReport) -> str | None:
        task = report.task
        if report.end == "stopped" or task.success:
            return None
        what = "impossible task" if task.impossible else f"step {task.failed_step} failed"
        return f"{what}: {' '.join(task.reason.split())}"

    def linger(self, meshcat) -> None:
        """Keeps simulating for the page until Ctrl-C (not after a stop)."""
        if self.end == "stopped":
            return
        cli.announce(meshcat, "showing the result")
        try:
            while True:
                self.mpi.advance(0.1)
        except BaseException as e:
            if not cli.is_stop(e):
                raise


def _print_step(step: StepReport) -> None:
    mark = "ok  " if step.success else "FAIL"
    print(
        f"[{mark}] {step.name:<18} t = {step.sim_time_s:6.2f} s  "
        f"planning {step.planning_time_s * 1000:6.1f} ms  {step.message}",
        flush=True,
    )


def load(path, overrides, *, scene=None, station=None) -> PickPlaceScenario:
    """The scenario at ``path`` with ``scene`` (a scene file replacing its scene), the
    overrides and ``station`` (a file of the station section) applied, checked."""
    scenario = load_pickplace_scenario(path, scene_file=scene, overrides=overrides)
    if station is not None:
        loaded = load_typed(ArmStationConfig, filename=station, defaults=scenario.station)
        for key in ("model", "scene", "initial_q"):
            if getattr(loaded, key) != getattr(scenario.station, key):
                raise ConfigError(f"{station}: 'station.{key}' is set by the scenario")
        scenario = dc.replace(scenario, station=loaded)
    return scenario


def make_run(inputs: Inputs, options, *, meshcat=None, realtime=False) -> PickPlaceRun:
    """The recipe's run; ``options.no_wait`` starts the task at once with a viewer."""
    wait = not recipe.option(options, "no_wait", False)
    return PickPlaceRun(inputs.scenario, meshcat=meshcat, realtime=realtime, wait=wait)


RECIPE = AppRecipe(
    name="pickplace",
    scenario=InputFile(
        PickPlaceScenario,
        lambda: config_dir() / "pickplace_scenario.yaml",
        check_scenario,
        load_overridden=load,
    ),
    seed_key="planner.seed",
    make_run=make_run,
    scenario_flag="--scenario",
    flags=(
        recipe.file_flag(
            "--scene", "scene file", "scene YAML (replaces the scenario's scene)", loader=True
        ),
        recipe.file_flag(
            "--station", "station file", "YAML of the scenario's station section", loader=True
        ),
        Flag("--mode", "mode", {"choices": MODES, "help": "default: the scenario's (physics)"}),
        recipe.switch("--no-wait", "with a viewer: start at once"),
    ),
    cli=CliText(
        seed="planner random seed",
        set_example="task.lift_height=0.08",
        headless="no Meshcat, no pacing",
    ),
)
"""``python -m drake_sim.pickplace``: scenario ``config/pickplace_scenario.yaml``."""


def report_keys() -> tuple[str, ...]:
    """The keys of the run's report (a sweep's metrics)."""
    return ("end", "mode", "setup_time_s", *TaskReport().to_dict())


def generate_scene(scenario: PickPlaceScenario, k: int) -> PickPlaceScenario:
    """Scene k of a sweep's ``scene: {random: N}``: ``random_scene`` drawn from
    ``default_rng(k)`` on the scenario's table (the same scene k in every sweep)."""
    scene = random_scene(np.random.default_rng(k), scenario.scene)
    scenario = dc.replace(scenario, scene=scene)
    check_scenario(scenario, f"random scene {k}")
    return scenario
