"""CARMEN logs (``.clf``, ``.log``) as ``LaserLog``: ``FLASER`` and ``ROBOTLASER1`` lines (see
``drake_sim.base.laser_logs`` for the formats); other lines are skipped.

A ``FLASER`` line does not say where its scanner's range ends: SICK scanners log about 81.9 m
where nothing returned, but ACES's scanner logs 50.00 m (11,139 of its 1.3 million readings;
the largest other one is 49.91). Read as hits, those would draw walls 50 m away. So a log's
largest reading, when it is at least ``NO_ECHO_SHARE`` of all of them and ``NO_ECHO_COUNT``
or more (no real surface is exactly as far away so often), counts as "no echo" too.
"""

import dataclasses as dc
from pathlib import Path

import numpy as np

from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic
from drake_sim.base.laser_scans import LaserLog, LaserScanRecord, gmapping_angles, no_echo_to_inf
from drake_sim.base.planar import relative_pose

NO_ECHO_SHARE, NO_ECHO_COUNT = 0.001, 100
"""A log's largest reading is "no echo" when at least this share of its readings, and this
many, are it (ACES: 0.8 %; MIT CSAIL's 81.91: 3.3 %)."""


def read_carmen(path: Path | str, *, range_max: float = 81.0) -> LaserLog:
    """Reads a CARMEN log's ``FLASER`` and ``ROBOTLASER1`` lines (see the module's notes).

    Raises:
        ConfigError: a laser line that is cut short or holds something that is not a number
            (file and line named), or a file that cannot be read as text.
    """
    path = Path(path)
    try:
        lines = path.read_text(errors="strict").splitlines()
    except (OSError, UnicodeDecodeError) as e:
        raise ConfigError(f"{path}: cannot read it as a CARMEN log ({e})") from None
    scans = []
    kinds = set()
    laser_pose = np.zeros(3)
    for number, line in enumerate(lines, 1):
        fields = line.split()
        if not fields or fields[0] not in ("FLASER", "ROBOTLASER1"):
            continue
        try:
            scan, laser = _carmen_scan(fields, range_max)
        except (ValueError, IndexError) as e:
            raise ConfigError(f"{path}:{number}: a malformed {fields[0]} line ({e})") from None
        if laser is not None and fields[0] not in kinds:  # the first ROBOTLASER1's offset
            laser_pose = relative_pose(scan.odometry, laser)
        scans.append(scan)
        kinds.add(fields[0])
    kind = "/".join(sorted(kinds)) or "FLASER"
    return LaserLog(path, _no_echo_at_the_maximum(scans), laser_pose, kind, kind)


def write_flaser(log: LaserLog, path: Path | str) -> Path:
    """Writes ``log`` as a CARMEN log of ``FLASER`` lines, as the Kümmerle datasets' ``.clf``
    files are (atomically): ranges in centimetres, no return as the scan's ``range_max``, the
    odometry as both poses (a scan with none before it takes the first the log has), the time
    with its microseconds. ``read_carmen`` reads it back, the ranges to the centimetre.

    Raises:
        ConfigError: a scan's beams are not at GMapping's angles (a ``FLASER`` line cannot
            carry others), or no scan has odometry.
    """
    first = next((s.odometry for s in log.scans if s.odometry is not None), None)
    if first is None:
        raise ConfigError(f"{path}: a FLASER line needs odometry, and the log has none")
    lines = ["# FLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta "
             "ipc_timestamp ipc_hostname logger_timestamp"]  # fmt: skip
    for scan in log.scans:
        count = len(scan.ranges)
        if count < 2 or not np.allclose(scan.angles, gmapping_angles(count), atol=1e-6):
            raise ConfigError(f"{path}: the scan at {scan.time} s is not at GMapping's angles")
        ranges = np.where(np.isfinite(scan.ranges), scan.ranges, scan.range_max)
        pose = " ".join(f"{v:.6f}" for v in (first if scan.odometry is None else scan.odometry))
        values = " ".join(f"{v:.2f}" for v in ranges)
        stamp = f"{scan.time:.6f}"
        lines.append(f"FLASER {count} {values} {pose} {pose} {stamp} drake_sim {stamp}")
    return write_atomic(path, "\n".join(lines) + "\n", "CARMEN log")


def _no_echo_at_the_maximum(scans: list[LaserScanRecord]) -> list[LaserScanRecord]:
    """``scans`` with the log's largest reading as no return if it is common enough (the
    module's notes), and each scan's ``range_max`` lowered to it."""
    if not scans:
        return scans
    ranges = np.concatenate([s.ranges for s in scans])
    finite = ranges[np.isfinite(ranges)]
    if not len(finite):
        return scans
    largest = finite.max()
    count = np.count_nonzero(finite == largest)
    if count < NO_ECHO_SHARE * len(ranges) or count < NO_ECHO_COUNT:
        return scans
    return [
        dc.replace(s, ranges=no_echo_to_inf(s.ranges, largest), range_max=min(s.range_max, largest))
        for s in scans
    ]


def _carmen_scan(fields: list[str], range_max: float) -> tuple[LaserScanRecord, list | None]:
    """(the scan, the laser's own pose in the odometry frame or None) of one laser line."""
    laser = None
    if fields[0] == "FLASER":
        count = int(fields[1])
        if count < 2:
            raise ValueError(f"{count} beams")
        ranges = [float(v) for v in fields[2 : 2 + count]]
        rest = fields[2 + count :]
        if len(ranges) != count or len(rest) < 7:
            raise ValueError("fewer fields than its beam count needs")
        odometry = [float(v) for v in rest[3:6]]
        time = float(rest[6])
        angles = gmapping_angles(count)
        maximum = range_max
    else:  # ROBOTLASER1 type start fov resolution max accuracy remission_mode n r.. m rem..
        start, resolution, maximum = float(fields[2]), float(fields[4]), float(fields[5])
        count = int(fields[8])
        ranges = [float(v) for v in fields[9 : 9 + count]]
        remissions = int(fields[9 + count])
        rest = fields[10 + count + remissions :]
        if len(ranges) != count or len(rest) < 12 or count < 1:
            raise ValueError("fewer fields than its beam counts need")
        laser, odometry = [float(v) for v in rest[0:3]], [float(v) for v in rest[3:6]]
        time = float(rest[11])
        angles = start + resolution * np.arange(count)
        maximum = min(maximum, range_max) if maximum > 0 else range_max
    values = np.array([*odometry, *(laser or ()), time])
    if not np.all(np.isfinite(values)):
        raise ValueError("a pose or time that is not finite")
    scan = LaserScanRecord(
        time=time,
        ranges=no_echo_to_inf(ranges, maximum),
        angles=np.asarray(angles, dtype=float),
        range_min=0.0,
        range_max=float(maximum),
        odometry=np.array(odometry),
    )
    return scan, laser
