"""The lidar robot's navigation run (drake_sim.runs.navigation): goals reached or failed and
scored against the truth, goals sent from Python and their handles, pose estimates, and (slow)
the acceptance runs on the mapped arenas."""

import math

import numpy as np
import pytest

import drake_sim.runs.navigation as mut
from diagrams.navigation_scenario import ExtraObstacle, world_arena
from drake_sim.worlds.arena import BoxSpec, load_arena, shipped_arenas
from drake_sim.worlds.route import random_goals
from tests import navigation_helpers as nh


@pytest.fixture(scope="module")
def room_map(tmp_path_factory):
    return nh.saved_truth_map("room", tmp_path_factory.mktemp("maps"))[0]


@pytest.fixture(scope="module")
def slam_map(tmp_path_factory):
    """``slam_map(name)``: the map a mapping run of the arena saves (made once per arena)."""
    folder, maps = tmp_path_factory.mktemp("slam_maps"), {}

    def get(name: str):
        if name not in maps:
            maps[name] = nh.saved_slam_map(name, folder)[0]
        return maps[name]

    return get


def _run(occupancy_map, goals, *, arena="room", world=None, **kwargs):
    arena_ = load_arena(nh.arena_file(arena))
    run = mut.NavigationRun(
        nh.scenario(),
        nh.robot(),
        world or arena_,
        occupancy_map,
        start=arena_.start_pose(),
        goals=goals,
        **kwargs,
    )
    run.run(run.default_duration())
    return run, run.report()


def test_a_goal_is_reached_precisely_without_touching_anything(room_map):
    goal = nh.pose_deg(0.0, -1.0, 90.0)
    run, report = _run(room_map, [goal])
    assert report.end == "done" and report.reached_all
    (result,) = report.goals
    assert result.reached and result.message == "arrived"
    assert result.position_error_m < 0.05 and result.yaw_error_deg < 10.0
    assert result.goal == pytest.approx([0.0, -1.0, 90.0])
    assert 2.2 < result.path_length_m < 3.5  # about 2.6 m from the start
    assert report.collisions == 0 and 0.1 < report.min_clearance_m < 1.0
    assert report.converged_after_s == 0.0  # started from the true pose
    assert report.localization_error_mean_m < 0.03
    assert report.sim_time_s == pytest.approx(run.context.get_time())
    assert report.to_dict()["goals"][0]["reached"] is True


def test_an_unreachable_goal_fails_fast_and_says_so(room_map):
    # The middle of box_c in the room: no free cell within the planner's tolerance.
    run, report = _run(room_map, [nh.pose_deg(0.3, 1.4, 0.0)])
    assert report.end == "failed" and not report.reached_all
    (result,) = report.goals
    assert not result.reached and "unreachable" in result.message or "obstacle" in result.message
    assert result.time_s < 5.0


def test_the_default_duration_allows_each_goal_its_time(room_map):
    goals = [nh.pose_deg(0.0, -1.0, 90.0), nh.pose_deg(2.0, 0.0, 0.0)]
    arena = load_arena(nh.arena_file("room"))
    run = mut.NavigationRun(
        nh.scenario(), nh.robot(), arena, room_map, start=arena.start_pose(), goals=goals
    )
    start = arena.start_pose()[:2]
    expected = run.goal_timeout(goals[0], start) + run.goal_timeout(goals[1], goals[0][:2])
    assert run.default_duration() == pytest.approx(expected)


def _random_goals(arena_name, count, seed):
    return random_goals(load_arena(nh.arena_file(arena_name)), count, seed)


@pytest.mark.slow
@pytest.mark.parametrize("arena_file", shipped_arenas(), ids=lambda p: p.stem)
def test_ten_random_goals_per_arena_are_reached_on_the_slam_map(arena_file, slam_map):
    # The workshop's order: map the arena, save the map, navigate on it (truth is the world).
    occupancy_map = slam_map(arena_file.stem)
    goals = _random_goals(arena_file.stem, 10, seed=7)
    run, report = _run(occupancy_map, goals, arena=arena_file.stem)
    assert report.reached_all, [g.message for g in report.goals]
    assert report.collisions == 0
    top_speed = run.robot.limits.max_linear_velocity  # 0.26 m/s
    for g in report.goals:
        assert g.position_error_m <= 0.05 and g.yaw_error_deg <= 10.0
        assert g.time_s <= 2.5 * g.path_length_m / top_speed


