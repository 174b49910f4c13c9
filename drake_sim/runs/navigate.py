"""The navigate app's recipe (``python -m drake_sim.navigate``): the saved map, the goals (from
the command line, a goals file, the arena's default goals, random ones for a sweep, or the
Meshcat page), AMCL's start, and the run's summary and errors.

The run itself, its report and its goal handles are ``drake_sim.runs.navigation``'s.
"""

import dataclasses as dc
import math
from pathlib import Path

import numpy as np

from diagrams.navigation_scenario import (
    NavigationScenario,
    check_navigation_scenario,
    default_scenario_file,
    load_navigation_scenario,
    world_arena,
)
from drake_sim.base import cli
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap, load_map
from drake_sim.runs import recipe
from drake_sim.runs.lidar_robot import (
    ARENA_FLAG,
    LIDAR_FLAG,
    ROBOT_FILE,
    START_FLAG,
    WORLD_FLAG,
    load_world,
)
from drake_sim.runs.navigation import CHECK_PERIOD, NavigationReport, NavigationRun
from drake_sim.runs.recipe import AppRecipe, CliText, Flag, InputFile, Inputs
from drake_sim.runs.ros_recording import RECORD_LOG_FLAG, open_ros_log
from drake_sim.systems.viewer.goal_panel import GoalPanel
from drake_sim.worlds.arena import arena_grid
from drake_sim.worlds.map_world import check_map_agrees
from drake_sim.worlds.route import default_goals_file, load_goals, random_goals

GROUND_TRUTH_RESOLUTION = 0.05
"""m: the cells of the arena's ground-truth map, used when no map is given (a sweep)."""


class NavigateRun(NavigationRun):
    """A ``NavigationRun`` as the CLI drives it: from the command line's goals, or from the
    Meshcat page's (``interactive``) until Ctrl-C."""

    def __init__(self, scenario, robot, world, occupancy_map, *, start, interactive=False, **kw):
        super().__init__(scenario, robot, world, occupancy_map, start=start, **kw)
        self.occupancy_map = occupancy_map
        self.start = np.asarray(start, dtype=float)
        self.interactive = interactive

    def default_duration(self, *, viewer: bool = False) -> float:
        """Until Ctrl-C for goals from the page, else ``NavigationRun``'s per-goal time."""
        return math.inf if self.interactive else super().default_duration(viewer=viewer)

    def set_up_viewer(self, meshcat) -> None:
        """Points Meshcat's camera at the arena from the start and hides the grid."""
        x, y = self.start[:2]
        meshcat.SetCameraPose([x - 2.0, y - 3.0, 5.0], [0.0, 0.0, 0.0])
        meshcat.SetProperty("/Grid", "visible", False)

    def drive(self, duration: float, *, meshcat=None, headless: bool = True) -> None:
        if not self.interactive:
            super().drive(duration, meshcat=meshcat, headless=headless)
            return
        self.drive_from_the_page(meshcat, duration)

    def drive_from_the_page(self, meshcat, duration: float) -> None:
        """Runs until Ctrl-C (or ``duration``), turning the page's presses into goals, pose
        estimates and global localisation."""
        lower = np.array(self.occupancy_map.origin[:2])
        upper = lower + [self.occupancy_map.width_m, self.occupancy_map.height_m]
        panel = GoalPanel(meshcat=meshcat, lower=lower, upper=upper, start=self.start)
        cli.announce(meshcat, "waiting for goals: set x, y, yaw with the sliders, press a button")
        try:
            while self.context.get_time() < duration:
                for action, pose in panel.poll():
                    if action == "goal":
                        self.send_goal(pose)
                    elif action == "pose":
                        self.set_pose_estimate(pose)
                    else:
                        self.start_global_localization()
                self.advance(CHECK_PERIOD)
        except BaseException as e:
            if not cli.is_stop(e):
                raise
        finally:
            panel.remove()

    def log_complete(self) -> bool:
        """Goals from the page end with Ctrl-C: such a run's log is complete."""
        return self.interactive or super().log_complete()

    def summary(self, report: NavigationReport) -> str:
        reached = sum(g.reached for g in report.goals)
        if self.interactive:
            return (
                f"{len(report.goals)} goals given in the page, {reached} reached; "
                f"{report.sim_time_s:.1f} s simulated"
            )
        return (
            f"{reached} of {len(self.goals)} goals reached, ended by {report.end}; collisions "
            f"{report.collisions}, min clearance {report.min_clearance_m:.3f} m, localisation "
            f"error mean {_m(report.localization_error_mean_m)} max "
            f"{_m(report.localization_error_max_m)}; {report.sim_time_s:.1f} s simulated at "
            f"{report.real_time_factor:.1f}x real time"
        )

    def error(self, report: NavigationReport) -> str | None:
        """One line: which goal was not reached and why (None when all were, or stopped)."""
        if self.interactive or report.reached_all or report.end == "stopped":
            return None
        if report.end == "sim_failed":
            return f"simulation failed at t = {report.sim_time_s:.3f} s: {self.failure}"
        failed = next((i for i, g in enumerate(report.goals) if not g.reached), None)
        if failed is not None:
            g = report.goals[failed]
            return f"goal {failed} ({g.goal[0]:g}, {g.goal[1]:g}) not reached: {g.message}"
        index = len(report.goals)
        if index < len(self.goals):
            x, y, _ = self.goals[index]
            return (
                f"goal {index} ({x:g}, {y:g}) not reached in {report.sim_time_s:.1f} s: timed out"
            )
        return "no goals"


