"""The independent path audit (drake_sim.tools.path_audit): it finds a segment that touches a
box between the planner's samples, from other sampling offsets; values go to joints by name,
not by position; a benchmark report's solved rows are audited against their MBM problems; and
bad input is a one-line error (exit 2)."""

import json

import numpy as np
import pytest

import drake_sim.tools.path_audit as mut
from planning import PlanningScene
from tests.graze_helpers import JOINT_NAMES, grazing_segment


@pytest.fixture(scope="module")
def grazing():
    scene = PlanningScene()
    q_a, q_b, target = grazing_segment(scene)
    return scene, q_a, q_b, target


def test_samples_run_from_every_offset_and_keep_both_ends():
    s = mut.segment_samples(0.025, 0.01, 2)
    np.testing.assert_allclose(s, [0.0, 0.005, 0.01, 0.015, 0.02, 0.025])
    assert list(mut.segment_samples(0.0, 0.01, 4)) == [0.0]


def test_the_audit_finds_a_touch_between_the_planners_samples(grazing):
    _, q_a, q_b, target = grazing
    # The planner's own samples (every 0.01 rad from q_a) miss it; other offsets find it.
    assert mut.audit_path(target, [q_a, q_b], JOINT_NAMES, offsets=1)[0] == np.inf
    distance, pair, segment, at, _ = mut.audit_path(target, [q_a, q_b], JOINT_NAMES, offsets=4)
    assert -1e-4 < distance < 0.0
    assert pair == "panda_hand <-> world/blade"
    assert segment == 0 and 0.04 < at < 0.06


def test_joint_values_go_by_name(grazing):
    _, q_a, q_b, target = grazing
    order = np.arange(7)[::-1]
    names = [JOINT_NAMES[k] for k in order]
    path = np.vstack([q_a, q_b])[:, order]
    assert mut.audit_path(target, path, names, offsets=4)[0] < 0.0


def test_a_path_that_does_not_fit_its_names_is_refused(grazing):
    _, q_a, q_b, target = grazing
    with pytest.raises(ValueError, match="7 joints"):
        mut.audit_path(target, [q_a[:6], q_b[:6]], JOINT_NAMES)


def test_a_report_is_audited_against_its_problems(tmp_path, mbm_folder):
    scene = PlanningScene()
    target = mut.planning_scene_target(scene)
    problem = next(p for p in mut_problems(mbm_folder))
    request = mut._request_joints(problem.request_file)
    start = np.array([request[n] for n in JOINT_NAMES])
    rows = [
        {
            "family": problem.family,
            "problem": problem.number,
            "success": True,
            "path": [start.tolist(), start.tolist()],
            "joint_names": JOINT_NAMES,
        },
        {"family": problem.family, "problem": problem.number, "success": False, "path": None},
    ]
    audited, touches = mut.audit_rows(rows, mbm_folder, target)
    assert (audited, touches) == (1, [])
    report = tmp_path / "report.json"
    report.write_text(json.dumps(rows))
    assert mut.main([str(report), "--dataset", str(mbm_folder), "--offsets", "2"]) == 0


def mut_problems(folder):
    from planning.io import mbm

    return mbm.iter_problems(folder, ["box_panda"], 1)


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    report = tmp_path / "report.json"
    report.write_text("{not json")
    assert mut.main([str(report)]) == 2
    assert "not a benchmark report" in capsys.readouterr().err
    report.write_text(json.dumps([{"family": "box_panda", "problem": 1, "success": True}]))
    assert mut.main([str(report)]) == 2
    rows = [{"family": "box_panda", "problem": 1, "success": True, "path": [[0.0] * 7]}]
    with pytest.raises(mut.ConfigError, match="joint_names"):
        mut.audit_rows(rows, tmp_path, None)
