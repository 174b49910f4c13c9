"""``python -m drake_sim.flip``: the robot shuttles along a line by flipping over its axle.

With a viewer (the default) it runs in real time in Meshcat, drawing the robot, its odometry
trail and its true trail, until Ctrl-C (or SIGTERM) or ``--duration``; a stop still prints the
summary and writes the report. ``--headless`` runs flat out for 20 s (or ``--duration``).
``--teleop`` turns the flip controller off: drive with the W/A/S/D keys and Space to stop, in
the Meshcat page. ``--report`` writes the JSON report (docs/flip.md, The report).
Exit codes: 0 for a completed run, 1 if the simulation failed, 2 for bad input.
"""

import json
import math
import sys

from pydrake.geometry import StartMeshcat

from diagrams.flip_scenario import FlipScenario, check_flip_scenario, load_flip_scenario
from drake_sim.base import cli, config
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from drake_sim.flip_run import FlipRun
from drake_sim.robots.ddrive import default_robot_file
from drake_sim.robots.ddrive_params import load_robot_params
from drake_sim.systems.viewer.teleop import BUTTONS

HEADLESS_DURATION = 20.0  # s, the default run length without a viewer.
PROGRESS_MIN_DURATION = 10.0  # s simulated: shorter headless runs show no progress bar.


def _parse_args(argv):
    parser = cli.ArgumentParser(prog="python -m drake_sim.flip", description=__doc__.split("\n")[0])
    cli.add_robot_and_config_options(
        parser, default_robot=default_robot_file(), default_config=config_dir() / "flip.yaml"
    )
    parser.add_argument(
        "--duration",
        type=cli.positive_float,
        help=f"simulated seconds (default: until Ctrl-C with a viewer; {HEADLESS_DURATION:g} "
        "when --headless)",
    )
    parser.add_argument("--headless", action="store_true", help="no Meshcat, no pacing")
    parser.add_argument(
        "--record", type=cli.output_file("replay"), help="write a self-contained HTML replay"
    )
    parser.add_argument("--report", type=cli.output_file("report"), help="write the JSON report")
    parser.add_argument("--seed", type=cli.non_negative_int, help="random seed (IMU noise)")
    parser.add_argument("--teleop", action="store_true", help="drive with Meshcat keys")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scenario value, e.g. --set flip.drive_speed=1.0 (repeatable)",
    )
    args = parser.parse_args(argv)
    if args.teleop and args.headless:
        raise ConfigError("--teleop needs the viewer: drop --headless")
    return args


def apply_overrides(scenario: FlipScenario, overrides: list[str]) -> FlipScenario:
    """Applies ``KEY=VALUE`` overrides (dotted keys, YAML values) to a scenario and checks it.

    Raises:
        ConfigError: for a malformed override, an unknown key or a bad value.
    """
    scenario = config.apply_overrides(FlipScenario, scenario, overrides)
    check_flip_scenario(scenario, "--set")
    return scenario


def _set_up_viewer(meshcat, scenario: FlipScenario, *, teleop: bool, record: bool) -> None:
    """Points Meshcat's camera at the robot, hides the grid, and starts recording if asked."""
    pose = scenario.scene.robot_pose
    meshcat.SetCameraPose([pose.x - 0.6, pose.y - 2.0, 1.1], [pose.x + 0.4, pose.y, 0.15])
    meshcat.SetProperty("/Grid", "visible", False)  # The street is the floor.
    if teleop:
        keys = ", ".join(label for label, _, _ in BUTTONS)
        print(f"teleop: click the Meshcat page, then use its buttons or keys: {keys}")
    if record:
        meshcat.StartRecording()


def main(argv=None) -> int:
    args = _parse_args(argv)
    robot = load_robot_params(args.robot)
    scenario = apply_overrides(load_flip_scenario(args.config), args.set)
    viewer = not args.headless
    duration = args.duration
    if duration is None:
        duration = math.inf if viewer else HEADLESS_DURATION
    meshcat = StartMeshcat() if viewer or args.record else None
    run = FlipRun(
        scenario,
        robot,
        seed=args.seed,
        meshcat=meshcat,
        realtime=viewer,
        controller="teleop" if args.teleop else "flip",
    )
    failure, end = None, "duration"
    try:
        if meshcat is not None:
            _set_up_viewer(meshcat, scenario, teleop=args.teleop, record=bool(args.record))
        cli.announce(meshcat if viewer else None, "running")
        # A bar on long headless runs, on a terminal only (tqdm stays silent in logs).
        run.advance_to(duration, progress=args.headless and duration >= PROGRESS_MIN_DURATION)
    except BaseException as e:
        # A user stop is summarised like a finished run; a simulation error is reported.
        end, message = cli.run_ending(e)
        failure = message or None
    finally:
        if args.record:
            cli.write_replay(meshcat, args.record)
    report = run.report()
    summary = (
        f"flips {report.flips} (failed {report.failed_flips}, recovered {report.recoveries}), "
        f"lateral deviation {report.max_lateral_deviation_m:.3f} m, "
        f"travel extent {report.travel_extent_m:.2f} m, "
        f"odometry error {report.odometry_error_m:.3f} m over {report.distance_travelled_m:.1f} m, "
        f"{report.sim_time_s:.1f} s simulated at {report.real_time_factor:.1f}x real time"
    )
    print(summary)
    if args.report:
        data = {"end": end, **report.to_dict()}  # end: duration, stopped or failed
        cli.write_text(args.report, json.dumps(data, indent=2) + "\n", "report")
    if failure is not None:
        print(
            f"error: simulation failed at t = {report.sim_time_s:.3f} s: {failure}", file=sys.stderr
        )
        return cli.EXIT_FAILED
    return cli.EXIT_OK


if __name__ == "__main__":
    sys.exit(cli.run(main))
