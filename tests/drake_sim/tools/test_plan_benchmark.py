"""python -m planning.benchmark: one MBM problem end to end, the report rows, where the problems
come from (pip mocked), random problems saved and run again, bad input."""

import hashlib
import json
import subprocess

import numpy as np
import pytest

import drake_sim.tools.plan_benchmark as mut
from planning import PlanningScene
from planning.io import mbm
from tests.cli_helpers import assert_bad_input, run_module
from tests.mbm_helpers import FakePip, make_problems_archive, make_sdist
from tests.robot_helpers import dev_resources, vamp_robot

MODULE = "drake_sim.tools.plan_benchmark"


@pytest.fixture
def fresh(tmp_path, monkeypatch):
    """An empty cache of its own and no $DRAKE_SIM_MBM."""
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv(mbm.ENV_VAR, raising=False)
    return tmp_path / "cache"


def test_one_problem_report(tmp_path, capsys, monkeypatch, mbm_folder):
    report = tmp_path / "report.json"
    # No --dataset: the problems come from $DRAKE_SIM_MBM.
    monkeypatch.setenv(mbm.ENV_VAR, str(mbm_folder))
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
    folder = mbm_folder
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


def test_dataset_may_be_the_archive_its_folder_or_the_problems(tmp_path, fresh):
    archive = make_problems_archive(tmp_path / "set" / "problems.tar.bz2", ["box_panda"])
    folder = mut._parse_args(["--dataset", str(archive), "--families", "box_panda"]).dataset
    assert (folder / "box_panda" / "scene0001.yaml").is_file()
    assert folder.is_relative_to(fresh)  # unpacked into the cache, not beside the archive
    for given in (archive.parent, folder):
        assert mut._parse_args(["--dataset", str(given), "--families", "box_panda"]).dataset == (
            folder
        )


def test_without_dataset_the_problems_are_downloaded_once_then_cached(
    tmp_path, fresh, monkeypatch, capsys
):
    archive = make_problems_archive(tmp_path / "src" / "problems.tar.bz2", ["box_panda"])
    monkeypatch.setitem(
        mbm.ARCHIVE_SHA256, "panda", hashlib.sha256(archive.read_bytes()).hexdigest()
    )
    pip = FakePip(make_sdist(tmp_path / "sdist", {"panda": archive.read_bytes()}).read_bytes())
    monkeypatch.setattr(subprocess, "run", pip)
    args = mut._parse_args(["--families", "box_panda", "--limit", "1"])
    assert args.dataset == fresh / "mbm" / "panda"
    assert capsys.readouterr().err.startswith("note: downloading the MotionBenchMaker panda")
    assert mut._parse_args(["--families", "box_panda"]).dataset == args.dataset
    assert len(pip.commands) == 1 and capsys.readouterr().err == ""


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1, err
    return err


def test_problems_that_cannot_be_had_exit_2_with_one_line(tmp_path, fresh, monkeypatch, capsys):
    stderr = "ERROR: Could not find a version that satisfies the requirement vamp-planner==0.6.4\n"
    monkeypatch.setattr(subprocess, "run", FakePip(returncode=1, stderr=stderr))
    assert mut.main(["--limit", "1"]) == 2
    note, err = capsys.readouterr().err.splitlines()  # the note on the download, the error
    assert note.startswith("note: downloading") and err.startswith("error: cannot download")
    assert "Could not find a version" in err and "--dataset" in err
    assert not (fresh / "mbm" / "panda").exists()
    corrupt = tmp_path / "problems.tar.bz2"
    corrupt.write_bytes(b"BZh9 not really")
    assert mut.main(["--dataset", str(corrupt)]) == 2
    assert "not a readable problems.tar.bz2" in one_error_line(capsys)
    monkeypatch.setenv(mbm.ENV_VAR, str(tmp_path / "nowhere"))
    assert mut.main(["--limit", "1"]) == 2
    assert f"error: {mbm.ENV_VAR}: " in one_error_line(capsys)
    given = make_problems_archive(tmp_path / "set" / "problems.tar.bz2", ["box_panda"])
    assert mut.main(["--dataset", str(given), "--families", "cage_panda"]) == 2
    assert "no MBM family cage_panda" in one_error_line(capsys)


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


def test_profile_prints_the_breakdown(capsys, mbm_folder):
    profile = ["--families", "cage_panda", "--limit", "2", "--profile"]
    assert mut.main(["--dataset", str(mbm_folder), *profile]) == 0
    out = capsys.readouterr().out
    assert "profile over 2 requests" in out and "tail only" in out
    assert "compiled: fine check on spheres" in out and "checks per request" in out
    assert "compiled_rrt.plan" in out and "compiled configurations" in out
    # The wrappers are gone afterwards.
    assert mut.MotionPlanner.plan_path.__module__ == "planning.motion_planner"


