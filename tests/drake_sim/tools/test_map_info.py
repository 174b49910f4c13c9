"""``python -m drake_sim.tools.map_info``: a saved map described and scored; bad map files."""

import subprocess
import sys

import numpy as np
import pytest

import drake_sim.tools.map_info as mut
from drake_sim.base import cli
from drake_sim.base.map_files import OccupancyMap, save_map
from drake_sim.base.resources import config_dir
from drake_sim.robots.turtlebot3 import default_turtlebot3_file
from drake_sim.robots.turtlebot3_params import load_turtlebot3_params
from drake_sim.worlds.arena import arena_grid, load_arena
from tests.cli_helpers import assert_bad_input

ROOM = config_dir() / "arenas" / "room.yaml"


@pytest.fixture(scope="module")
def truth_files(tmp_path_factory):
    """The room's ground truth saved as map_server files: a perfect map."""
    height = load_turtlebot3_params(default_turtlebot3_file()).scan_height
    truth = arena_grid(load_arena(ROOM), 0.05, height=height)
    return save_map(truth, tmp_path_factory.mktemp("maps") / "room")


def test_describe_counts_the_cells():
    cells = np.array([[-1, 0, 0], [100, 0, -1]], dtype=np.int8)
    text = mut.describe(OccupancyMap(cells=cells, resolution=0.5, origin=(1.0, -2.0, 0.0)))
    assert text.startswith("3 x 2 cells (1.50 x 1.00 m) at 0.5 m, origin (1.000, -2.000, 0.000)")
    assert text.endswith("3 free, 1 occupied, 2 unknown")


def test_a_perfect_map_scores_one_against_its_arena(truth_files, capsys):
    _, yaml_file = truth_files
    assert cli.run(mut.main, [str(yaml_file), "--arena", str(ROOM)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert "cells" in out[0]
    assert "map IoU 1.000, known 100.0 %" in out[1]


def _run(*args):
    return subprocess.run(
        [sys.executable, "-m", "drake_sim.tools.map_info", *args],
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_unreadable_map_files_are_one_line_and_exit_2(truth_files, tmp_path):
    pgm, yaml_file = truth_files
    assert_bad_input(_run(str(tmp_path / "missing.yaml")), "missing.yaml")
    truncated = tmp_path / "room.pgm"
    truncated.write_bytes(pgm.read_bytes()[:200])
    (tmp_path / "room.yaml").write_text(yaml_file.read_text())
    assert_bad_input(_run(str(tmp_path / "room.yaml")), "room.pgm")
    bad_yaml = tmp_path / "bad.yaml"
    bad_yaml.write_text(yaml_file.read_text().replace("resolution: 0.05", "resolution: -0.05"))
    assert_bad_input(_run(str(bad_yaml)), "resolution")
    no_image = tmp_path / "no_image.yaml"
    no_image.write_text(yaml_file.read_text().replace("room.pgm", "nowhere.pgm"))
    assert_bad_input(_run(str(no_image)), "nowhere.pgm")
