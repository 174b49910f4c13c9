"""``python -m drake_sim.walle``: Wall-E balances, follows a line, or both, on a course.

With a viewer (the default) it runs in real time in Meshcat until the run ends (one lap, the
open course's end, a fall, the line lost for good, ``--duration``) or Ctrl-C; ``--headless``
runs flat out. ``--mode balance`` holds position on the course's start (``--teleop``: drive
with the W/A/S/D keys and Space in the Meshcat page); ``follow`` is the statically stable
variant on casters; ``both`` balances while following the line. ``--report`` writes the JSON
report (DESIGN.md, Wall-E course). Exit codes: 0 for a completed run, 1 if the robot fell or
lost the line for good (or the simulation failed), 2 for bad input.
"""

import json
import sys

from pydrake.geometry import StartMeshcat

from diagrams.walle_scenario import (
    MODES,
    WalleScenario,
    check_walle_scenario,
    course_path,
    default_scenario_file,
    load_walle_scenario,
)
from drake_sim.base import cli, config
from drake_sim.base.errors import ConfigError
from drake_sim.robots.walle import default_robot_file
from drake_sim.robots.walle_params import load_walle_params
from drake_sim.systems.viewer.teleop import BUTTONS
from drake_sim.walle_run import WalleCourseRun
from drake_sim.worlds.course import load_course

_RUN_OPTIONS = (
    ("--mode", {"choices": MODES, "help": "what the robot does (default: the scenario's)"}),
    ("--course", {"type": cli.input_file("course file"), "help": "course YAML"}),
    (
        "--duration",
        {
            "type": cli.positive_float,
            "help": "simulated seconds (default: the scenario's, else one lap; balance mode: "
            "until Ctrl-C with a viewer, 10 s headless)",
        },
    ),
    ("--headless", {"action": "store_true", "help": "no Meshcat, no real-time pacing"}),
    ("--record", {"type": cli.output_file("replay"), "help": "write an HTML replay"}),
    ("--report", {"type": cli.output_file("report"), "help": "write the JSON report"}),
    ("--seed", {"type": cli.non_negative_int, "help": "random seed (IMU noise)"}),
    ("--teleop", {"action": "store_true", "help": "balance mode: drive with Meshcat keys"}),
    (
        "--set",
        {
            "action": "append",
            "default": [],
            "metavar": "KEY=VALUE",
            "help": "override a scenario value, e.g. --set line_follower.speed=0.2",
        },
    ),
)
"""The options besides ``--robot`` and ``--config``: (flag, ``add_argument`` keywords)."""


def _parse_args(argv):
    parser = cli.ArgumentParser(
        prog="python -m drake_sim.walle", description=__doc__.split("\n")[0]
    )
    cli.add_robot_and_config_options(
        parser, default_robot=default_robot_file(), default_config=default_scenario_file()
    )
    for flag, options in _RUN_OPTIONS:
        parser.add_argument(flag, **options)
    return parser.parse_args(argv)


def load_scenario(args) -> WalleScenario:
    """The scenario file with ``--set``, ``--mode`` and ``--course`` applied, checked.

    Raises:
        ConfigError: for a bad file, override or combination of flags.
    """
    scenario = load_walle_scenario(args.config)
    scenario = config.apply_overrides(WalleScenario, scenario, args.set)
    if args.mode is not None:
        scenario.mode = args.mode
    if args.course is not None:
        scenario.course = str(args.course.absolute())
    check_walle_scenario(scenario, "--set" if args.set else str(args.config))
    if args.teleop and args.headless:
        raise ConfigError("--teleop needs the viewer: drop --headless")
    if args.teleop and scenario.mode != "balance":
        raise ConfigError("--teleop drives the balancing robot: use it with --mode balance")
    return scenario


def _point_viewer_at_start(meshcat, course) -> None:
    """Points Meshcat's camera at the course's start from behind and above; hides the grid
    (the course is the floor)."""
    x, y = course.start.x, course.start.y
    meshcat.SetCameraPose([x - 1.0, y - 2.0, 1.5], [x + 0.5, y + 0.5, 0.0])
    meshcat.SetProperty("/Grid", "visible", False)


def main(argv=None) -> int:
    args = _parse_args(argv)
    scenario = load_scenario(args)
    robot = load_walle_params(args.robot)
    course = load_course(course_path(scenario))
    viewer = not args.headless
    meshcat = StartMeshcat() if viewer or args.record else None
    run = WalleCourseRun(
        scenario,
        robot,
        course,
        seed=args.seed,
        meshcat=meshcat,
        realtime=viewer,
        teleop=args.teleop,
    )
    duration = args.duration or run.default_duration(viewer=viewer)
    try:
        if meshcat is not None:
            _point_viewer_at_start(meshcat, course)
            if args.record:
                meshcat.StartRecording()
        if args.teleop:
            print(f"teleop: in the Meshcat page, {', '.join(b[0] for b in BUTTONS)}")
        cli.announce(meshcat if viewer else None, "running")
        run.run(duration)  # Ends on its own conditions, a user stop, or a failure.
    except BaseException as e:  # a stop between the set-up and the run's own loop
        if not cli.is_stop(e):
            raise
        run.end = "stopped"
    finally:
        if args.record:
            cli.write_replay(meshcat, args.record)
    report = run.report()
    print(
        f"{scenario.mode} on {course_path(scenario).name}: ended by {report.end}, "
        f"course {100 * report.course_fraction:.0f} %, laps {report.laps}, "
        f"line offset mean {report.mean_line_offset_m:.4f} m max {report.max_line_offset_m:.4f} m, "
        f"max pitch {report.max_abs_pitch_deg:.1f} deg, {report.sim_time_s:.1f} s simulated "
        f"at {report.real_time_factor:.1f}x real time"
    )
    if args.report:
        cli.write_text(args.report, json.dumps(report.to_dict(), indent=2) + "\n", "report")
    failures = {
        "failed": f"simulation failed at t = {report.sim_time_s:.3f} s: {run.failure}",
        "fell": f"the robot fell at t = {report.time_upright_s:.2f} s",
        "lost_line": f"the robot lost the line for good at t = {report.sim_time_s:.2f} s",
    }
    if report.end in failures:
        print(f"error: {failures[report.end]}", file=sys.stderr)
        return cli.EXIT_FAILED
    return cli.EXIT_OK


if __name__ == "__main__":
    sys.exit(cli.run(main))
