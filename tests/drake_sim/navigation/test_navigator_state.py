"""The navigator's state, goal results and status (``navigator_state``): copies that share
nothing the next update changes, a goal's end recorded once, and the status read from the state."""

import copy

import numpy as np
import pytest

import drake_sim.navigation.navigator_state as mut
from drake_sim.navigation.costmap import LETHAL, NO_INFORMATION, Costmap


@pytest.fixture
def state():
    static = np.zeros((10, 12), dtype=np.uint8)
    static[5, 5] = LETHAL
    return mut.NavState(Costmap(static, 0.1), goals=[(1.0, 0.5, 0.0), (0.2, 0.3, 1.0)])


def test_a_new_state_is_idle_with_its_goals_queued(state):
    assert state.state == "idle" and state.goal is None and state.goal_index == -1
    np.testing.assert_array_equal(state.queue[1], [0.2, 0.3, 1.0])
    assert mut.STATES[0] == "idle"


def test_copy_costmap_copies_the_layers_and_shares_the_config(state):
    other = mut.copy_costmap(state.costmap)
    other.obstacle_layer[0, 0] = LETHAL
    assert state.costmap.obstacle_layer[0, 0] == NO_INFORMATION
    for name in ("static_layer", "costs"):
        assert getattr(other, name) is not getattr(state.costmap, name)
        np.testing.assert_array_equal(getattr(other, name), getattr(state.costmap, name))
    assert other.config is state.costmap.config


def test_a_deep_copy_has_its_own_costmap_queue_and_results(state):
    other = copy.deepcopy(state)
    other.queue.pop()
    other.results.append("a result")
    other.costmap.costs[0, 0] = 7
    assert len(state.queue) == 2 and state.results == []
    assert state.costmap.costs[0, 0] != 7
    assert other.path is state.path  # replaced, never changed in place: shared


def test_finish_goal_records_the_result_once(state):
    mut.finish_goal(state, 3.0, [0, 0, 0], True, "")  # no goal yet: nothing to end
    assert state.results == [] and state.state == "idle"
    state.goal, state.goal_start, state.first_length, state.driven = state.queue.pop(0), 1.0, 2, 3
    state.command = np.ones(2)
    mut.finish_goal(state, 3.5, [0.9, 0.5, 0.1], False, "blocked: stuck")
    (result,) = state.results
    assert (result.reached, result.message, result.time_s) == (False, "blocked: stuck", 2.5)
    assert (result.path_length_m, result.driven_m) == (2, 3)
    np.testing.assert_array_equal(result.final_pose, [0.9, 0.5, 0.1])
    assert state.state == "failed" and state.message == "blocked: stuck" and state.goal is None
    np.testing.assert_array_equal(state.command, [0.0, 0.0])


def test_status_of_reads_the_state(state):
    status = mut.status_of(state)
    assert status.goal is None and status.pending == 2 and not status.finished
    state.goal = state.queue.pop(0)
    state.queue.clear()
    mut.finish_goal(state, 1.0, [1.0, 0.5, 0.0], True, "")
    status = mut.status_of(state)
    assert status.state == "arrived" and status.finished and len(status.results) == 1
    np.testing.assert_array_equal(status.goal, [1.0, 0.5, 0.0])  # the last goal, a copy
    assert status.goal is not state.results[0].goal
    assert status.costmap is state.costmap
