"""``python -m drake_sim.navigate``: the lidar robot localises on a saved map and drives to goals.

AMCL localises the robot on ``--map`` (map_server's ``.yaml``) from a first guess
(``--initial-pose``, default the true start) or from nothing (``--global-localization``), and
the navigator (a global costmap from the map and the live scans, A* on it, a DWA local planner
on a rolling local costmap, recoveries) drives it to each goal in turn: ``--goal X Y YAW`` or
``--goals FILE`` (``goals: [{x, y, yaw}]``, metres and degrees). Without either, with a viewer,
goals and pose estimates are given in the Meshcat page (sliders and buttons standing in for
RViz's "2D Nav Goal" and "2D Pose Estimate") until Ctrl-C; headless, the arena's goals file in
``config/goals/`` is driven. The robot really drives in ``--arena`` (default the scenario's),
which may hold obstacles the map does not (``extra_obstacles`` in the scenario). Exit codes: 0
when every goal was reached, 1 when one was not (one line says which and why), 2 for bad input.
"""

import json
import math
import sys

import numpy as np
from pydrake.geometry import StartMeshcat

from diagrams.navigation_scenario import (
    NavigationScenario,
    check_navigation_scenario,
    config_path,
    default_scenario_file,
    load_navigation_scenario,
    world_arena,
)
from drake_sim.base import cli, config
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap, load_map
from drake_sim.navigation_run import CHECK_PERIOD, NavigationRun
from drake_sim.robots.turtlebot3 import default_turtlebot3_file
from drake_sim.robots.turtlebot3_params import load_turtlebot3_params
from drake_sim.systems.viewer.goal_panel import GoalPanel
from drake_sim.worlds.arena import load_arena
from drake_sim.worlds.route import default_goals_file, load_goals


def _pose_option(parser, flag: str, help_text: str, group=None):
    (group or parser).add_argument(
        flag, nargs=3, type=float, metavar=("X", "Y", "YAW"), help=help_text
    )


def _parse_args(argv):
    parser = cli.ArgumentParser(
        prog="python -m drake_sim.navigate", description=__doc__.split("\n")[0]
    )
    cli.add_robot_and_config_options(
        parser, default_robot=default_turtlebot3_file(), default_config=default_scenario_file()
    )
    parser.add_argument("--map", type=cli.input_file("map file"), required=True, help="map .yaml")
    parser.add_argument("--arena", type=cli.input_file("arena file"), help="arena YAML")
    goals = parser.add_mutually_exclusive_group()
    _pose_option(parser, "--goal", "one goal: x, y (m), yaw (degrees)", goals)
    goals.add_argument("--goals", type=cli.input_file("goals file"), help="goals YAML")
    start = parser.add_mutually_exclusive_group()
    _pose_option(parser, "--initial-pose", "AMCL's first guess: x, y (m), yaw (deg)", start)
    start.add_argument(
        "--global-localization", action="store_true", help="AMCL starts from no guess"
    )
    parser.add_argument(
        "--duration", type=cli.positive_float, help="simulated seconds at most (default: per goal)"
    )
    parser.add_argument("--headless", action="store_true", help="no Meshcat, no real-time pacing")
    parser.add_argument("--record", type=cli.output_file("replay"), help="write an HTML replay")
    parser.add_argument("--report", type=cli.output_file("report"), help="write the JSON report")
    parser.add_argument("--seed", type=cli.non_negative_int, help="random seed")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scenario value, e.g. --set amcl.max_particles=1000",
    )
    return parser.parse_args(argv)


def _check_pose(values, what: str, occupancy_map: OccupancyMap) -> np.ndarray:
    """``[x, y, yaw_deg]`` from the command line as ``[x, y, yaw_rad]``: finite, on the map."""
    if not all(math.isfinite(v) for v in values):
        raise ConfigError(f"{what}: every value must be a finite number, got {list(values)}")
    rows, cols = occupancy_map.cell_of(np.array([values[:2]]))
    if not occupancy_map.inside(rows, cols)[0]:
        raise ConfigError(f"{what}: ({values[0]}, {values[1]}) is outside the map")
    return np.array([values[0], values[1], math.radians(values[2])])


def load_scenario(args) -> NavigationScenario:
    """The scenario file with ``--set`` and ``--arena`` applied, checked."""
    scenario = load_navigation_scenario(args.config)
    scenario = config.apply_overrides(NavigationScenario, scenario, args.set)
    if args.arena is not None:
        scenario.arena = str(args.arena.absolute())
    return check_navigation_scenario(scenario, "--set" if args.set else str(args.config))


def _interactive(args) -> bool:
    """Goals from the Meshcat page: a viewer and no goal on the command line."""
    return not args.headless and args.goal is None and args.goals is None


def _goals(args, arena_file, occupancy_map) -> list[np.ndarray]:
    if _interactive(args):
        return []
    if args.goal is not None:
        return [_check_pose(args.goal, "--goal", occupancy_map)]
    path = args.goals if args.goals is not None else default_goals_file(arena_file)
    if not path.is_file():
        raise ConfigError(f"{arena_file}: no default goals ({path} is missing); give --goal")
    goals = [(g.x, g.y, g.yaw) for g in load_goals(path)]
    return [_check_pose(g, f"{path}: goals[{i}]", occupancy_map) for i, g in enumerate(goals)]


