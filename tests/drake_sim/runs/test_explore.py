"""The exploring run: a small unknown room mapped by itself, the report, partial maps."""

import numpy as np
import pytest

import drake_sim.runs.explore as mut
from drake_sim.base.map_files import load_map
from drake_sim.runs import mapping
from drake_sim.worlds.arena import load_arena, shipped_arenas
from drake_sim.worlds.route import default_route_file, load_route

SMALL_ROOM = """size: [3.0, 2.4]
wall: {height: 0.4, thickness: 0.05}
obstacles:
  - {name: box, box: {size: [0.4, 0.4, 0.3], position: [0.5, 0.2]}}
start: {x: -1.0, y: -0.6, yaw: 0}
"""


@pytest.fixture
def small_room(tmp_path):
    path = tmp_path / "small.yaml"
    path.write_text(SMALL_ROOM)
    return path


def test_a_small_room_is_explored_mapped_and_saved(small_room, tmp_path):
    out = tmp_path / "maps" / "small"
    run = mut.RECIPE.start(overrides=[f"arena={small_room}"], out=out)
    assert run.run(run.default_duration()) == "explored"
    report = run.finish()
    assert report.end == "explored"
    assert report.known_fraction >= 0.95 and report.map_iou >= 0.95
    assert report.collisions == 0 and report.min_clearance_m > 0.05
    assert report.pose_rmse_m < 0.05
    assert report.frontiers_visited >= 1 and report.frontiers_left == 0
    assert 1.0 < report.distance_m < 15.0
    assert report.sim_time_s < 60.0 and report.real_time_factor > 0
    assert report.map_files == [f"{out}.pgm", f"{out}.yaml"]
    saved = load_map(f"{out}.yaml")
    assert saved.occupied().sum() > 100 and saved.free().sum() > 1000
    assert set(mut.report_keys()) == set(report.to_dict())


def test_a_run_cut_short_saves_a_partial_map_and_keeps_the_old_one(small_room, tmp_path):
    out = tmp_path / "maps" / "small"
    out.parent.mkdir()
    (out.parent / "small.yaml").write_text("an old map\n")
    run = mut.RECIPE.start(overrides=[f"arena={small_room}", "time_limit=3"], out=out)
    assert run.run(run.default_duration()) == "duration"
    report = run.finish()
    assert report.end == "time_limit"
    assert report.map_files[1] == f"{out}.partial.yaml"
    assert (out.parent / "small.yaml").read_text() == "an old map\n"
    assert report.known_fraction < 0.95 and report.frontiers_left > 0
    assert "not explored in the time limit" in run.error(report)


def test_a_goal_that_does_not_reveal_its_frontier_is_blacklisted(small_room):
    run = mut.RECIPE.start(overrides=[f"arena={small_room}"])
    run.run(2.0)
    chosen = run._chosen
    assert chosen is not None and run.target is not None
    run._give_up()
    assert len(run.blacklist) == len(chosen.seen_from_goal(run.config)) > 0
    assert run._chosen is None
    # Those cells are no frontier any more.
    run._choose(run.context.get_time())
    for cell in chosen.seen_from_goal(run.config):
        for frontier in run.frontiers:
            assert np.min(np.hypot(*(frontier.cells - cell).T)) > run.config.blacklist_radius


def test_before_the_first_scan_nothing_is_explored_and_the_slam_is_at_the_start(small_room):
    run = mut.RECIPE.start(overrides=[f"arena={small_room}"])
    assert run.amcl is None
    # Before the first scan the map is empty: no frontier, but not explored either.
    assert run._choose(0.0) is None and run._choose(1.0) is None and run.frontiers == []
    pose = run.diagram.GetOutputPort("estimated_pose").Eval(run.context)
    assert np.allclose(pose, [-1.0, -0.6, 0.0])


@pytest.mark.slow
@pytest.mark.parametrize("arena_file", shipped_arenas(), ids=lambda p: p.stem)
def test_every_shipped_arena_is_explored_faster_than_its_route(arena_file):
    """The acceptance: explored, known and IoU >= 0.95, no collision, pose RMSE <= 5 cm, within
    600 s and 1.5 times the time the arena's mapping route takes (its length at the route
    follower's speed)."""
    arena = load_arena(arena_file)
    route = load_route(default_route_file(arena_file), arena)
    speed = mapping.RECIPE.load().scenario.route_follower.speed
    route_s = mapping.route_length(arena.start_pose(), route.waypoints) / speed
    run = mut.RECIPE.start(overrides=[f"arena={arena_file}"])
    assert run.run(run.default_duration()) == "explored"
    report = run.report()
    assert report.known_fraction >= 0.95 and report.map_iou >= 0.95
    assert report.collisions == 0 and report.pose_rmse_m <= 0.05
    assert report.sim_time_s <= min(600.0, 1.5 * route_s)
