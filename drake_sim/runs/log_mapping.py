"""``python -m drake_sim.mapping --log FILE``: offline SLAM on a recorded log (a ROS 1 bag, a
ROS 2 bag or a CARMEN log), as slam_toolbox and Cartographer run on a bag; no simulation.

Every scan goes through the scenario's SLAM (``slam`` section, ``--set slam.KEY=VALUE``) in file
order (``drake_sim.systems.estimation.log_slam``), with its pose graph and loop closures on
(``slam.loop_closure``; ``--no-loop-closure``: the scan matcher alone), as slam_toolbox and
Cartographer map a bag. Written at the end: the map as map_server
files (``--out``, default ``maps/<log name>``), the trajectory in TUM format (``--trajectory``:
``timestamp x y z qx qy qz qw``, the base's pose at each processed scan, or the laser's with
``--trajectory-frame sensor``) and the report
(``--report``). A run stopped by Ctrl-C or SIGTERM writes ``NAME.partial`` files beside them
and leaves complete ones alone; it exits 0, as a completed run does.
"""

import argparse
import dataclasses as dc
import json
import math
import time
from pathlib import Path

import numpy as np

from drake_sim.base import cli
from drake_sim.base.errors import ConfigError
from drake_sim.base.laser_logs import read_log, write_tum
from drake_sim.base.map_files import save_map
from drake_sim.base.planar import compose
from drake_sim.runs import command
from drake_sim.runs.recipe import AppRecipe
from drake_sim.systems.estimation.log_slam import run_log_slam
from drake_sim.systems.viewer.log_view import LogView

DEFAULT_OUT = Path("maps")
LOG_ONLY = (
    "trajectory",
    "trajectory_frame",
    "scan_topic",
    "odom_topic",
    "laser_pose",
    "scan_angles",
    "no_loop_closure",
)
"""Options that mean something only with ``--log``."""
SIMULATION_ONLY = (
    "arena", "world", "start", "route", "teleop", "lidar", "record", "record_log", "duration",
)  # fmt: skip
"""Options of a simulated run that a log's run refuses."""


@dc.dataclass
class LogMappingReport:
    """The report of a log's SLAM run (``--report``, JSON)."""

    end: str  # "done" or "stopped"
    log: str
    scan_topic: str
    odom_topic: str
    laser_pose: list[float]  # [x, y, yaw] of the sensor on the base (m, m, rad)
    scans: int  # scans processed
    log_duration_s: float  # from the first processed scan's time to the last's
    wall_time_s: float
    real_time_factor: float  # log_duration_s / wall_time_s
    loop_closures: int  # loop-closure constraints added to the pose graph
    odometry_jumps: int  # large odometry steps the scans showed to be jumps (dropped)
    rejected_matches: int  # scans whose match the gate rejected (the prediction stood)
    map_size_m: float  # the longer side of the SLAM's grids at the end (they grow as needed)
    map_files: list[str]
    trajectory: str | None

    def to_dict(self) -> dict:
        return dc.asdict(self)


def add_flags(p: argparse.ArgumentParser) -> None:
    """Adds ``--log`` and the options that go with it to the mapping app's parser."""
    group = p.add_argument_group("offline SLAM on a recorded log (instead of a simulation)")
    group.add_argument(
        "--log",
        type=cli.input_path("log"),
        help="a ROS 1 bag, a ROS 2 bag (folder or file) or a CARMEN log (.clf, .log) to map",
    )
    group.add_argument(
        "--trajectory",
        type=cli.output_file("trajectory"),
        help="with --log: write the base's pose at every scan here (TUM format)",
    )
    group.add_argument(
        "--trajectory-frame",
        choices=("base", "sensor"),
        help="with --log: the trajectory's poses are the base's (default) or the laser's (the "
        "frame the Kümmerle datasets' relations are in)",
    )
    group.add_argument("--scan-topic", help="with --log: the LaserScan topic (default: found)")
    group.add_argument("--odom-topic", help="with --log: the Odometry topic (default: found)")
    group.add_argument(
        "--laser-pose",
        nargs=3,
        type=float,
        metavar=("X", "Y", "YAW"),
        help="with --log: the sensor on the base, x, y (m), yaw (deg) (default: the log's tf)",
    )
    group.add_argument(
        "--no-loop-closure",
        action="store_true",
        default=None,
        help="with --log: the scan matcher alone (default: with the pose graph and loop "
        "closures, slam.loop_closure)",
    )
    group.add_argument(
        "--scan-angles",
        choices=("log", "gmapping"),
        help="with --log: the scans' own beam angles (default) or GMapping's for that many "
        "beams (-90 deg + i * resolution; the Kümmerle datasets' bags need it)",
    )