def test_random_problems_end_to_end_then_again_from_the_saved_folder(tmp_path):
    saved, report = tmp_path / "saved", tmp_path / "report.json"
    args = ["--random", 2, "--seed", 5, "--timeout", 2, "--report", report]
    result = run_module(MODULE, *args, "--save-problems", saved)
    assert result.returncode == 0, result.stderr
    assert "random" in result.stdout
    rows = json.loads(report.read_text())
    assert [(r["family"], r["problem"]) for r in rows] == [("random", 1), ("random", 2)]
    assert sorted(p.name for p in (saved / "random").iterdir()) == [
        "request0001.yaml",
        "request0002.yaml",
        "scene0001.yaml",
        "scene0002.yaml",
    ]
    for row in rows:
        assert row["joint_names"] == [f"panda_joint{i}" for i in range(1, 8)]
        assert row["valid"] and row["success"] and row["path_valid_fine"], row
        request = mbm.load_request(saved / "random" / f"request{row['problem']:04d}.yaml")
        path = np.asarray(row["path"])
        np.testing.assert_allclose(path[0], request.q_start[:7])
        np.testing.assert_allclose(path[-1], request.q_goal[:7])
    # The saved folder is a problem set: --dataset runs the same problems (random family).
    again = tmp_path / "again.json"
    result = run_module(MODULE, "--dataset", saved, "--timeout", 2, "--report", again)
    assert result.returncode == 0, result.stderr
    rows_again = json.loads(again.read_text())
    assert [(r["family"], r["problem"], r["valid"]) for r in rows_again] == [
        (r["family"], r["problem"], r["valid"]) for r in rows
    ]
    for a, b in zip(rows, rows_again, strict=True):
        np.testing.assert_allclose(a["path"][0], b["path"][0])
        np.testing.assert_allclose(a["path"][-1], b["path"][-1])
    # Without --save-problems nothing is left behind, and the same seed gives the same problems.
    third = tmp_path / "third.json"
    assert run_module(MODULE, *args[:-1], third).returncode == 0
    for a, b in zip(rows, json.loads(third.read_text()), strict=True):
        np.testing.assert_array_equal(a["path"][0], b["path"][0])
        np.testing.assert_array_equal(a["path"][-1], b["path"][-1])


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--random", "0"], "--random: must be >= 1"),
        (["--random", "2", "--dataset", "."], "--dataset does not go with it"),
        (["--random", "2", "--families", "box_panda"], "--families does not go with it"),
        (["--save-problems", "{tmp}/out"], "give --random N"),
        (["--random", "2", "--save-problems", "{tmp}/file"], "is not a directory"),
        (["--random", "2", "--save-problems", "{tmp}/full"], "holds problems already"),
    ],
)
def test_random_bad_input_exits_2_with_one_line(tmp_path, args, needle):
    (tmp_path / "file").write_text("x")
    (tmp_path / "full" / "random").mkdir(parents=True)
    (tmp_path / "full" / "random" / "scene0001.yaml").write_text("name: x\n")
    args = [a.format(tmp=tmp_path) for a in args]
    assert_bad_input(run_module(MODULE, *args), needle)


def test_a_random_problem_that_cannot_be_made_is_a_row_saying_so(tmp_path, monkeypatch):
    from planning.task import random_problems

    def draws(scene, count, seed, workspace):
        yield random_problems.ProblemGenerationError(1, "random problem 1: no start and goal")

    monkeypatch.setattr(mut, "random_problems", draws)
    report = tmp_path / "report.json"
    out = tmp_path / "out"
    result = run_module(MODULE, "--random", 1, "--save-problems", out, "--report", report)
    assert result.returncode == 0, result.stderr
    (row,) = json.loads(report.read_text())
    assert row["family"] == "random" and row["problem"] == 1
    assert not row["valid"] and not row["success"] and "no start and goal" in row["error"]
    assert not (out / "random").exists()


def _robot_set(robot: str):
    """The robot's MBM set, unpacked from the development copy of the vamp sdist (with its
    description in the session's cache), or a skip: 65 MB more per robot is not a test's."""
    vamp_robot(robot)
    dev = dev_resources()
    if dev is None or not (dev / robot / "problems.tar.bz2").is_file():
        pytest.skip(f"no development copy of the {robot} MotionBenchMaker set")
    return mbm.problems_folder(dev / robot)


def test_another_robot_plans_its_own_set_and_its_paths_hold_under_drake(tmp_path):
    folder = _robot_set("ur5")
    report = tmp_path / "ur5.json"
    args = ["--robot", "ur5", "--dataset", str(folder), "--families", "box_ur5", "--limit", "1"]
    assert mut.main([*args, "--report", str(report)]) == 0
    (row,) = json.loads(report.read_text())
    names = [f"{j}_joint" for j in ("shoulder_pan", "shoulder_lift", "elbow")]
    assert row["joint_names"][:3] == names and len(row["joint_names"]) == 6
    assert row["valid"] and row["success"] and row["path_valid_fine"]
    path = np.asarray(row["path"])
    assert path.shape[1] == 6
    scene = PlanningScene(mut.robot_config("ur5"))
    scene.load_moveit(folder / "box_ur5/scene0001.yaml")
    start, goal, others = mbm.read_request(folder / "box_ur5/request0001.yaml", row["joint_names"])
    scene.set_positions(others)
    np.testing.assert_allclose(path[0], start)
    np.testing.assert_allclose(path[-1], goal)
    for a, b in zip(path[:-1], path[1:], strict=True):
        n = int(np.ceil(np.linalg.norm(b - a) / 0.01))
        assert all(scene.is_collision_free(a + s * (b - a)) for s in np.linspace(0, 1, n + 1))


def test_a_robot_without_a_shipped_set_needs_its_problems(capsys):
    assert mut.main(["--robot", "config/robots/panda_primitives.yaml"]) == 2
    assert "--dataset" in capsys.readouterr().err
