"""The flipping robot's run (drake_sim.runs.flip): its recipe, ``run`` with and without the
progress bar (the same run, a bar on terminals only), and the report."""

import argparse
import io
import math

import numpy as np
import pytest

import drake_sim.runs.flip as mut
from tests.flip_helpers import default_robot, flip_scenario, seeded

WALL_CLOCK_KEYS = {"wall_time_s", "real_time_factor"}


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _report(run) -> dict:
    return {k: v for k, v in run.report().to_dict().items() if k not in WALL_CLOCK_KEYS}


def _run() -> mut.FlipRun:
    return mut.FlipRun(seeded(flip_scenario(), 1), default_robot())


def test_progress_changes_nothing_but_the_display(monkeypatch):
    terminal = _Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    plain = _run()
    assert plain.run(1.2) == "duration"
    shown = _run()
    assert shown.run(1.2, progress=True) == "duration"
    assert shown.context.get_time() == pytest.approx(1.2)
    assert _report(shown) == _report(plain)
    assert "simulated s" in terminal.getvalue()


def test_no_bar_when_stderr_is_not_a_terminal(capsys):
    run = _run()
    run.run(0.6, progress=True)
    assert run.context.get_time() == pytest.approx(0.6)
    assert capsys.readouterr().err == ""


def test_the_report_has_the_contract_keys_and_the_seed():
    run = _run()
    run.run(0.5)
    report = run.report()
    assert report.seed == 1 and report.end == "duration" and report.finite
    assert report.sim_time_s == pytest.approx(0.5)
    assert set(report.to_dict()) == set(mut.report_keys())
    assert {"flips", "max_lateral_deviation_m", "travel_extent_m", "odometry_error_m"} <= set(
        mut.report_keys()
    )


def test_the_recipe_puts_the_seed_in_the_scenario_and_picks_the_controller():
    inputs = mut.RECIPE.load(overrides=["scene.world=''", "robot.body.mass=2.0"], seed=3)
    assert inputs.seed == 3 and inputs.scenario.scene.random_seed == 3
    assert inputs.scenario.scene.world == "" and inputs.robot.body.mass == 2.0
    run = mut.RECIPE.make_run(inputs, {"controller": "cmd_vel"})
    assert run.seed == 3 and run.controller == "cmd_vel"
    cli_run = mut.RECIPE.make_run(inputs, argparse.Namespace(teleop=False))
    assert cli_run.controller == "flip"


def test_default_duration():
    run = _run()
    assert run.default_duration(viewer=True) == math.inf
    assert run.default_duration() == mut.HEADLESS_DURATION


def test_summarize_measures_along_the_first_heading():
    times = np.array([0.0, 1.0, 2.0])
    truth = np.array([[0.0, 1.0, 2.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.0]])
    odometry = truth + [[0.0, 0.0, 0.3], [0.0, 0.0, 0.4], [0.0, 0.0, 0.0]]
    figures = mut.summarize(times, truth, odometry, truth, None)
    assert figures["max_lateral_deviation_m"] == pytest.approx(0.1)
    assert figures["travel_extent_m"] == pytest.approx(2.0)
    assert figures["odometry_error_m"] == pytest.approx(0.5)
    assert figures["naive_odometry_error_m"] == 0.0 and figures["flips"] == 0
