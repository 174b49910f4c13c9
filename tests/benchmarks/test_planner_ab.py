"""benchmarks/planner_ab.py: the interleaved order, the report, bad input; one slow real run."""

import importlib.util
import subprocess
from pathlib import Path

import pytest

from planning.io import mbm
from tests.mbm_helpers import FakePip, mbm_problems

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("planner_ab", ROOT / "benchmarks" / "planner_ab.py")
mut = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(mut)


def test_old_and_new_take_turns_going_first():
    assert mut.schedule([4, 7, 9, 12]) == [(4, True), (7, False), (9, True), (12, False)]


def test_the_report_gives_medians_ratios_and_families():
    rows = [
        ("box", 0.002, 0.001, 4.0, 4.0),
        ("box", 0.004, 0.004, 5.0, 5.5),
        ("cage", 0.010, 0.005, 6.0, 6.0),
    ]
    report = mut.summarize(rows)
    assert "3 problems, ms: OLD median 4.000" in report
    assert "NEW median 4.000" in report
    assert "per-problem median 0.500, total 0.625" in report  # ratios 0.5, 1, 0.5
    assert "the same length on 67%" in report
    assert "box" in report and "cage" in report


def test_settings_change_a_section_field_with_its_type():
    from planning.motion_planner import MotionPlannerOptions

    base = MotionPlannerOptions()
    changed = base.shortcut.iterations + 10
    options = mut.with_settings(base, [f"shortcut.iterations={changed}", "rrt.balance=false"])
    assert options.shortcut.iterations == changed and options.rrt.balance is False
    assert base.rrt.balance is True  # both settings change their default
    assert options.rrt.step == base.rrt.step
    for bad in ("shortcut.nope=1", "shortcut.iterations=x", "rrt.balance=maybe", "rrt.step=-1"):
        with pytest.raises(ValueError, match="--set"):
            mut.with_settings(base, [bad])


@pytest.mark.parametrize(
    "argv",
    [
        ["/nonexistent/a", "/nonexistent/b"],
        [str(ROOT)],  # one checkout only
        [str(ROOT), str(ROOT), "--set", "iterations=3"],  # not section.field=value
        [str(ROOT), str(ROOT), "--dataset", "/nonexistent/problems"],
    ],
)
def test_bad_input_is_one_line_and_exit_code_2(argv, capsys):
    assert mut.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and "\n" not in err


def test_problems_that_cannot_be_had_are_one_line_and_exit_code_2(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(tmp_path))
    monkeypatch.delenv(mbm.ENV_VAR, raising=False)
    failing = FakePip(returncode=1, stderr="ERROR: No matching distribution found\n")
    monkeypatch.setattr(subprocess, "run", failing)
    assert mut.main([str(ROOT), str(ROOT)]) == 2
    note, err = capsys.readouterr().err.splitlines()  # no worker was started
    assert note.startswith("note: downloading") and err.startswith("error: cannot download")
    assert len(failing.commands) == 1


@pytest.mark.slow
def test_a_checkout_against_itself(capsys):
    argv = [str(ROOT), str(ROOT), "--limit", "1", "--families", "table_pick_panda"]
    assert mut.main([*argv, "--dataset", str(mbm_problems())]) == 0
    out = capsys.readouterr().out
    assert "1 problems" in out and "the same length on 100%" in out
