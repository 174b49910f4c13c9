"""read_log's dispatch and checks, and TUM trajectories."""

import numpy as np
import pytest

from drake_sim.base import laser_logs as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.laser_scans import gmapping_angles


def _flaser(ranges, odom, time):
    values = " ".join(f"{r:.2f}" for r in ranges)
    pose = " ".join(f"{v:.6f}" for v in odom)
    return f"FLASER {len(ranges)} {values} {pose} {pose} {time:.6f} host {time + 0.01:.6f}"


def _robotlaser(ranges, start, resolution, odom, laser, time):
    values = " ".join(f"{r:.2f}" for r in ranges)
    pose = " ".join(f"{v:.6f}" for v in odom)
    lpose = " ".join(f"{v:.6f}" for v in laser)
    return (
        f"ROBOTLASER1 0 {start} {resolution * len(ranges)} {resolution} 30.0 0.01 0 "
        f"{len(ranges)} {values} 2 0.5 0.5 {lpose} {pose} 0.1 0.0 0.5 0.5 0.0 "
        f"{time:.6f} h {time:.6f}"
    )


def test_a_log_without_scans_or_file_is_refused(tmp_path):
    empty = tmp_path / "empty.clf"
    empty.write_text("ODOM 0 0 0 0 0 0 1 h 1\n")
    with pytest.raises(ConfigError, match="no laser scans"):
        mut.read_log(empty)
    with pytest.raises(ConfigError, match="no such log"):
        mut.read_log(tmp_path / "missing.clf")
    with pytest.raises(ConfigError, match="angles must be"):
        mut.read_log(empty, angles="sick")


def test_gmapping_angles_replace_a_logs_own(tmp_path):
    path = tmp_path / "r.clf"
    path.write_text(_robotlaser([1.0] * 6, -0.3, 0.1, [0, 0, 0], [0, 0, 0], 1.0) + "\n")
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
