"""``python -m drake_sim.mapping``: the lidar robot maps an arena with scan-matching SLAM and saves
the map as map_server files.

It drives a route (``--route FILE``, else the arena's default route in ``config/routes/``) or,
with ``--teleop``, the W/A/S/D keys in the Meshcat page, while the SLAM builds the map from the
lidar's scans and the wheel odometry. Meshcat shows the robot (the truth), the scan, the map as
it grows and the SLAM pose's trail against the true one. At the end the map is written as
``--out``'s ``.pgm`` and ``.yaml`` (map_saver's format) and scored against the arena; a run that
ends before its route does (Ctrl-C, SIGTERM, ``--duration``, a failure) keeps any map already at
``--out`` and writes ``NAME.partial.pgm`` / ``.yaml`` beside it instead. Exit
codes: 0 for a completed run, 1 if the route was not completed (or the simulation failed),
2 for bad input.
"""

import json
import sys
from pathlib import Path

from pydrake.geometry import StartMeshcat

from diagrams.mapping_scenario import (
    MappingScenario,
    check_mapping_scenario,
    config_path,
    default_scenario_file,
    load_mapping_scenario,
)
from drake_sim.base import cli, config
from drake_sim.base.errors import ConfigError
from drake_sim.mapping_run import MappingRun
from drake_sim.robots.turtlebot3 import default_turtlebot3_file
from drake_sim.robots.turtlebot3_params import load_turtlebot3_params
from drake_sim.systems.sensors.lidar import load_lidar_config
from drake_sim.systems.viewer.teleop import BUTTONS
from drake_sim.worlds.arena import load_arena
from drake_sim.worlds.route import default_route_file, load_route

DEFAULT_OUT = "maps"
"""The folder of the map files when ``--out`` is not given: ``maps/<arena's name>``."""


def _parse_args(argv):
    parser = cli.ArgumentParser(
        prog="python -m drake_sim.mapping", description=__doc__.split("\n")[0]
    )
    cli.add_robot_and_config_options(
        parser, default_robot=default_turtlebot3_file(), default_config=default_scenario_file()
    )
    parser.add_argument("--arena", type=cli.input_file("arena file"), help="arena YAML")
    parser.add_argument(
        "--lidar",
        type=cli.input_file("lidar file"),
        help="lidar YAML, e.g. config/lidars/sick_tim571.yaml (default: the scenario's LDS-01)",
    )
    drive = parser.add_mutually_exclusive_group()
    drive.add_argument(
        "--route", type=cli.input_file("route file"), help="route YAML (waypoints to drive)"
    )
    drive.add_argument("--teleop", action="store_true", help="drive with the Meshcat keys")
    parser.add_argument(
        "--out",
        type=cli.output_file("map"),
        help=f"map files to write, without extension (default {DEFAULT_OUT}/<arena>)",
    )
    parser.add_argument(
        "--duration",
        type=cli.positive_float,
        help="simulated seconds at most (default: enough for the route; teleop: until Ctrl-C)",
    )
    parser.add_argument("--headless", action="store_true", help="no Meshcat, no real-time pacing")
    parser.add_argument("--record", type=cli.output_file("replay"), help="write an HTML replay")
    parser.add_argument("--report", type=cli.output_file("report"), help="write the JSON report")
    parser.add_argument("--seed", type=cli.non_negative_int, help="random seed (odometry, lidar)")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scenario value, e.g. --set lidar.noise_sigma=0.02",
    )
    return parser.parse_args(argv)


def load_scenario(args) -> MappingScenario:
    """The scenario file with ``--set``, ``--arena`` and ``--route`` applied, checked.

    Raises:
        ConfigError: for a bad file, override or combination of flags.
    """
    scenario = load_mapping_scenario(args.config)
    scenario = config.apply_overrides(MappingScenario, scenario, args.set)
    if args.arena is not None:
        scenario.arena = str(args.arena.absolute())
    if args.route is not None:
        scenario.route = str(args.route.absolute())
    if args.lidar is not None:
        scenario.lidar = load_lidar_config(args.lidar)
    check_mapping_scenario(scenario, "--set" if args.set else str(args.config))
    if args.teleop and args.headless:
        raise ConfigError("--teleop needs the viewer: drop --headless")
    return scenario


