"""CARMEN logs as LaserLog: FLASER and ROBOTLASER1 lines, file order, malformed lines named."""

import dataclasses as dc
import math

import numpy as np
import pytest

from drake_sim.base import carmen_logs as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.laser_scans import gmapping_angles
from tests import log_helpers as lh


def test_a_carmen_log_reads_in_file_order_with_its_odometry(tmp_path):
    ranges = [1.0, 2.0, 81.91, 3.0]
    lines = [
        "# a comment",
        "PARAM robot_front_laser_max 81.9 host 0",
        "ODOM 0.1 0.2 0.3 0 0 0 5.0 host 5.0",
        lh.flaser_line(ranges, [1.0, 2.0, 0.5], 10.000001),
        lh.flaser_line(ranges, [1.5, 2.0, 0.6], 9.5),  # stamped earlier: file order stays
        lh.robotlaser_line([1.0, 2.0, 3.0], -0.5, 0.5, [3.0, 4.0, 1.0], [3.1, 4.0, 1.0], 11.25),
    ]
    path = tmp_path / "run.clf"
    path.write_text("\n".join(lines) + "\n")
    log = mut.read_carmen(path)
    assert [s.time for s in log.scans] == [10.000001, 9.5, 11.25]
    first = log.scans[0]
    np.testing.assert_allclose(first.odometry, [1.0, 2.0, 0.5])
    assert math.isinf(first.ranges[2]) and first.ranges[3] == 3.0
    np.testing.assert_allclose(first.angles, gmapping_angles(4))
    robot = log.scans[2]
    np.testing.assert_allclose(robot.angles, [-0.5, 0.0, 0.5])
    np.testing.assert_allclose(robot.odometry, [3.0, 4.0, 1.0])
    assert robot.range_max == 30.0
    np.testing.assert_allclose(log.laser_pose, [0.1 * math.cos(1.0), -0.1 * math.sin(1.0), 0.0])
    assert log.duration == pytest.approx(1.75)


@pytest.mark.parametrize(
    "line",
    [
        "FLASER 4 1.0 2.0 3.0",  # cut short
        "FLASER 2 1.0 abc 0 0 0 0 0 0 1.0 h 1.0",  # not a number
        "FLASER 2 1.0 2.0 0 0 0 0 nan 0 1.0 h 1.0",  # odometry not finite
    ],
)
def test_a_malformed_laser_line_is_named(tmp_path, line):
    path = tmp_path / "bad.log"
    path.write_text(lh.flaser_line([1.0, 2.0], [0, 0, 0], 1.0) + "\n" + line + "\n")
    with pytest.raises(ConfigError, match=r"bad.log:2: a malformed FLASER line"):
        mut.read_carmen(path)


def test_a_log_whose_largest_reading_recurs_takes_it_for_no_echo(tmp_path):
    """ACES's scanner logs 50.00 m where nothing returned: so often that it is no surface."""
    rng = np.random.default_rng(0)
    lines = []
    for k in range(200):
        ranges = np.round(rng.uniform(0.5, 49.9, 180), 2)
        ranges[k % 7 :: 90] = 50.0  # two beams a scan see nothing
        lines.append(lh.flaser_line(ranges, [0.1 * k, 0.0, 0.0], 1.0 + 0.2 * k))
    path = tmp_path / "aces.clf"
    path.write_text("\n".join(lines) + "\n")
    log = mut.read_carmen(path)
    first = log.scans[0]
    assert np.isinf(first.ranges[0::90]).all() and np.isfinite(first.ranges).sum() == 178
    assert first.range_max == 50.0 and first.ranges[np.isfinite(first.ranges)].max() < 50.0
    # ...but not a reading that a few beams share: the 81.91 m rule alone applies.
    few = tmp_path / "few.clf"
    few.write_text("\n".join(lines[:2]) + "\n")
    assert np.isfinite(mut.read_carmen(few).scans[0].ranges).all()


def test_a_log_written_as_flaser_lines_reads_back_to_the_centimetre(tmp_path):
    from drake_sim.base.laser_scans import LaserLog, LaserScanRecord

    rng = np.random.default_rng(1)
    scans = []
    for k in range(3):
        ranges = rng.uniform(0.2, 20.0, 181)
        ranges[5 + k] = np.inf
        odometry = None if k == 0 else np.array([0.1 * k, -0.2, 0.3 * k])
        scans.append(
            LaserScanRecord(10.0 + k * 0.123457, ranges, gmapping_angles(181), 0.0, 81.91, odometry)
        )
    log = LaserLog(tmp_path / "in.bag", scans, np.zeros(3), "/scan", "/odom")
    back = mut.read_carmen(mut.write_flaser(log, tmp_path / "out.clf"))
    assert [s.time for s in back.scans] == [s.time for s in scans]
    for original, read in zip(scans, back.scans, strict=True):
        finite = np.isfinite(original.ranges)
        np.testing.assert_array_equal(np.isfinite(read.ranges), finite)
        np.testing.assert_allclose(read.ranges[finite], original.ranges[finite], atol=0.005)
        np.testing.assert_allclose(read.angles, original.angles)
    np.testing.assert_allclose(back.scans[0].odometry, scans[1].odometry)  # the first there is
    np.testing.assert_allclose(back.scans[2].odometry, scans[2].odometry)
    other = dc.replace(log, scans=[dc.replace(scans[1], angles=np.linspace(-1, 1, 181))])
    with pytest.raises(ConfigError, match="not at GMapping's angles"):
        mut.write_flaser(other, tmp_path / "other.clf")
