"""RRT-Connect (planning.search.rrt): Tree's nodes, nearest neighbour and branches; joined_path
joins two trees' branches at their meeting point; rrt_connect around a wall returns a path from
the start to the goal whose segments are at most a step long and collision-free at the fine
resolution (on sphere-first checks, as the planner searches, and on Drake's checker alone), one
extension per query (the classic algorithm) or a batch of them, the trees in turn or the smaller
first (balanced), the same path for the same seed,
and None when out of time or rounds."""

import time

import numpy as np
import pytest

import planning.search.rrt as mut
from planning.collision.checker import CheckerAdapter
from planning.collision.sphere_checker import SphereCheckerAdapter
from planning.paths import densify

E = np.eye(7)
FINE = 0.01  # rad


def plan(scene, ends, seed, step=0.5, goal_bias=0.05, adapter=None, batch=1, balance=False):
    """RRT-Connect with edges checked every FINE rad (sphere models first, then Drake)."""
    return mut.rrt_connect(
        adapter or SphereCheckerAdapter(scene, FINE),
        *ends,
        step=step,
        goal_bias=goal_bias,
        deadline=time.perf_counter() + 60.0,  # a backstop only: max_rounds ends it first
        rng=np.random.default_rng(seed),
        max_rounds=5000,
        batch=batch,
        balance=balance,
    )


def assert_fine_collision_free(scene, path):
    """Every sample at most FINE apart along the path, each checked by the scene."""
    samples, _ = densify(path, FINE)
    assert all(scene.is_collision_free(q) for q in samples)


def test_tree_adds_nodes_finds_the_nearest_and_walks_branches():
    dut = mut.Tree(np.zeros(7), capacity=2)
    assert dut.size == 1 and dut.parent[0] == -1
    a = dut.add(E[0], 0)
    b = dut.add(E[0] + E[1], a)  # beyond the capacity: the tree grows
    c = dut.add(-E[2], 0)
    assert (a, b, c) == (1, 2, 3) and dut.size == 4 and len(dut.q) >= 4
    assert dut.nearest(np.full(7, 0.01)) == 0
    assert dut.nearest(E[0] + 0.9 * E[1]) == b
    assert dut.nearest(-3 * E[2]) == c
    branch = dut.branch(b)
    np.testing.assert_array_equal(np.array(branch), [np.zeros(7), E[0], E[0] + E[1]])
    np.testing.assert_array_equal(np.array(dut.branch(0)), [np.zeros(7)])


def test_joined_path_meets_once_and_is_reversed_for_the_goal_tree():
    start, goal, meet = np.zeros(7), 2 * E[0], E[0] + E[1]
    a = mut.Tree(start)
    i = a.add(0.5 * E[1], 0)
    i = a.add(meet, i)
    b = mut.Tree(goal)
    j = b.add(meet.copy(), 0)  # b reached a's node: the meeting point is in both trees
    path = mut.joined_path(a, i, b, j, reverse=False)
    np.testing.assert_array_equal(path, [start, 0.5 * E[1], meet, goal])
    # When tree a grew from the goal, the path is turned around: from b's root to a's.
    back = mut.joined_path(a, i, b, j, reverse=True)
    np.testing.assert_array_equal(back, path[::-1])


@pytest.mark.parametrize("batch, balance", [(1, False), (16, False), (1, True), (16, True)])
def test_a_path_around_the_wall_from_start_to_goal(scene, ends, batch, balance):
    start, goal = ends
    assert not scene.is_edge_collision_free(start, goal)
    step = 0.5
    path = plan(scene, ends, seed=0, step=step, batch=batch, balance=balance)
    assert path is not None and path.shape[1] == 7 and len(path) >= 3
    np.testing.assert_array_equal(path[0], start)
    np.testing.assert_array_equal(path[-1], goal)
    lengths = np.linalg.norm(np.diff(path, axis=0), axis=1)
    assert np.all(lengths <= step + 1e-9) and np.all(lengths > 1e-12)  # no repeated waypoint
    assert_fine_collision_free(scene, path)


def test_a_path_around_the_wall_on_drakes_checker_alone(scene, ends):
    path = plan(scene, ends, seed=0, adapter=CheckerAdapter(scene, FINE))
    np.testing.assert_array_equal(path[[0, -1]], ends)
    assert_fine_collision_free(scene, path)


@pytest.mark.parametrize("seed, batch", [(1, 1), (2, 1), (3, 16)])
def test_the_same_seed_gives_the_same_path(scene, ends, seed, batch):
    first, again = plan(scene, ends, seed, batch=batch), plan(scene, ends, seed, batch=batch)
    np.testing.assert_array_equal(first, again)
    assert_fine_collision_free(scene, first)
    other = plan(scene, ends, seed + 10, batch=batch)
    assert not np.array_equal(first, other) or len(first) == 2


def test_a_free_straight_line_within_a_step_is_the_path(scene, ends):
    """With goal_bias 1 the first extension heads for the goal and reaches it."""
    start = ends[0]
    goal = start - 0.3 * E[0]
    path = plan(scene, (start, goal), seed=0, step=1.0, goal_bias=1.0)
    np.testing.assert_array_equal(path, [start, goal])


def test_out_of_time_or_rounds_gives_none(scene, ends):
    rng = np.random.default_rng(0)
    adapter = CheckerAdapter(scene)
    kwargs = dict(step=0.5, goal_bias=0.05, rng=rng)
    assert mut.rrt_connect(adapter, *ends, deadline=time.perf_counter() - 1.0, **kwargs) is None
    deadline = time.perf_counter() + 60.0
    assert mut.rrt_connect(adapter, *ends, deadline=deadline, max_rounds=0, **kwargs) is None
