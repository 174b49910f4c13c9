"""A recorded 2D laser log's scans (``LaserLog``), what ``drake_sim.base.laser_logs`` reads
from CARMEN logs and ROS bags, and the two conventions of such logs every reader shares:
GMapping's beam angles and "no echo" readings as ``inf``."""

import dataclasses as dc
import math
from pathlib import Path

import numpy as np

from drake_sim.base.errors import ConfigError


@dc.dataclass(frozen=True)
class LaserScanRecord:
    """One scan of a log.

    Attributes:
        time: s, the scan's timestamp as logged.
        ranges: (k,) m, ``inf`` where the beam saw nothing.
        angles: (k,) rad, each beam's direction in the sensor frame.
        range_min, range_max: m, the scan's limits.
        odometry: [x, y, yaw] of the base from the log's odometry at this scan (m, m, rad), or
            None when the log has none before it.
    """

    time: float
    ranges: np.ndarray
    angles: np.ndarray
    range_min: float
    range_max: float
    odometry: np.ndarray | None


@dc.dataclass(frozen=True)
class LaserLog:
    """A log's scans in file order, and where they came from.

    Attributes:
        path: the file read.
        scans: the scans, in the order of the file.
        laser_pose: [x, y, yaw] of the sensor in the base frame (m, m, rad).
        scan_topic, odom_topic: what was read ("FLASER"/"ROBOTLASER1" for CARMEN).
    """

    path: Path
    scans: list[LaserScanRecord]
    laser_pose: np.ndarray
    scan_topic: str
    odom_topic: str

    @property
    def duration(self) -> float:
        """s from the first scan's time to the last's (their file order; 0 for one scan)."""
        if not self.scans:
            return 0.0
        times = [s.time for s in self.scans]
        return float(max(times) - min(times))


def gmapping_angles(count: int) -> np.ndarray:
    """(count,) rad: GMapping's beam angles for a CARMEN ``FLASER`` line of ``count`` beams."""
    if count < 2:
        raise ConfigError(f"a FLASER line needs at least 2 beams, got {count}")
    resolution = math.pi / (2 * (count // 2))
    return -math.pi / 2 + resolution * np.arange(count)


def no_echo_to_inf(ranges, range_max: float) -> np.ndarray:
    """A float copy of ``ranges`` with readings at or beyond ``range_max``, or not finite, or
    negative, as ``inf`` (no return)."""
    r = np.array(ranges, dtype=float)
    with np.errstate(invalid="ignore"):
        r[~np.isfinite(r) | (r >= range_max) | (r < 0.0)] = np.inf
    return r
