"""python -m planning.benchmark: one MBM problem end to end, the report rows, bad input."""

import json
from pathlib import Path

import numpy as np
import pytest

import planning.benchmark as mut
from planning import PlanningScene
from planning.io import mbm

DATASET = mbm.default_dataset()  # the repository's copy: benchmarks/data/mbm_panda


def test_one_problem_report(tmp_path, capsys):
    report = tmp_path / "report.json"
    # No --dataset: the repository's own copy is the default.
    code = mut.main(
        [
            "--families",
            "box_panda",
            "--limit",
            "1",
            "--report",
            str(report),
        ]
    )
    assert code == 0
    rows = json.loads(report.read_text())
    assert len(rows) == 1
    row = rows[0]
    for key in (
        "family",
        "problem",
        "valid",
        "success",
        "time_s",
        "path_length",
        "path_valid_fine",
        "path",
    ):
        assert key in row
    assert row["family"] == "box_panda" and row["problem"] == 1
    assert row["valid"] and row["success"] and row["path_valid_fine"]
    path = np.asarray(row["path"])
    assert path.shape[1] == 7
    assert row["path_length"] == pytest.approx(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
    # The path can be re-checked by anyone: check it here with the scene's own queries.
    folder = mut.problems_folder(DATASET)
    scene = PlanningScene()
    scene.load_moveit(folder / "box_panda/scene0001.yaml")
    request = mbm.load_request(folder / "box_panda/request0001.yaml")
    scene.finger_positions = request.q_start[7:]
    np.testing.assert_allclose(path[0], request.q_start[:7])
    np.testing.assert_allclose(path[-1], request.q_goal[:7])
    for a, b in zip(path[:-1], path[1:], strict=True):
        n = int(np.ceil(np.linalg.norm(b - a) / 0.01))
        assert all(scene.is_collision_free(a + s * (b - a)) for s in np.linspace(0, 1, n + 1))
    assert "box_panda" in capsys.readouterr().out


def test_dataset_may_be_the_archive_its_folder_or_the_problems(tmp_path):
    archive = DATASET / "problems.tar.bz2"
    assert DATASET.is_relative_to(Path(mut.__file__).resolve().parents[1])  # inside the checkout
    folder = mut.problems_folder(DATASET)
    assert (folder / "box_panda" / "scene0001.yaml").is_file()
    assert mut.problems_folder(archive) == folder
    assert mut.problems_folder(folder) == folder
    assert mut.problems_folder(folder.parent) == folder
    with pytest.raises(FileNotFoundError):
        mut.problems_folder(tmp_path)


def test_default_dataset_missing_exits_2(monkeypatch, capsys):
    def missing():
        raise FileNotFoundError("MBM problems not found")

    monkeypatch.setattr(mut.mbm, "default_dataset", missing)
    assert mut.main(["--limit", "1"]) == 2
    assert "MBM problems not found" in capsys.readouterr().err


def test_bad_arguments_exit_2(capsys):
    assert mut.main(["--families", "nowhere"]) == 2
    assert mut.main(["--dataset", "/nonexistent/folder"]) == 2
    assert capsys.readouterr().err


def test_summary_table():
    rows = [
        {
            "family": "f",
            "problem": 1,
            "valid": True,
            "success": True,
            "time_s": 0.1,
            "path_length": 2.0,
            "path_valid_fine": True,
        },
        {
            "family": "f",
            "problem": 2,
            "valid": False,
            "success": False,
            "time_s": None,
            "path_length": None,
            "path_valid_fine": None,
        },
    ]
    table = mut.summarize(rows)
    assert "f " in table and "100.0" in table and "2.00" in table
    assert "speed-up" not in table
    rows[0].update(ompl_success=True, ompl_time_s=0.5, ompl_path_length=2.5)
    rows.append(dict(rows[0], problem=3, time_s=0.3, ompl_success=False, ompl_time_s=5.0))
    table = mut.summarize(rows)
    # Medians: ours 0.2 s, OMPL 2.75 s over both valid problems; 0.1 vs 0.5 s on the one
    # both solved.
    assert "13.8x over 2 valid problems" in table
    assert "5.0x over the 1 both solved (ours 100.0 ms)" in table


def test_plot_writes_a_png(tmp_path):
    pytest.importorskip("matplotlib")
    rows = [
        {"family": "f", "problem": k, "valid": True, "success": True, "time_s": 0.05 * k}
        | {"ompl_success": k > 1, "ompl_time_s": 0.2 * k}
        for k in range(1, 6)
    ]
    rows.append({"family": "f", "problem": 6, "valid": False, "success": False, "time_s": None})
    out = tmp_path / "times.png"
    mut.plot_times(rows, out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_progress_falls_back_to_plain_lines(monkeypatch, capsys):
    import builtins

    real_import = builtins.__import__

    def no_tqdm(name, *args, **kwargs):
        if name == "tqdm":
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_tqdm)
    bar = mut._progress(3)
    bar.write("one line")
    bar.update()
    bar.close()
    assert "one line" in capsys.readouterr().out


def test_profile_prints_the_breakdown(capsys):
    assert mut.main(["--families", "cage_panda", "--limit", "2", "--profile"]) == 0
    out = capsys.readouterr().out
    assert "profile over 2 requests" in out and "tail only" in out
    assert "compiled: fine check on spheres" in out and "checks per request" in out
    assert "compiled_rrt.plan" in out and "compiled configurations" in out
    # The wrappers are gone afterwards.
    assert mut.MotionPlanner.plan_path.__module__ == "planning.motion_planner"
