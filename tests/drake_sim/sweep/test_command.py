import signal
import subprocess
import sys
import time

import pytest

from drake_sim.base import cli
from drake_sim.sweep import command as mut
from drake_sim.sweep.table import TABLE_FILE, read_rows
from tests.cli_helpers import assert_bad_input
from tests.drake_sim.sweep.sweep_files import tiny_flip, write_sweep

METRICS = ("flips", "travel_extent_m", "odometry_error_m")


def sweep(argv):
    return cli.run(mut.main, [str(a) for a in argv])


def rows_of(folder):
    return sorted(read_rows(folder / TABLE_FILE)[1], key=lambda r: r["index"])


def test_bad_input_is_one_line_and_exit_2(tmp_path):
    path = write_sweep(tmp_path, "runner: flip\nparameters: {robot.body.mas: {grid: [1]}}\n")
    result = subprocess.run(
        [sys.executable, "-m", "drake_sim.sweep", str(path), "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert_bad_input(result, "unknown parameter path 'body.mas'")
    assert not (tmp_path / "o").exists()  # checked before anything ran or was written


@pytest.mark.parametrize(
    "text, needle",
    [
        ("runner: walker\n", "unknown runner 'walker'"),
        ("runner: flip\nparameters: {a.b: {uniform: [3, 1]}}\n", "needs low < high"),
        ("runner: flip\nparameters: {imu.rate: {normal: [1, -2]}}\n", "needs sigma >= 0"),
        ("runner: flip\nparameters: {imu.rate: {grid: []}}\n", "grid needs a non-empty list"),
        ("runner: flip\nparameters: {imu.rate: {grid: [.nan]}}\n", "must be finite"),
    ],
)
def test_bad_sweep_files(tmp_path, capsys, text, needle):
    assert sweep([write_sweep(tmp_path, text), "--out", tmp_path / "o"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: ") and needle in err


@pytest.mark.parametrize(
    "argv, needle",
    [
        ([], "give a sweep file, or --plot DIR"),
        (["missing.yaml"], "sweep file not found: missing.yaml"),
        (["{sweep}", "--workers", "0"], "must be >= 1"),
        (["{sweep}", "--backend", "slurm"], "invalid choice: 'slurm'"),
        (["{sweep}", "--address", "auto"], "--address is for --backend ray"),
        (["--plot", "{sweep}"], "--plot: not a folder"),
    ],
)
def test_bad_command_lines(tmp_path, capsys, argv, needle):
    path = tiny_flip(tmp_path)
    argv = [a.format(sweep=path) for a in argv]
    assert sweep([*argv, "--out", tmp_path / "o"] if argv else argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err
    assert not (tmp_path / "o").exists()  # nothing written on bad input


def test_ray_not_installed_fails_before_the_plan_and_the_table(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray fails
    out = tmp_path / "o"
    assert sweep([tiny_flip(tmp_path), "--backend", "ray", "--out", out]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""  # no run plan
    assert captured.err.count("\n") == 1 and "--backend ray: Ray is not installed" in captured.err
    assert not out.exists()  # no results.csv, no sweep.json
    out.mkdir()
    (out / TABLE_FILE).write_text("kept\n")
    assert sweep([tiny_flip(tmp_path), "--backend", "ray", "--out", out, "--resume"]) == 2
    assert (out / TABLE_FILE).read_text() == "kept\n"
    assert sorted(p.name for p in out.iterdir()) == [TABLE_FILE]


def test_tiny_sweep_limit_then_resume(tmp_path, capsys):
    path, out = tiny_flip(tmp_path, repeats=2), tmp_path / "out"
    assert sweep([path, "--workers", "2", "--out", out, "--limit", "2"]) == 0
    first = rows_of(out)
    assert [r["index"] for r in first] == [0, 1]
    assert all(r["status"] == "ok" and r["success"] is True for r in first)
    assert [r["flip.drive_speed"] for r in first] == [0.6, 0.6]
    assert all(isinstance(r[m], int | float) for r in first for m in METRICS)
    assert "rollouts 2 (ok 2, failed 0)" in capsys.readouterr().out
    assert sweep([path, "--workers", "2", "--out", out]) == 2  # never overwrites
    assert "pass --resume" in capsys.readouterr().err
    assert sweep([path, "--workers", "2", "--out", out, "--resume"]) == 0
    text = capsys.readouterr().out
    assert "2 of 4 rollouts to run" in text and "success 4/4" in text
    second = rows_of(out)
    assert [r["index"] for r in second] == [0, 1, 2, 3]
    assert second[:2] == first  # not recomputed: same wall times, same workers
    complete = (out / TABLE_FILE).read_bytes()
    assert sweep([path, "--out", out, "--resume"]) == 0  # nothing left to run
    assert "0 of 4 rollouts to run" in capsys.readouterr().out
    assert (out / TABLE_FILE).read_bytes() == complete
    assert (out / "summary.json").is_file() and (out / "sweep.json").is_file()


def test_failed_rollouts_are_rows(tmp_path, capsys):
    path = write_sweep(
        tmp_path,
        "runner: flip\noptions: {duration: 0.2}\n"
        "parameters: {robot.body.mass: {grid: [-1.0, 2.5]}}\nmetrics: [flips]\nsuccess: finite\n",
    )
    assert sweep([path, "--workers", "1", "--out", tmp_path / "o"]) == 0
    rows = rows_of(tmp_path / "o")
    assert [r["status"] for r in rows] == ["failed", "ok"]
    assert "'body.mass' must be finite and > 0" in rows[0]["reason"]
    assert rows[0]["success"] is False and rows[1]["success"] is True
    assert "success 1/2" in capsys.readouterr().out


def test_ctrl_c_keeps_finished_rows_and_resume_reruns_none(tmp_path):
    # About 0.2 s of work per rollout: the stop lands with most of the ten still to run.
    path, out = tiny_flip(tmp_path, duration=4.0, repeats=5), tmp_path / "out"
    argv = [sys.executable, "-m", "drake_sim.sweep", str(path), "--workers", "1"]
    proc = subprocess.Popen(
        [*argv, "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline and len(read_rows(out / TABLE_FILE)[1]) < 1:
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 0, stderr
    assert "stopped: " in stdout and "(--resume continues)" in stdout
    assert "Traceback" not in stderr
    stopped = rows_of(out)
    assert 1 <= len(stopped) < 10
    resumed = subprocess.run(
        [*argv, "--out", str(out), "--resume"], capture_output=True, text=True, timeout=120
    )
    assert resumed.returncode == 0, resumed.stderr
    assert f"{10 - len(stopped)} of 10 rollouts to run" in resumed.stdout
    final = rows_of(out)
    assert [r["index"] for r in final] == list(range(10))
    assert [r for r in final if r["index"] in {s["index"] for s in stopped}] == stopped


def test_plot_command(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    path, out = tiny_flip(tmp_path, duration=0.2), tmp_path / "out"
    assert sweep([path, "--workers", "1", "--out", out]) == 0
    assert sweep(["--plot", out]) == 0
    assert "success.png" in capsys.readouterr().out
    assert (out / "hist_flips.png").is_file()
    assert (out / "odometry_error_m_vs_flip.drive_speed.png").is_file()


def test_local_and_ray_give_the_same_table(tmp_path):
    pytest.importorskip("ray")
    path = tiny_flip(tmp_path, duration=0.5)
    assert sweep([path, "--workers", "2", "--out", tmp_path / "local"]) == 0
    assert sweep([path, "--backend", "ray", "--workers", "2", "--out", tmp_path / "ray"]) == 0
    local, ray = rows_of(tmp_path / "local"), rows_of(tmp_path / "ray")
    keep = ("index", "status", "success", "seed", "flip.drive_speed", *METRICS)
    assert [{k: r[k] for k in keep} for r in local] == [{k: r[k] for k in keep} for r in ray]
    assert all(r["status"] == "ok" for r in ray)