def _m(value) -> str:
    return "n/a" if value is None else f"{value:.3f} m"


def check_pose(values, what: str, occupancy_map: OccupancyMap | None) -> np.ndarray:
    """``[x, y, yaw_deg]`` from the command line as ``[x, y, yaw_rad]``: finite, on the map
    (when there is one)."""
    if not all(math.isfinite(v) for v in values):
        raise ConfigError(f"{what}: every value must be a finite number, got {list(values)}")
    if occupancy_map is None:
        return np.array([values[0], values[1], math.radians(values[2])])
    rows, cols = occupancy_map.cell_of(np.array([values[:2]]))
    if not occupancy_map.inside(rows, cols)[0]:
        raise ConfigError(f"{what}: ({values[0]}, {values[1]}) is outside the map")
    return np.array([values[0], values[1], math.radians(values[2])])


def _goals(options, arena, arena_file: Path, occupancy_map, interactive: bool, seed: int):
    """The goals the options name: none (the page's), ``goal``, ``goals``: a goals file, a
    number of random ones (an int, drawn with ``seed``) or a list of ``[x, y, yaw_rad]`` poses;
    else the arena's default goals file."""
    if interactive:
        return []
    goal, goals = recipe.option(options, "goal"), recipe.option(options, "goals")
    if goal is not None:
        return [check_pose(goal, "--goal", occupancy_map)]
    if isinstance(goals, int):
        return random_goals(arena, goals, seed)
    if isinstance(goals, list | tuple):
        return [np.asarray(g, dtype=float) for g in goals]
    path = Path(goals) if goals is not None else default_goals_file(arena_file)
    if not path.is_file():
        raise ConfigError(f"{arena_file}: no default goals ({path} is missing); give --goal")
    poses = [(g.x, g.y, g.yaw) for g in load_goals(path)]
    return [check_pose(g, f"{path}: goals[{i}]", occupancy_map) for i, g in enumerate(poses)]


def make_run(inputs: Inputs, options, *, meshcat=None, realtime=False) -> NavigateRun:
    """The recipe's run. ``options``: ``map`` (map_server YAML; with a ``start`` and no world
    named, also the world the robot drives in; without one, the command line navigates with no
    prior map, on the live SLAM and what the lidar sees, while a caller's dict gets the arena's
    ground truth at the lidar's height, what a perfect mapping run saves, unless ``no_map``),
    ``goal`` ([x, y, yaw_deg]),
    ``goals`` (a goals file, a number of random goals, or a list of ``[x, y, yaw_rad]``),
    ``initial_pose`` (AMCL's first
    guess, [x, y, yaw_deg]; default the true start), ``global_localization``, ``record_log``
    (a ROS 2 log, ``FILE.mcap``, of the run); with a viewer and
    no goals, the goals come from the page (``headless`` False)."""
    scenario, robot = inputs.scenario, inputs.robot
    map_file = recipe.option(options, "map")
    # No saved map: the command line navigates with none (as move_base and nav2 can); a
    # caller's dict gets the arena's ground truth unless it asks for none (``no_map``).
    no_map = not map_file and recipe.option(options, "no_map", not isinstance(options, dict))
    own_world = map_file and not scenario.world and not _arena_named(options)
    if own_world and scenario.start:  # --map and --start, no arena: the map is the world
        scenario = dc.replace(scenario, world=str(map_file))
    arena_file, arena, world_map = load_world(scenario)
    if map_file:
        occupancy_map = load_map(map_file)
    elif no_map:
        occupancy_map = None
    else:
        occupancy_map = arena_grid(arena, GROUND_TRUTH_RESOLUTION, height=robot.scan_height)
    world = world_arena(
        scenario, arena, str(recipe.option(options, "scenario") or default_scenario_file())
    )
    interactive = (
        not recipe.option(options, "headless", True)
        and recipe.option(options, "goal") is None
        and recipe.option(options, "goals") is None
    )
    goals = _goals(options, arena, arena_file, occupancy_map, interactive, inputs.seed)
    start = np.array(arena.start_pose())
    if map_file and world_map is None:  # a map and an arena: do they describe the same place?
        poses = [start[:2], *(np.asarray(g, dtype=float)[:2] for g in goals)]
        try:
            check_map_agrees(arena, occupancy_map, poses, f"--map {map_file}, arena {arena_file}")
        except ConfigError as e:
            if own_world:
                hint = (
                    "no arena named: give the robot's start with --start X Y YAW to drive in "
                    "the map's own world, or name the arena the map was made in with --arena"
                )
            else:
                hint = "to drive in the map's own world: --world MAP --start X Y YAW"
            raise ConfigError(f"{e} ({hint})") from None
    global_localization = bool(recipe.option(options, "global_localization", False))
    if no_map and (global_localization or recipe.option(options, "initial_pose") is not None):
        raise ConfigError(
            "--initial-pose and --global-localization are AMCL's: give the map it localises "
            "on with --map (without one the live SLAM localises the robot)"
        )
    estimate = None
    if recipe.option(options, "initial_pose") is not None:
        guess = recipe.option(options, "initial_pose")
        estimate = check_pose(guess, "--initial-pose", occupancy_map)
    elif not global_localization:
        estimate = start
    return NavigateRun(
        scenario,
        robot,
        world,
        occupancy_map=occupancy_map,
        start=start,
        goals=goals,
        initial_estimate=estimate,
        global_localization=global_localization,
        meshcat=meshcat,
        realtime=realtime,
        interactive=interactive,
        log_writer=open_ros_log(options),
    )