def check_flags(args: argparse.Namespace) -> None:
    """Raises ConfigError for a ``--log`` option without ``--log``, or a simulation's with it."""
    if args.log is None:
        given = [name for name in LOG_ONLY if getattr(args, name, None) is not None]
        if given:
            flag = "--" + given[0].replace("_", "-")
            raise ConfigError(f"{flag} goes with --log FILE (offline SLAM on a recorded log)")
        return
    given = [name for name in SIMULATION_ONLY if getattr(args, name, None)]
    if given:
        flag = "--" + given[0].replace("_", "-")
        raise ConfigError(f"--log maps a recorded log: {flag} is for a simulated run")


def run(recipe: AppRecipe, args: argparse.Namespace) -> int:
    """One offline SLAM run from the command line; returns the exit code (0: done or stopped)."""
    inputs = command.load_from_args(recipe, args)
    log = read_log(
        args.log,
        scan_topic=args.scan_topic,
        odom_topic=args.odom_topic,
        angles=args.scan_angles or "log",
    )
    laser = None
    if args.laser_pose is not None:
        x, y, yaw = args.laser_pose
        if not all(math.isfinite(v) for v in (x, y, yaw)):
            raise ConfigError(f"--laser-pose must be finite numbers, got {args.laser_pose}")
        laser = np.array([x, y, math.radians(yaw)])
    config = inputs.scenario.slam
    loops = dc.replace(config.loop_closure, enabled=not args.no_loop_closure)
    meshcat = view = None
    if not args.headless:
        from pydrake.geometry import StartMeshcat  # noqa: PLC0415 (Meshcat's server starts here)

        meshcat = StartMeshcat()
        view = LogView(meshcat)
    cli.announce(meshcat, f"mapping {args.log.name}")
    start = time.perf_counter()
    result = run_log_slam(
        log,
        dc.replace(config, loop_closure=loops),
        laser_pose=laser,
        should_stop=cli.stop_received,
        on_scan=_drawer(view),
    )
    wall = time.perf_counter() - start
    if view is not None:
        view.finish(result.slam, result.poses)
    end = "stopped" if result.stopped else "done"
    out = args.out or DEFAULT_OUT / _name(args.log)
    trajectory = args.trajectory
    if result.stopped:  # a complete result already there stays whole
        out = out.with_name(f"{out.name}.partial")
        if trajectory is not None:
            trajectory = trajectory.with_name(f"{trajectory.stem}.partial{trajectory.suffix}")
    files = []
    if result.scans:
        files = [str(p) for p in save_map(result.slam.map(), out)]
        if trajectory is not None:
            poses = result.poses
            if args.trajectory_frame == "sensor":
                poses = compose(poses, result.slam.X_base_sensor)
            write_tum(trajectory, result.times, poses)
    span = float(np.ptp(result.times)) if result.scans else 0.0
    report = LogMappingReport(
        end=end,
        log=str(args.log),
        scan_topic=log.scan_topic,
        odom_topic=log.odom_topic,
        laser_pose=[float(v) for v in result.slam.X_base_sensor],
        scans=result.scans,
        log_duration_s=span,
        wall_time_s=wall,
        real_time_factor=span / wall if wall > 0 else math.inf,
        loop_closures=result.loop_closures,
        odometry_jumps=result.odometry_jumps,
        rejected_matches=result.slam.rejected,
        map_size_m=_map_side(result.slam),
        map_files=files,
        trajectory=str(trajectory) if trajectory is not None and result.scans else None,
    )
    print(
        f"{end}: {report.scans} of {len(log.scans)} scans ({span:.1f} s of log) in {wall:.1f} s "
        f"({report.real_time_factor:.2f}x real time), {report.odometry_jumps} odometry jumps, "
        f"{report.rejected_matches} matches rejected, {report.loop_closures} loop closures; "
        f"map {files[1] if files else 'none'}",
        flush=True,
    )
    if args.report:
        cli.write_text(args.report, json.dumps(report.to_dict(), indent=2) + "\n", "report")
    if meshcat is not None and not result.stopped:
        _linger(meshcat)
    return cli.EXIT_OK


def _drawer(view: LogView | None):
    """``run_log_slam``'s ``on_scan`` for ``view`` (None: nothing drawn)."""
    if view is None:
        return None
    return lambda slam, scan: view.update(
        slam, scan.time, scan.ranges, scan.angles, scan.range_min, scan.range_max
    )


def _linger(meshcat) -> None:
    """Keeps the page with the final map open until Ctrl-C."""
    cli.announce(meshcat, "showing the map")
    try:
        while True:
            time.sleep(0.1)
    except BaseException as e:
        if not cli.is_stop(e):
            raise


def _name(path: Path) -> str:
    name = path.name
    for suffix in (".orig.bag", ".bag", ".mcap", ".db3", ".clf", ".log"):
        if name.endswith(suffix) and len(name) > len(suffix):
            return name[: -len(suffix)]
    return name or "log"


def _map_side(slam) -> float:
    """m: the longer side of ``slam``'s map grid (a ``GraphSlam``'s matcher's)."""
    grid = getattr(slam, "local", slam).grids[0]
    return float(max(grid.shape) * grid.resolution)