@pytest.mark.slow
def test_a_box_put_across_the_path_after_mapping_is_avoided(slam_map):
    room_map = slam_map("room")
    arena = load_arena(nh.arena_file("room"))
    scenario = nh.scenario()
    scenario.extra_obstacles = [
        ExtraObstacle(box=BoxSpec(size=[0.4, 0.6, 0.3], position=[0.3, -1.8]))
    ]
    world = world_arena(scenario, arena)
    run = mut.NavigationRun(
        scenario,
        nh.robot(),
        world,
        room_map,
        start=arena.start_pose(),
        goals=[nh.pose_deg(2.0, -1.8, 0.0)],
    )
    run.run(run.default_duration())
    report = run.report()
    assert report.reached_all and report.collisions == 0


@pytest.mark.slow
@pytest.mark.parametrize("arena_file", shipped_arenas(), ids=lambda p: p.stem)
def test_amcl_converges_from_half_a_metre_and_30_degrees_off(arena_file, slam_map):
    occupancy_map = slam_map(arena_file.stem)
    arena = load_arena(arena_file)
    x, y, yaw = arena.start_pose()
    guess = np.array([x + 0.5 * math.cos(1.0), y + 0.5 * math.sin(1.0), yaw + math.radians(30)])
    goals = _random_goals(arena_file.stem, 3, seed=3)  # driving well over 10 s
    run, report = _run(occupancy_map, goals, arena=arena_file.stem, initial_estimate=guess)
    times, position, heading = run.localization_errors()
    after = times >= 10.0
    assert times[-1] > 20.0
    assert position[after].max() < 0.05 and heading[after].max() < 3.0


@pytest.mark.slow
def test_global_localization_converges_in_the_room(slam_map):
    goals = _random_goals("room", 4, seed=11)
    run, report = _run(slam_map("room"), goals, global_localization=True)
    assert report.converged_after_s is not None and report.converged_after_s <= 60.0


def test_navigate_to_from_python_and_a_handle_that_is_cancelled(room_map):
    arena = load_arena(nh.arena_file("room"))
    run = mut.NavigationRun(nh.scenario(), nh.robot(), arena, room_map, start=arena.start_pose())
    result = run.navigate_to(nh.pose_deg(-1.0, -1.8, 0.0))
    assert result.reached and result.position_error_m < 0.05
    handle = run.send_goal(nh.pose_deg(2.0, -1.8, 0.0))
    assert not handle.done() and handle.result() is None
    run.advance(2.0)
    assert 0.0 < handle.distance_left_m < 3.5
    handle.cancel()
    run.advance(0.3)
    assert handle.done() and not handle.result().reached
    assert "cancel" in handle.result().message
    command = run.diagram.GetOutputPort("cmd_vel").Eval(run.context)
    assert np.allclose(command, 0.0)


def test_a_pose_estimate_restarts_amcl_where_it_is_put(room_map):
    arena = load_arena(nh.arena_file("room"))
    run = mut.NavigationRun(nh.scenario(), nh.robot(), arena, room_map, start=arena.start_pose())
    run.advance(0.5)
    run.set_pose_estimate(nh.pose_deg(1.0, 1.0, 90.0), np.diag([0.01, 0.01, 0.01]))
    particles = run.diagram.GetOutputPort("particles").Eval(run.context)
    assert np.abs(np.mean(particles[:, :2], axis=0) - [1.0, 1.0]).max() < 0.1
    run.start_global_localization()
    particles = run.diagram.GetOutputPort("particles").Eval(run.context)
    assert np.ptp(particles[:, 0]) > 4.0  # over the whole room


def test_an_arrival_far_from_the_truth_is_no_arrival():
    """The navigator arrives by its estimate; the report scores the true pose: within the goal
    tolerance plus LOST_M it is an arrival, beyond it "lost" (a wrong global localisation)."""
    from types import SimpleNamespace

    from drake_sim.navigation.navigator_state import GoalResult

    scenario = SimpleNamespace(navigator=SimpleNamespace(
        controller=SimpleNamespace(xy_goal_tolerance=0.05)))  # fmt: skip
    run = SimpleNamespace(scenario=scenario, results=[])
    goal = np.array([1.0, 2.0, 0.0])
    for truth in ([1.02, 2.0, 0.0], [1.0, 2.0 + 0.05 + mut.LOST_M + 0.01, 0.0]):
        result = GoalResult(goal, True, "", 10.0, 3.0, 3.1, goal)
        mut.NavigationRun._record_goal(run, result, np.array(truth))
    near, far = run.results
    assert near.reached and near.position_error_m == pytest.approx(0.02)
    assert not far.reached and far.position_error_m is None
    assert far.message == "arrived by its own estimate only, 0.56 m from the goal (lost)"