def _arena_named(options) -> bool:
    """Whether the command line names the world (``--arena``, ``--world``, a scenario file of
    the user's, ``--set arena=``/``world=``); otherwise a ``--map`` given with ``--start`` is
    the world too."""
    if any(recipe.option(options, name) for name in ("arena", "world", "scenario")):
        return True
    sets = recipe.option(options, "set") or ()
    return any(str(item).split("=", 1)[0] in ("arena", "world") for item in sets)


def _pose_flag(name: str, help_text: str, group: str) -> Flag:
    kwargs = {"nargs": 3, "type": float, "metavar": ("X", "Y", "YAW"), "help": help_text}
    return Flag(name, kwargs=kwargs, group=group)


RECIPE = AppRecipe(
    name="navigate",
    robot=ROBOT_FILE,
    scenario=InputFile(
        NavigationScenario,
        default_scenario_file,
        check_navigation_scenario,
        load_overridden=load_navigation_scenario,
    ),
    seed_key="random_seed",
    make_run=make_run,
    flags=(
        recipe.file_flag(
            "--map", "map file", "map .yaml (none: no prior map, the live SLAM and the lidar alone)"
        ),
        ARENA_FLAG,
        WORLD_FLAG,
        START_FLAG,
        Flag(
            "--params",
            key="params",
            kwargs={
                "nargs": "+",
                "type": cli.input_file("parameter file"),
                "metavar": "FILE",
                "help": "ROS parameter files (nav2_params.yaml; ROS 1 YAML or launch), in order",
            },
        ),
        LIDAR_FLAG,
        RECORD_LOG_FLAG,
        _pose_flag("--goal", "one goal: x, y (m), yaw (degrees)", "goals"),
        recipe.file_flag("--goals", "goals file", "goals YAML", group="goals"),
        _pose_flag("--initial-pose", "AMCL's first guess: x, y (m), yaw (deg)", "start"),
        recipe.switch("--global-localization", "AMCL starts from no guess", "start"),
    ),
    cli=CliText(
        set_example="amcl.max_particles=1000",
        duration="simulated seconds at most (default: per goal)",
    ),
)
"""``python -m drake_sim.navigate``: robot ``config/turtlebot3.yaml``, scenario
``config/navigation_scenario.yaml``."""


SUMMARY_KEYS = ("goals_reached", "max_position_error_m", "max_yaw_error_deg")
"""A sweep row's summary of the per-goal list (``sweep_row``)."""


def report_keys() -> tuple[str, ...]:
    """The keys of a sweep's row: the report's, the goal list summed up in ``SUMMARY_KEYS``."""
    fields = tuple(f.name for f in dc.fields(NavigationReport) if f.name != "goals")
    return (*fields, *SUMMARY_KEYS)


def sweep_row(report: dict) -> dict:
    """The report with its per-goal list summed up: goals reached, the worst position and yaw
    errors of those reached."""
    report = dict(report)
    reached = [g for g in report.pop("goals") if g["reached"]]
    worst = {
        key: max((g[key] for g in reached), default=None)
        for key in ("position_error_m", "yaw_error_deg")
    }
    return {
        **report,
        "goals_reached": len(reached),
        "max_position_error_m": worst["position_error_m"],
        "max_yaw_error_deg": worst["yaw_error_deg"],
    }
