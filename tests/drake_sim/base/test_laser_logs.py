"""read_log's dispatch and checks, and TUM trajectories."""

import numpy as np
import pytest

from drake_sim.base import laser_logs as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.laser_scans import gmapping_angles
from tests import log_helpers as lh


def test_a_log_without_scans_or_file_is_refused(tmp_path):
    empty = tmp_path / "empty.clf"
    empty.write_text("ODOM 0 0 0 0 0 0 1 h 1\n")
    with pytest.raises(ConfigError, match="no laser scans"):
        mut.read_log(empty)
    with pytest.raises(ConfigError, match="no such log"):
        mut.read_log(tmp_path / "missing.clf")
    with pytest.raises(ConfigError, match="angles must be"):
        mut.read_log(empty, angles="sick")
    with pytest.raises(ConfigError, match="a CARMEN log has no topics"):
        mut.read_log(empty, scan_topic="/scan")


def test_gmapping_angles_replace_a_logs_own(tmp_path):
    path = tmp_path / "r.clf"
    path.write_text(lh.robotlaser_line([1.0] * 6, -0.3, 0.1, [0, 0, 0], [0, 0, 0], 1.0) + "\n")
    log = mut.read_log(path, angles="gmapping")
    np.testing.assert_allclose(log.scans[0].angles, gmapping_angles(6))


def test_a_tum_trajectory_round_trips(tmp_path):
    times = [1.5, 2.25]
    poses = [[1.0, 2.0, 0.0], [3.0, -1.0, 2.5]]
    path = mut.write_tum(tmp_path / "t.txt", times, poses)
    rows = np.loadtxt(path)
    np.testing.assert_allclose(rows[:, 0], times)
    np.testing.assert_allclose(rows[:, 1:3], [[1.0, 2.0], [3.0, -1.0]])
    assert np.all(rows[:, 3:6] == 0.0)
    yaw = 2.0 * np.arctan2(rows[:, 6], rows[:, 7])
    np.testing.assert_allclose(yaw, [0.0, 2.5])
    with pytest.raises(ConfigError, match="2 timestamps for 1 poses"):
        mut.write_tum(tmp_path / "u.txt", times, poses[:1])
    with pytest.raises(ConfigError, match="not finite"):
        mut.write_tum(tmp_path / "u.txt", [1.0], [[0.0, float("nan"), 0.0]])
