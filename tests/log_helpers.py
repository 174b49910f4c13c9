"""Recorded logs for the offline SLAM tests, made here from the synthetic room of
``slam_helpers``: the truth, the drifting odometry and the lidar's scans of one drive."""

import math

import numpy as np

from drake_sim.base.laser_scans import LaserLog, LaserScanRecord
from tests import slam_helpers as sh

RANGE_MAX = 3.5


def room_drive(waypoints=sh.ROOM_ROUTE[:5], *, seed=0):
    """(truth (k, 3), odometry (k, 3), ranges (k, n), angles (n,)) of a drive in the room at
    5 Hz: 2 % and 0.5 deg/m of odometry drift, 1 cm of range noise, the LDS-01's 3.5 m."""
    truth = sh.drive(waypoints, sh.ROOM_START)
    odometry = sh.drifting_odometry(truth, seed=seed)
    ranges, angles = sh.lidar_scans(sh.room(), truth, seed=seed, range_max=RANGE_MAX)
    return truth, odometry, ranges, angles


def laser_log(truth, odometry, ranges, angles, *, t0=100.0, rate=5.0) -> LaserLog:
    """The drive as an in-memory LaserLog (the sensor at the base's origin)."""
    scans = [
        LaserScanRecord(t0 + k / rate, r.copy(), angles.copy(), 0.0, RANGE_MAX, o.copy())
        for k, (r, o) in enumerate(zip(ranges, odometry, strict=True))
    ]
    return LaserLog(None, scans, np.zeros(3), "test", "test")


def carmen_text(odometry, ranges, angles, *, t0=100.0, rate=5.0) -> str:
    """The drive as CARMEN ROBOTLASER1 lines (no echo: 81.91 m, as SICK's)."""
    step = float(angles[1] - angles[0])
    lines = []
    for k, (r, o) in enumerate(zip(ranges, odometry, strict=True)):
        values = " ".join("81.91" if not math.isfinite(v) else f"{v:.4f}" for v in r)
        pose = f"{o[0]:.6f} {o[1]:.6f} {o[2]:.6f}"
        t = t0 + k / rate
        lines.append(
            f"ROBOTLASER1 0 {angles[0]:.9f} {step * len(r):.9f} {step:.9f} {RANGE_MAX} 0.01 0 "
            f"{len(r)} {values} 0 {pose} {pose} 0 0 0 0 0 {t:.6f} test {t:.6f}"
        )
    return "\n".join(lines) + "\n"


def rmse(estimate, truth) -> float:
    """m: root mean square of the position errors."""
    d = np.asarray(estimate)[:, :2] - np.asarray(truth)[:, :2]
    return float(np.sqrt(np.mean(np.sum(d * d, axis=1))))


def flaser_line(ranges, odom, time):
    """A CARMEN FLASER line (its odometry also as the corrected pose)."""
    values = " ".join(f"{r:.2f}" for r in ranges)
    pose = " ".join(f"{v:.6f}" for v in odom)
    return f"FLASER {len(ranges)} {values} {pose} {pose} {time:.6f} host {time + 0.01:.6f}"


def robotlaser_line(ranges, start, resolution, odom, laser, time):
    """A CARMEN ROBOTLASER1 line with two remission values and a 30 m maximum."""
    values = " ".join(f"{r:.2f}" for r in ranges)
    pose = " ".join(f"{v:.6f}" for v in odom)
    lpose = " ".join(f"{v:.6f}" for v in laser)
    return (
        f"ROBOTLASER1 0 {start} {resolution * len(ranges)} {resolution} 30.0 0.01 0 "
        f"{len(ranges)} {values} 2 0.5 0.5 {lpose} {pose} 0.1 0.0 0.5 0.5 0.0 "
        f"{time:.6f} h {time:.6f}"
    )
