"""The navigate app's recipe (drake_sim.runs.navigate): the map, the goals the options name,
AMCL's start, the run's summary and errors, and a sweep's row."""

import math

import numpy as np
import pytest

import drake_sim.runs.navigate as mut
from drake_sim.base.errors import ConfigError
from drake_sim.runs.navigation import GoalReport, NavigationReport
from drake_sim.worlds.arena import arena_grid, load_arena
from drake_sim.worlds.route import default_goals_file, load_goals, random_goals
from tests import navigation_helpers as nh


@pytest.fixture(scope="module")
def room_map():
    """The room's ground truth at the lidar's height (what ``make_run`` uses without a map)."""
    arena = load_arena(nh.arena_file("room"))
    return arena_grid(arena, mut.GROUND_TRUTH_RESOLUTION, height=nh.robot().scan_height)


def test_check_pose_takes_degrees_and_refuses_what_is_off_the_map(room_map):
    pose = mut.check_pose([1.0, -1.0, 90.0], "--goal", room_map)
    np.testing.assert_allclose(pose, [1.0, -1.0, math.pi / 2])
    with pytest.raises(ConfigError, match="--goal: .* outside the map"):
        mut.check_pose([50.0, 0.0, 0.0], "--goal", room_map)
    with pytest.raises(ConfigError, match="--initial-pose: every value must be a finite"):
        mut.check_pose([0.0, math.nan, 0.0], "--initial-pose", room_map)


def test_headless_without_goals_drives_the_arena_s_goals_file():
    run = mut.RECIPE.start(seed=4)
    path = default_goals_file(nh.arena_file("room"))
    expected = [[g.x, g.y, math.radians(g.yaw)] for g in load_goals(path)]
    np.testing.assert_allclose(run.goals, expected)
    assert not run.interactive and run.seed == 4 and run.scenario.random_seed == 4
    np.testing.assert_allclose(run.start, load_arena(nh.arena_file("room")).start_pose())


def test_one_goal_or_random_goals_drawn_with_the_run_s_seed():
    one = mut.RECIPE.start(goal=[0.0, -1.0, 90.0])
    np.testing.assert_allclose(one.goals, [[0.0, -1.0, math.pi / 2]])
    drawn = mut.RECIPE.start(goals=3, seed=5)
    expected = random_goals(load_arena(nh.arena_file("room")), 3, 5)
    np.testing.assert_allclose(drawn.goals, expected)


def test_with_a_viewer_and_no_goals_the_goals_come_from_the_page():
    run = mut.RECIPE.start(headless=False)
    assert run.interactive and run.goals == []
    assert run.default_duration(viewer=True) == math.inf
    assert run.error(run.report()) is None
    assert "goals given in the page" in run.summary(run.report())


def test_a_missing_goals_file_for_the_arena_is_bad_input(tmp_path):
    arena = tmp_path / "hall.yaml"
    arena.write_text(nh.arena_file("room").read_text())
    with pytest.raises(ConfigError, match="no default goals"):
        mut.RECIPE.start(overrides=[f"arena={arena}"])


def _goal(reached: bool, message: str = "arrived") -> GoalReport:
    error = 0.01 if reached else None
    return GoalReport([1.0, 2.0, 0.0], reached, error, error, 5.0, 1.0, message)


def _report(end: str, goals) -> NavigationReport:
    return NavigationReport(
        end=end,
        goals=goals,
        reached_all=bool(goals) and all(g.reached for g in goals),
        collisions=0,
        min_clearance_m=0.2,
        localization_error_mean_m=None,
        localization_error_max_m=None,
        converged_after_s=0.0,
        sim_time_s=12.0,
        wall_time_s=1.0,
        real_time_factor=12.0,
        seed=0,
    )


def test_the_error_line_says_which_goal_and_why():
    run = mut.RECIPE.start(goal=[1.0, 2.0, 0.0])
    assert run.error(_report("done", [_goal(True)])) is None
    assert run.error(_report("stopped", [])) is None
    failed = run.error(_report("failed", [_goal(False, "unreachable")]))
    assert failed == "goal 0 (1, 2) not reached: unreachable"
    assert "not reached in 12.0 s: timed out" in run.error(_report("duration", []))
    run.failure = "diverged"
    assert run.error(_report("sim_failed", [])).endswith(": diverged")
    assert "1 of 1 goals reached, ended by done" in run.summary(_report("done", [_goal(True)]))


def test_a_sweep_row_sums_the_goals_up():
    report = _report("failed", [_goal(True), _goal(False, "unreachable")]).to_dict()
    row = mut.sweep_row(report)
    assert "goals" not in row and row["goals_reached"] == 1
    assert row["max_position_error_m"] == 0.01 and row["max_yaw_error_deg"] == 0.01
    assert set(row) == set(mut.report_keys())
    none = mut.sweep_row(_report("failed", [_goal(False)]).to_dict())
    assert none["goals_reached"] == 0 and none["max_position_error_m"] is None
