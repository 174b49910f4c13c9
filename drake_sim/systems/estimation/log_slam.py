"""Offline SLAM on a recorded log: every scan of a ``LaserLog`` (``drake_sim.base.laser_logs``)
fed in file order into ``ScanMatchingSlam``, as slam_toolbox and Cartographer run on a bag.

The odometry's motion between scans is the prediction. A log's odometry can be wrong in ways
the matcher cannot bridge: a scan before the first odometry message has no motion; a step that
moves more than ``JUMP_DISTANCE`` m or turns more than ``JUMP_ANGLE`` rad between two scans may
be a glitch (MIT CSAIL's logged odometry jumps 0.95 m and 85 degrees) or a real move (Intel's
log has gaps with 0.5 to 0.9 m steps), so the scan is matched from both predictions, with the
step and without it, and the better accepted match decides (``ScanMatchingSlam.update``'s
``alternative_odom_pose``); a step dropped that way counts as a jump. The map's side is the
odometry's extent plus twice the scans' useful range (``map_side``), at least the config's
``map_size``. With ``config.loop_closure.enabled`` the SLAM is ``graph_slam.GraphSlam`` (a pose
graph with loop closures; the map drawn again from the final graph at the end); without, the
trajectory is the scan matcher's.
"""

import dataclasses as dc
import math
from collections.abc import Callable

import numpy as np

from drake_sim.base import cli
from drake_sim.base.laser_scans import LaserLog, LaserScanRecord
from drake_sim.base.planar import compose, relative_pose
from drake_sim.systems.estimation.graph_slam import GraphSlam, make_slam
from drake_sim.systems.estimation.scan_matching_slam import ScanMatchingSlam
from drake_sim.systems.estimation.slam_config import SlamConfig

JUMP_DISTANCE = 0.5
"""m: an odometry step between two scans longer than this may be a jump: the scan is matched
both with and without it."""
JUMP_ANGLE = math.radians(45.0)
"""rad: likewise for a turn."""
USEFUL_RANGE = 30.0
"""m: the farthest returns ``map_side`` makes room for around the odometry's extent ..."""
REACH_QUANTILE = 0.99
"""... and the share of the log's returns it makes room for (a few stray long ones do not
double the map)."""
MAP_SIDE_STEP = 10.0
"""m: ``map_side`` rounds up to a multiple of this."""


@dc.dataclass
class LogSlamResult:
    """What a log's SLAM run produced.

    Attributes:
        slam: the SLAM, its map and trajectory (one pose per processed scan).
        times: (n,) s, the processed scans' timestamps as logged.
        poses: (n, 3) the base's pose [x, y, yaw] after each of them (m, m, rad).
        scans: scans processed (all of the log's unless stopped).
        odometry_jumps: large odometry steps the scans showed to be jumps (dropped).
        loop_closures: loop closures added to the pose graph (0 with loop closure off).
        stopped: True if ``should_stop`` ended it before the last scan.
    """

    slam: ScanMatchingSlam | GraphSlam
    times: np.ndarray
    poses: np.ndarray
    scans: int
    odometry_jumps: int
    loop_closures: int
    stopped: bool


def map_side(log: LaserLog, config: SlamConfig) -> float:
    """m: the side of a square map that holds the log's odometry extent plus the returns around
    it (``REACH_QUANTILE`` of them, up to ``USEFUL_RANGE``), rounded up to ``MAP_SIDE_STEP``;
    at least ``config.map_size``."""
    odometry = np.array([s.odometry[:2] for s in log.scans if s.odometry is not None])
    returns = np.concatenate([s.ranges[np.isfinite(s.ranges)] for s in log.scans])
    reach = min(float(np.quantile(returns, REACH_QUANTILE)), USEFUL_RANGE) if returns.size else 0.0
    extent = float(np.ptp(odometry, axis=0).max()) if len(odometry) else 0.0
    side = MAP_SIDE_STEP * math.ceil((extent + 2.0 * reach + 2.0) / MAP_SIDE_STEP)
    return max(float(config.map_size), side)


def run_log_slam(
    log: LaserLog,
    config: SlamConfig,
    *,
    laser_pose=None,
    should_stop: Callable[[], bool] | None = None,
    progress: Callable[[int, int], None] | None = None,
    on_scan: Callable[[object, LaserScanRecord], None] | None = None,
) -> LogSlamResult:
    """Runs ``ScanMatchingSlam`` over every scan of ``log`` in file order.

    Args:
        log: the scans with their odometry.
        config: the SLAM's parameters; its ``map_size`` grows to ``map_side`` if smaller.
        laser_pose: [x, y, yaw] of the sensor on the base (None: the log's).
        should_stop: polled between scans; True ends the run early (``stopped``), as does
            a user stop (Ctrl-C, SIGTERM: ``cli.is_stop``) raised while a scan is processed.
        progress: called with (scans done, scans in all) every 100 scans.
        on_scan: called with the SLAM and the scan after each scan it took (a viewer).
    """
    config = dc.replace(config, map_size=map_side(log, config))
    sensor = log.laser_pose if laser_pose is None else np.asarray(laser_pose, dtype=float)
    first = next((s.odometry for s in log.scans if s.odometry is not None), np.zeros(3))
    slam = make_slam(config, initial_pose=first, X_base_sensor=sensor)
    odom = np.array(first, dtype=float)  # the odometry as the SLAM is fed it (jumps removed)
    last = None  # the log's odometry at the previous scan
    jumps = 0
    times = []
    stopped = False
    try:
        for k, scan in enumerate(log.scans):
            if should_stop is not None and should_stop():
                stopped = True
                break
            alternative = None
            if scan.odometry is not None:
                if last is not None:
                    step = relative_pose(last, scan.odometry)
                    if math.hypot(step[0], step[1]) > JUMP_DISTANCE or abs(step[2]) > JUMP_ANGLE:
                        alternative = odom  # a jump, or a real move: the scan decides
                    odom = compose(odom, step)
                last = scan.odometry
            slam.update(
                scan.ranges,
                scan.angles,
                odom,
                range_max=scan.range_max,
                range_min=scan.range_min,
                time=scan.time,
                alternative_odom_pose=alternative,
            )
            if alternative is not None and np.array_equal(slam.odometry, alternative):
                jumps += 1  # the scan matched better without the step: it was a jump
                odom = alternative
            times.append(scan.time)
            if on_scan is not None:
                on_scan(slam, scan)
            if progress is not None and (k + 1) % 100 == 0:
                progress(k + 1, len(log.scans))
    except BaseException as e:  # a stop lands wherever the scan's processing was
        if not cli.is_stop(e):
            raise
        stopped = True
    if isinstance(slam, GraphSlam) and not stopped:
        slam.finish()
    n = min(len(times), slam.scans)  # a stop between the update and its time: drop that scan
    poses = slam.trajectory[:n]
    closures = slam.loop_closures if isinstance(slam, GraphSlam) else 0
    times = np.array(times[:n], dtype=float)
    return LogSlamResult(slam, times, poses, n, jumps, closures, stopped)
