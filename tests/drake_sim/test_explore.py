"""``python -m drake_sim.explore``: the command line, its report and exit codes."""

import json
import subprocess
import sys

import pytest

from tests.cli_helpers import assert_bad_input, run_module
from tests.drake_sim.runs.test_explore import SMALL_ROOM

REPORT_KEYS = {
    "end",
    "known_fraction",
    "map_iou",
    "pose_rmse_m",
    "distance_m",
    "sim_time_s",
    "collisions",
    "min_clearance_m",
    "frontiers_visited",
    "wall_time_s",
    "real_time_factor",
}


def test_a_small_room_is_explored_from_the_command_line(tmp_path):
    arena = tmp_path / "small.yaml"
    arena.write_text(SMALL_ROOM)
    report_file, out = tmp_path / "report.json", tmp_path / "maps" / "small"
    result = subprocess.run(
        [sys.executable, "-m", "drake_sim.explore", "--headless", "--arena", str(arena),
         "--report", str(report_file), "--out", str(out), "--seed", "3"],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    report = json.loads(report_file.read_text())
    assert report.keys() >= REPORT_KEYS
    assert report["end"] == "explored" and report["seed"] == 3
    assert report["known_fraction"] >= 0.95 and report["collisions"] == 0
    assert (out.parent / "small.yaml").is_file() and (out.parent / "small.pgm").is_file()
    assert "ended by explored" in result.stdout


def test_out_of_time_exits_1_with_one_line(tmp_path):
    arena = tmp_path / "small.yaml"
    arena.write_text(SMALL_ROOM)
    result = run_module(
        "drake_sim.explore", "--headless", "--arena", arena, "--time-limit", "2",
        "--out", tmp_path / "m",
    )  # fmt: skip
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "not explored in the time limit" in lines[0]
    assert (tmp_path / "m.partial.yaml").is_file() and not (tmp_path / "m.yaml").exists()


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--time-limit", "-5"], "--time-limit"),
        (["--arena", "no_such_arena.yaml"], "no_such_arena.yaml"),
        (["--start", "0", "0", "0"], "--start"),
        (["--set", "exploration.approach=0"], "approach"),
        (["--set", "exploration.nonsense=1"], "nonsense"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(args, needle):
    assert_bad_input(run_module("drake_sim.explore", "--headless", *args), needle)
