"""``python -m drake_sim.mapping --log FILE``: a recorded log mapped offline, its map, TUM
trajectory and report written; a stopped run keeps complete files; bad input is one line."""

import json
import signal
import subprocess
import sys

import numpy as np
import pytest

import drake_sim.mapping as mut_app
from drake_sim.base import cli
from drake_sim.base.map_files import load_map
from drake_sim.runs import log_mapping as mut
from tests import log_helpers as lh
from tests.cli_helpers import assert_bad_input, run_module


def _main(*args):
    return cli.run(mut_app.main, ["--headless", *args])


REPORT_KEYS = {
    "end", "log", "scan_topic", "odom_topic", "laser_pose", "scans", "log_duration_s",
    "wall_time_s", "real_time_factor", "loop_closures", "odometry_jumps", "rejected_matches",
    "map_size_m", "map_files", "trajectory",
}  # fmt: skip


@pytest.fixture(scope="module")
def drive():
    return lh.room_drive()


@pytest.fixture
def log_file(tmp_path, drive):
    truth, odometry, ranges, angles = drive
    path = tmp_path / "room.clf"
    path.write_text(lh.carmen_text(odometry, ranges, angles))
    return path


def test_a_carmen_log_is_mapped_with_its_trajectory_and_report(tmp_path, drive, log_file):
    truth = drive[0]
    out, traj, report = tmp_path / "maps" / "room", tmp_path / "traj.txt", tmp_path / "r.json"
    result = run_module(
        "drake_sim.mapping", "--log", log_file, "--out", out, "--trajectory", traj,
        "--report", report, "--headless",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    first, second = result.stdout.splitlines()[:2]
    assert first == "mapping room.clf headless (Ctrl-C stops)"
    assert second.startswith(f"done: {len(truth)} of {len(truth)} scans")
    rows = np.loadtxt(traj)
    assert rows.shape == (len(truth), 8)
    np.testing.assert_allclose(rows[:, 0], 100.0 + np.arange(len(truth)) / 5.0, atol=1e-6)
    assert lh.rmse(rows[:, 1:3], truth) < 0.03
    data = json.loads(report.read_text())
    assert set(data) == REPORT_KEYS
    assert data["end"] == "done" and data["scans"] == len(truth) and data["loop_closures"] == 0
    assert data["log_duration_s"] == pytest.approx((len(truth) - 1) / 5.0)
    assert data["real_time_factor"] > 0 and data["scan_topic"] == "ROBOTLASER1"
    grid = load_map(out.with_suffix(".yaml"))
    assert data["map_files"] == [str(out.with_suffix(".pgm")), str(out.with_suffix(".yaml"))]
    assert grid.occupied().sum() > 100 and grid.free().sum() > 1000


def test_a_stopped_run_writes_partial_files_and_keeps_complete_ones(
    tmp_path, log_file, monkeypatch
):
    out, traj = tmp_path / "room", tmp_path / "traj.txt"
    args = ["--log", log_file, "--out", out, "--trajectory", traj, "--headless"]
    assert run_module("drake_sim.mapping", *args).returncode == 0
    before = (out.with_suffix(".pgm").read_bytes(), traj.read_text())
    calls = []
    monkeypatch.setattr(cli, "stop_received", lambda: len(calls.append(0) or calls) > 30)
    result = run_module("drake_sim.mapping", *args)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[1].startswith("stopped: 30 of")
    assert (out.with_suffix(".pgm").read_bytes(), traj.read_text()) == before
    assert len(np.loadtxt(tmp_path / "traj.partial.txt")) == 30
    assert (tmp_path / "room.partial.yaml").is_file()


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--trajectory", "t.txt"], "--trajectory goes with --log FILE"),
        (["--no-loop-closure"], "--no-loop-closure goes with --log FILE"),
        (["--log", "LOG", "--start", "0", "0", "0"], "--start is for a simulated run"),
        (["--log", "LOG", "--laser-pose", "0", "nan", "0"], "--laser-pose must be finite"),
        (["--log", "LOG", "--scan-topic", "/scan"], "--odom-topic go with a bag"),
    ],
)
def test_bad_options_are_one_line(tmp_path, log_file, args, needle):
    args = [str(log_file) if a == "LOG" else a for a in args]
    assert_bad_input(run_module("drake_sim.mapping", *args, "--headless", cwd=tmp_path), needle)


def test_the_trajectory_is_the_base_s_or_the_sensor_s(tmp_path, log_file):
    base, sensor = tmp_path / "base.txt", tmp_path / "sensor.txt"
    args = ["--log", str(log_file), "--laser-pose", "0.1", "0", "90", "--out"]
    assert _main(*args, str(tmp_path / "a"), "--trajectory", str(base)) == 0
    frame = ["--trajectory-frame", "sensor"]
    assert _main(*args, str(tmp_path / "b"), "--trajectory", str(sensor), *frame) == 0
    b, s = np.loadtxt(base), np.loadtxt(sensor)
    yaw = 2 * np.arctan2(b[:, 6], b[:, 7])
    np.testing.assert_allclose(s[:, 1], b[:, 1] + 0.1 * np.cos(yaw), atol=2e-6)
    np.testing.assert_allclose(s[:, 2], b[:, 2] + 0.1 * np.sin(yaw), atol=2e-6)
    turned = 2 * np.arctan2(s[:, 6], s[:, 7])
    np.testing.assert_allclose(np.cos(turned - yaw), 0.0, atol=1e-6)  # 90 degrees on


def test_with_the_viewer_the_map_stays_on_the_page_until_ctrl_c(tmp_path, log_file):
    process = subprocess.Popen(
        [sys.executable, "-m", "drake_sim.mapping", "--log", str(log_file), "--out",
         str(tmp_path / "room")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        lines = []
        while not lines or not lines[-1].startswith("showing the map at http"):
            line = process.stdout.readline()
            assert line, process.stderr.read()
            lines.append(line.strip())
        assert lines[0].startswith("mapping room.clf at http") and lines[1].startswith("done:")
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 0 and "Traceback" not in err, err
    assert (tmp_path / "room.yaml").is_file()


def test_a_malformed_log_is_one_line_from_a_real_process(tmp_path):
    bad = tmp_path / "bad.clf"
    bad.write_text("FLASER 3 1.0 2.0\n")
    result = subprocess.run(
        [sys.executable, "-m", "drake_sim.mapping", "--log", str(bad), "--headless"],
        capture_output=True, text=True, cwd=tmp_path, check=False,
    )  # fmt: skip
    assert_bad_input(result, "bad.clf:1: a malformed FLASER line")
    assert not (tmp_path / "maps").exists()


def test_the_log_names_the_default_map():
    from pathlib import Path

    assert mut._name(Path("data/intel.orig.bag")) == "intel"
    assert mut._name(Path("run.clf")) == "run"
    assert mut._name(Path("rosbag2_2024")) == "rosbag2_2024"
