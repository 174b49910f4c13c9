"""Running Wall-E on a course and its report (drake_sim.runs.walle): the end conditions, the
course progress, the recipe, and (slow) the acceptance runs on every shipped course. Headless,
simulated time, seeded IMU noise."""

import dataclasses as dc
import math

import pytest

import drake_sim.runs.walle as mut
from diagrams.walle_balance_scenario import Push
from drake_sim.base.errors import ConfigError
from drake_sim.worlds.course import load_course, shipped_courses
from tests.walle_course_helpers import REPORT_KEYS, walle_robot_and_scenario

robot, scenario = walle_robot_and_scenario()


def _course(tmp_path, text):
    path = tmp_path / "course.yaml"
    path.write_text(text)
    return load_course(path)


def _run(scenario, robot, course, duration=None, **changes):
    run = mut.WalleCourseRun(dc.replace(scenario, **changes), robot, course)
    run.run(run.default_duration(viewer=False) if duration is None else duration)
    return run, run.report()


def test_follow_variant_finishes_a_short_open_course(tmp_path):
    """The caster variant follows a straight, a left quarter turn and a straight to the end:
    the run ends at the finish, with the whole course passed, close to the line."""
    course = _course(
        tmp_path,
        "segments: [{straight: 0.5}, {arc: {radius: 0.4, angle: 90}}, {straight: 0.5}]\n",
    )
    run, report = _run(scenario, robot, course, mode="follow")
    assert report.end == "finish"
    assert report.to_dict().keys() >= REPORT_KEYS
    assert report.course_fraction == 1.0 and report.laps == 1
    length = 1.0 + 0.4 * math.pi / 2
    assert report.progress_m == pytest.approx(length - scenario.finish_margin, abs=0.05)
    speed = scenario.line_follower.speed
    assert length / speed < report.lap_time_s < 2.0 * length / speed
    assert report.sim_time_s < run.default_duration(viewer=False)  # It stopped at the finish.
    assert not report.fell and report.max_abs_pitch_deg < 1.0  # On its casters.
    assert report.max_line_offset_m < 0.02 and report.mean_line_offset_m < 0.01


def test_balance_mode_holds_position():
    course = load_course(shipped_courses()[0])
    _, report = _run(scenario, robot, course, duration=2.0, mode="balance")
    assert report.end == "duration" and report.sim_time_s == pytest.approx(2.0)
    assert not report.fell and report.time_upright_s == pytest.approx(2.0)
    assert report.max_line_offset_m < 0.01 and abs(report.progress_m) < 0.05
    assert report.course_fraction < 0.01 and report.laps == 0 and report.lap_time_s is None
    assert report.max_abs_pitch_deg < 2.0


def test_a_hard_push_ends_the_run_with_a_fall():
    course = load_course(shipped_courses()[0])
    walle = dc.replace(scenario.walle, pushes=[Push(time=0.5, force=[40.0, 0, 0], duration=0.3)])
    _, report = _run(scenario, robot, course, duration=5.0, mode="balance", walle=walle)
    assert report.end == "fell" and report.fell
    assert 0.5 < report.time_upright_s < 2.0
    assert report.sim_time_s < report.time_upright_s + 2 * mut.CHECK_PERIOD  # Stopped at once.
    assert report.max_abs_pitch_deg > scenario.walle.balance.fallen_pitch


def test_losing_the_line_for_good_ends_the_run(tmp_path):
    """A detector that can never see the line (it asks for more contrast than an image has):
    the follower searches, turns its full search angle without finding it, and stops; the line
    is lost for good and the run ends there."""
    course = _course(tmp_path, "segments: [{straight: 1.0}]\n")
    follower = dc.replace(scenario.line_follower, search_turn=1.0, search_omega=2.0)
    blind = dc.replace(scenario.line_detector, min_contrast=256.0)
    _, report = _run(
        scenario, robot, course, mode="follow", line_follower=follower, line_detector=blind
    )
    assert report.end == "lost_line" and report.lost_line
    assert report.course_fraction < 1.0 and report.laps == 0


def test_the_recipe_seeds_the_imu_and_runs_the_scenario_s_course():
    run = mut.RECIPE.start(overrides=["mode=balance"], seed=2)
    assert run.seed == 2 and run.scenario.walle.random_seed == 2
    assert run.course == load_course(mut.course_path(run.scenario))
    assert run.default_duration(viewer=False) == mut.BALANCE_DURATION
    assert run.default_duration(viewer=True) == math.inf
    assert set(run.report().to_dict()) == set(mut.report_keys())


def test_teleop_is_for_the_balancing_robot_only():
    inputs = mut.RECIPE.load(overrides=["mode=follow"])
    with pytest.raises(ConfigError, match="--mode balance"):
        mut.RECIPE.make_run(inputs, {"teleop": True})


@pytest.mark.slow
@pytest.mark.parametrize("path", shipped_courses(), ids=lambda p: p.stem)
def test_acceptance_both_completes_every_shipped_course(path):
    """Balancing and following at the default speed: the whole course (a full lap on a loop),
    no fall, within 5 cm of the line at worst and 1.5 cm on average."""
    course = load_course(path)
    _, report = _run(scenario, robot, course, mode="both")
    assert not report.fell
    assert report.course_fraction == 1.0 and report.laps >= 1
    assert report.end == ("lap" if course.closed else "finish")
    assert report.max_line_offset_m <= 0.05
    assert report.mean_line_offset_m <= 0.015