def main(argv=None) -> int:
    args = _parse_args(argv)
    scenario = load_scenario(args)
    robot = load_turtlebot3_params(args.robot)
    occupancy_map = load_map(args.map)
    arena_file = config_path(scenario.arena)
    arena = load_arena(arena_file)
    world = world_arena(scenario, arena, str(args.config))
    goals = _goals(args, arena_file, occupancy_map)
    start = np.array(arena.start_pose())
    estimate = None
    if args.initial_pose is not None:
        estimate = _check_pose(args.initial_pose, "--initial-pose", occupancy_map)
    elif not args.global_localization:
        estimate = start
    viewer = not args.headless
    meshcat = StartMeshcat() if viewer or args.record else None
    run = NavigationRun(
        scenario,
        robot,
        world,
        occupancy_map,
        start=start,
        goals=goals,
        initial_estimate=estimate,
        global_localization=args.global_localization,
        seed=args.seed,
        meshcat=meshcat,
        realtime=viewer,
    )
    duration = args.duration or run.default_duration()
    try:
        if meshcat is not None:
            meshcat.SetCameraPose([start[0] - 2.0, start[1] - 3.0, 5.0], [0.0, 0.0, 0.0])
            meshcat.SetProperty("/Grid", "visible", False)
            if args.record:
                meshcat.StartRecording()
        if _interactive(args):
            _drive_from_the_page(run, meshcat, occupancy_map, start, args.duration)
        else:
            cli.announce(meshcat if viewer else None, "navigating")
            run.run(duration)
    except BaseException as e:  # a stop between the set-up and the run's own loop
        if not cli.is_stop(e):
            raise
        run.end = "stopped"
    finally:
        if args.record:
            cli.write_replay(meshcat, args.record)
    report = run.report()
    if _interactive(args):
        print(
            f"{len(report.goals)} goals given in the page, "
            f"{sum(g.reached for g in report.goals)} reached; {report.sim_time_s:.1f} s simulated"
        )
        if args.report:
            cli.write_text(args.report, json.dumps(report.to_dict(), indent=2) + "\n", "report")
        return cli.EXIT_OK
    reached = sum(g.reached for g in report.goals)
    print(
        f"{reached} of {len(goals)} goals reached, ended by {report.end}; collisions "
        f"{report.collisions}, min clearance {report.min_clearance_m:.3f} m, localisation "
        f"error mean {_m(report.localization_error_mean_m)} max "
        f"{_m(report.localization_error_max_m)}; {report.sim_time_s:.1f} s simulated at "
        f"{report.real_time_factor:.1f}x real time"
    )
    if args.report:
        cli.write_text(args.report, json.dumps(report.to_dict(), indent=2) + "\n", "report")
    if report.reached_all or report.end == "stopped":  # Ctrl-C or SIGTERM: a normal stop
        return cli.EXIT_OK
    print(f"error: {_why(run, report, goals)}", file=sys.stderr)
    return cli.EXIT_FAILED


def _drive_from_the_page(run, meshcat, occupancy_map, start, duration) -> None:
    """Runs until Ctrl-C (or ``duration``), turning the page's presses into goals, pose
    estimates and global localisation."""
    lower = np.array(occupancy_map.origin[:2])
    upper = lower + [occupancy_map.width_m, occupancy_map.height_m]
    panel = GoalPanel(meshcat=meshcat, lower=lower, upper=upper, start=start)
    cli.announce(meshcat, "waiting for goals: set x, y, yaw with the sliders, press a button")
    end = math.inf if duration is None else duration
    try:
        while run.context.get_time() < end:
            for action, pose in panel.poll():
                if action == "goal":
                    run.send_goal(pose)
                elif action == "pose":
                    run.set_pose_estimate(pose)
                else:
                    run.start_global_localization()
            run.advance(CHECK_PERIOD)
    except BaseException as e:
        if not cli.is_stop(e):
            raise
    finally:
        panel.remove()


def _m(value) -> str:
    return "n/a" if value is None else f"{value:.3f} m"


def _why(run, report, goals) -> str:
    """One line: which goal was not reached and why."""
    if report.end == "sim_failed":
        return f"simulation failed at t = {report.sim_time_s:.3f} s: {run.failure}"
    failed = next((i for i, g in enumerate(report.goals) if not g.reached), None)
    if failed is not None:
        g = report.goals[failed]
        return f"goal {failed} ({g.goal[0]:g}, {g.goal[1]:g}) not reached: {g.message}"
    index = len(report.goals)
    if index < len(goals):
        x, y, _ = goals[index]
        return f"goal {index} ({x:g}, {y:g}) not reached in {report.sim_time_s:.1f} s: timed out"
    return "no goals"


if __name__ == "__main__":
    sys.exit(cli.run(main))
