"""Recorded 2D laser logs, read without ROS: CARMEN logs and ROS 1 / ROS 2 bags.

A log becomes one ``LaserLog``: every scan in the file's order, each with the wheel odometry
of the same moment and the sensor's pose on the base, what an offline SLAM run (issue #40)
feeds scan by scan, as slam_toolbox and Cartographer do from a bag.

* **CARMEN** (``.clf``, ``.log``): ``FLASER`` lines (``FLASER n r_1 .. r_n x y theta odom_x
  odom_y odom_theta ipc_timestamp host logger_timestamp``) carry their own odometry; their beams
  lie at GMapping's angles, -90 deg + i * resolution, with the resolution 180 deg over the
  beam count rounded down to even (1 deg for 180 or 181 beams, 0.5 deg for 360 or 361).
  ``ROBOTLASER1`` lines give their start angle and resolution, the robot's odometry pose and
  the laser's (the first such line gives the sensor's pose on the base).
  Other lines (``ODOM``, ``PARAM``, ``SYNC``, comments) are skipped.
* **Bags** (ROS 1 ``.bag``; ROS 2 folders or files, sqlite3 or MCAP), read with ``rosbags``
  (pure Python): the ``sensor_msgs/LaserScan`` topic and the odometry (a ``nav_msgs/Odometry``
  topic, else the ``tf`` transform to the scan's base frame) are found by type unless named.
  A scan takes the latest odometry before it in the bag's order (a ROS 1 bag's written order:
  a log's stamps may run backwards, the order of recording does not; ``laser_bags``). The
  sensor's pose on the base comes from the bag's ``tf_static`` (or ``tf``), if it has it.

Ranges are as logged, with every reading at or beyond the scan's maximum (SICK's "no echo",
81.9 m) or not finite set to ``inf``: no return, which a mapper must not draw as an obstacle.
Timestamps are kept in file order, with the log's microseconds.
"""

import dataclasses as dc
import math
from pathlib import Path

import numpy as np

from drake_sim.base.carmen_logs import read_carmen
from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic
from drake_sim.base.laser_bags import read_bag
from drake_sim.base.laser_scans import LaserLog, gmapping_angles

CARMEN_SUFFIXES = (".clf", ".log")
"""File endings read as CARMEN logs; everything else is opened as a bag."""


def read_log(
    path: Path | str,
    *,
    scan_topic: str | None = None,
    odom_topic: str | None = None,
    angles: str = "log",
    range_max: float | None = None,
) -> LaserLog:
    """Reads a CARMEN log or a ROS bag (by its ending: ``CARMEN_SUFFIXES`` are CARMEN).

    Args:
        path: the log.
        scan_topic, odom_topic: a bag's topics (None: found by message type).
        angles: "log" (the scan's own angles) or "gmapping" (GMapping's angles for that many
            beams: the Kümmerle bags spread 180 beams over exactly 180 degrees).
        range_max: m, readings at or beyond it are "no return" (None: the scan's own maximum;
            CARMEN: 81.0 m, below SICK's 81.9 m "no echo").

    Raises:
        ConfigError: the file is missing, malformed, or has no scans; a named topic is absent
            (or named for a CARMEN log).
    """
    path = Path(path)
    if angles not in ("log", "gmapping"):
        raise ConfigError(f"angles must be 'log' or 'gmapping', got {angles!r}")
    if range_max is not None and not (math.isfinite(range_max) and range_max > 0):
        raise ConfigError(f"range_max must be a positive number of metres, got {range_max}")
    if not path.exists():
        raise ConfigError(f"{path}: no such log")
    if path.is_file() and path.suffix.lower() in CARMEN_SUFFIXES:
        if scan_topic is not None or odom_topic is not None:
            raise ConfigError(
                f"{path}: a CARMEN log has no topics (--scan-topic, --odom-topic go with a bag)"
            )
        log = read_carmen(path, range_max=81.0 if range_max is None else range_max)
    else:
        log = read_bag(path, scan_topic=scan_topic, odom_topic=odom_topic, range_max=range_max)
    if not log.scans:
        raise ConfigError(f"{path}: the log has no laser scans")
    if angles == "gmapping":
        scans = [dc.replace(s, angles=gmapping_angles(len(s.ranges))) for s in log.scans]
        log = dc.replace(log, scans=scans)
    return log


def write_tum(path: Path | str, times, poses) -> Path:
    """Writes a trajectory in TUM format (``timestamp x y z qx qy qz qw``, one line per pose;
    planar poses [x, y, yaw] at z = 0), atomically.

    Raises:
        ConfigError: times and poses of different lengths, or a value that is not finite.
    """
    times = np.asarray(times, dtype=float).reshape(-1)
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    if len(times) != len(poses):
        raise ConfigError(f"{path}: {len(times)} timestamps for {len(poses)} poses")
    if not (np.all(np.isfinite(times)) and np.all(np.isfinite(poses))):
        raise ConfigError(f"{path}: a trajectory with a value that is not finite")
    lines = [
        f"{t:.6f} {x:.6f} {y:.6f} 0 0 0 {math.sin(a / 2):.9f} {math.cos(a / 2):.9f}"
        for t, (x, y, a) in zip(times, poses, strict=True)
    ]
    return write_atomic(path, "".join(line + "\n" for line in lines), "trajectory")