def _route_file(scenario: MappingScenario, arena_file):
    if scenario.route:
        return config_path(scenario.route)
    route = default_route_file(arena_file)
    if not route.is_file():
        raise ConfigError(f"{arena_file}: no default route ({route} is missing); give --route")
    return route


def _save_map(run: MappingRun, out: Path, *, complete: bool):
    """Saves the run's map at ``out`` when the run is ``complete`` (the route driven to its end,
    or a teleop run, which Ctrl-C ends), else beside it as ``NAME.partial``: a run stopped or
    failed early never replaces a map that was there. Returns the files written."""
    if complete:
        return run.save_map(out)
    files = run.save_map(out.with_name(f"{out.name}.partial"))
    kept = f"; {out}.yaml is kept as it was" if Path(f"{out}.yaml").exists() else ""
    print(f"the run ended early ({run.end}): its partial map is {files[1]}{kept}")
    return files


def main(argv=None) -> int:
    args = _parse_args(argv)
    scenario = load_scenario(args)
    robot = load_turtlebot3_params(args.robot)
    arena_file = config_path(scenario.arena)
    arena = load_arena(arena_file)
    waypoints = (
        [] if args.teleop else load_route(_route_file(scenario, arena_file), arena).waypoints
    )
    out = args.out if args.out is not None else Path(DEFAULT_OUT) / arena_file.stem
    viewer = not args.headless
    meshcat = StartMeshcat() if viewer or args.record else None
    run = MappingRun(
        scenario,
        robot,
        arena,
        waypoints,
        seed=args.seed,
        meshcat=meshcat,
        realtime=viewer,
        teleop=args.teleop,
        keyframes=args.record is not None,
    )
    duration = args.duration or run.default_duration(viewer=viewer)
    try:
        if meshcat is not None:
            x, y, _ = arena.start_pose()
            meshcat.SetCameraPose([x - 2.0, y - 3.0, 4.0], [0.0, 0.0, 0.0])
            meshcat.SetProperty("/Grid", "visible", False)  # the arena has its own floor
            if args.record:
                meshcat.StartRecording()
        if args.teleop:
            print(f"teleop: in the Meshcat page, {', '.join(b[0] for b in BUTTONS)}")
        cli.announce(meshcat if viewer else None, "mapping")
        run.run(duration)
    except BaseException as e:  # a stop between the set-up and the run's own loop
        if not cli.is_stop(e):
            raise
        run.end = "stopped"
    finally:
        if args.record:
            cli.write_replay(meshcat, args.record)
    files = _save_map(run, out, complete=run.end == "route_done" or args.teleop)
    report = run.report()
    print(
        f"{arena_file.name}: ended by {report.end}, {report.scans} scans, map IoU "
        f"{report.map_iou:.3f}, known {100 * report.known_fraction:.1f} %, pose RMSE "
        f"{report.pose_rmse_m:.3f} m (final {report.final_pose_error_m:.3f} m, "
        f"{report.final_yaw_error_deg:.1f} deg; odometry {report.odometry_final_error_m:.3f} m), "
        f"{report.sim_time_s:.1f} s simulated at {report.real_time_factor:.1f}x real time; "
        f"map {files[1]}"
    )
    if args.report:
        cli.write_text(args.report, json.dumps(report.to_dict(), indent=2) + "\n", "report")
    if report.end == "failed":
        print(
            f"error: simulation failed at t = {report.sim_time_s:.3f} s: {run.failure}",
            file=sys.stderr,
        )
        return cli.EXIT_FAILED
    if report.end == "duration" and not args.teleop:
        print(
            f"error: the route was not completed in {report.sim_time_s:.1f} s "
            f"({100 * report.route_fraction:.0f} % of its waypoints)",
            file=sys.stderr,
        )
        return cli.EXIT_FAILED
    return cli.EXIT_OK


if __name__ == "__main__":
    sys.exit(cli.run(main))
