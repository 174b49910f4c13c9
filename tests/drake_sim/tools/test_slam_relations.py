"""Kümmerle's relation metric: exact trajectories score 0, a known error is measured, missing
times are counted, malformed files are one line."""

import json
import math

import numpy as np
import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.base.laser_logs import write_tum
from drake_sim.base.planar import relative_pose
from drake_sim.tools import slam_relations as mut
from tests.cli_helpers import assert_bad_input, run_module

TIMES = np.array([10.0, 10.0004, 11.0, 9.5, 12.0])  # not sorted, two 0.4 ms apart
TRUTH = np.array(
    [[0.0, 0.0, 0.0], [0.05, 0.0, 0.01], [1.0, 0.5, 0.3], [-0.5, 0.2, -0.2], [2.0, 1.0, 1.2]]
)


def _relations_file(tmp_path, pairs, truth=TRUTH):
    lines = []
    for i, j in pairs:
        x, y, yaw = relative_pose(truth[i], truth[j])
        lines.append(f"{TIMES[i]:.6f} {TIMES[j]:.6f} {x:.9f} {y:.9f} 0 0 0 {yaw:.9f}")
    path = tmp_path / "r.relations"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_the_truth_scores_zero_and_a_shifted_pose_scores_its_shift(tmp_path):
    relations = mut.load_relations(_relations_file(tmp_path, [(0, 1), (1, 2), (3, 4), (0, 4)]))
    exact = mut.score(TIMES, TRUTH, relations)
    assert exact.relations == 4 and exact.missing == 0
    assert exact.trans_mean_m == pytest.approx(0.0, abs=1e-8)
    assert exact.rot_mean_deg == pytest.approx(0.0, abs=1e-6)
    wrong = TRUTH.copy()
    wrong[4] += [0.1, 0.0, math.radians(2.0)]  # the last pose 10 cm and 2 degrees off
    moved = mut.score(TIMES, wrong, relations)
    # (3, 4) and (0, 4) see it, each by 10 cm plus the rotation of nothing: 0.1 m, 2 degrees.
    errors = np.array([0.0, 0.0, 0.1, 0.1])
    assert moved.trans_mean_m == pytest.approx(errors.mean(), abs=1e-6)
    assert moved.trans_std_m == pytest.approx(errors.std(), abs=1e-6)
    assert moved.rot_mean_deg == pytest.approx(1.0, abs=1e-5)
    assert moved.rot2_mean_deg2 == pytest.approx(2.0, abs=1e-4)


def test_times_match_to_the_microsecond_and_missing_ones_are_counted(tmp_path):
    relations = mut.load_relations(_relations_file(tmp_path, [(0, 1), (2, 4)]))
    t_i, t_j, d = relations
    extra = (np.append(t_i, 50.0), np.append(t_j, 10.0), np.vstack([d, [1.0, 0.0, 0.0]]))
    result = mut.score(TIMES, TRUTH, extra)
    assert result.relations == 2 and result.missing == 1
    assert result.trans_mean_m == pytest.approx(0.0, abs=1e-8)  # 10.0 and 10.0004 not mixed
    nothing = mut.score(TIMES + 100.0, TRUTH, relations)
    assert nothing.relations == 0 and nothing.missing == 2 and math.isnan(nothing.trans_mean_m)


def test_the_command_scores_a_tum_file(tmp_path):
    relations = _relations_file(tmp_path, [(0, 1), (1, 2), (3, 4)])
    traj = write_tum(tmp_path / "t.txt", TIMES, TRUTH)
    out = tmp_path / "score.json"
    result = run_module("drake_sim.tools.slam_relations", traj, relations, "--json", out)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("3 relations (0 missing): translation 0.000 +- 0.000 m")
    assert json.loads(out.read_text())["relations"] == 3
    times, poses = mut.load_tum(traj)
    np.testing.assert_allclose(poses, TRUTH, atol=1e-6)


@pytest.mark.parametrize(
    ("text", "needle", "cli_needle"),
    [
        ("1 2 3\n", "r.relations:1: a relation is 8 numbers", None),
        ("# nothing\n", "no relations", None),
        ("", "no relations", "relations is empty"),
    ],
)
def test_a_malformed_relations_file_is_one_line(tmp_path, text, needle, cli_needle):
    path = tmp_path / "r.relations"
    path.write_text(text)
    traj = write_tum(tmp_path / "t.txt", TIMES, TRUTH)
    with pytest.raises(ConfigError, match=needle):
        mut.load_relations(path)
    result = run_module("drake_sim.tools.slam_relations", traj, path)
    assert_bad_input(result, cli_needle or needle)


def test_a_malformed_trajectory_is_one_line(tmp_path):
    relations = _relations_file(tmp_path, [(0, 1)])
    bad = tmp_path / "bad.txt"
    bad.write_text("1 2 3 nan 0 0 0 1\n")
    result = run_module("drake_sim.tools.slam_relations", bad, relations)
    assert_bad_input(result, "bad.txt:1: a TUM pose is 8 numbers")
