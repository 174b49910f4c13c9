"""drake_sim.systems.estimation.pose_graph: a drifting loop is closed by its closure edge, a
wrong closure is held off by the robust loss, and bad edges are refused."""

import math

import numpy as np
import pytest

import drake_sim.systems.estimation.pose_graph as mut
from drake_sim.base.planar import compose, relative_pose

SIGMA = [0.02, 0.02, 0.01]


def square_loop(n_side=25, step=0.2):
    """(truth, odometry-chained estimate) of a square drive of 4 * n_side steps back to the
    start, the odometry turning 0.2 degrees too far each step."""
    truth = [np.zeros(3)]
    for k in range(4 * n_side):
        turn = math.pi / 2 if (k + 1) % n_side == 0 else 0.0
        truth.append(compose(truth[-1], [step, 0.0, turn]))
    truth = np.array(truth)
    steps = relative_pose(truth[:-1], truth[1:])
    steps[:, 2] += math.radians(0.2)
    estimate = [truth[0]]
    for s in steps:
        estimate.append(compose(estimate[-1], s))
    return truth, np.array(estimate), steps


def graph_of(estimate, steps):
    graph = mut.PoseGraph()
    for pose in estimate:
        graph.add_node(pose)
    for k, s in enumerate(steps):
        graph.add_edge(k, k + 1, s, SIGMA)
    return graph


def test_a_closure_edge_pulls_a_drifting_loop_back_to_its_start():
    truth, estimate, steps = square_loop()
    graph = graph_of(estimate, steps)
    last = len(truth) - 1
    assert np.hypot(*estimate[last, :2]) > 0.3  # the drift before
    graph.add_edge(0, last, relative_pose(truth[0], truth[last]), SIGMA)
    graph.optimize()
    poses = graph.poses
    assert np.hypot(*poses[last, :2]) < 0.02
    np.testing.assert_array_equal(poses[0], truth[0])  # the anchor stays
    # every node nearer the truth than the odometry put it
    before = np.hypot(*(estimate[:, :2] - truth[:, :2]).T)
    after = np.hypot(*(poses[:, :2] - truth[:, :2]).T)
    assert after.max() < 0.5 * before.max()


def test_a_wrong_closure_bends_the_graph_less_under_a_robust_loss():
    """Two right closures and one 1.5 m off: plain least squares spreads the wrong one over
    every node, Huber's loss less so, Cauchy's (the default) keeps the loop near the truth."""
    truth, estimate, steps = square_loop()
    error = {}
    for loss in ("linear", "huber", "cauchy"):
        graph = graph_of(estimate, steps)
        last = len(truth) - 1
        graph.add_edge(0, last, relative_pose(truth[0], truth[last]), SIGMA)
        graph.add_edge(10, last - 10, relative_pose(truth[10], truth[last - 10]), SIGMA)
        wrong = relative_pose(truth[50], truth[75]) + [1.5, 0.0, 0.0]
        graph.add_edge(50, 75, wrong, SIGMA)
        graph.optimize(loss=loss)
        error[loss] = np.hypot(*(graph.poses[:, :2] - truth[:, :2]).T).max()
    assert error["cauchy"] < 0.1 < error["huber"] < error["linear"], error


def test_optimising_a_consistent_graph_leaves_it_where_it_is():
    truth, _, _ = square_loop()
    graph = graph_of(truth, relative_pose(truth[:-1], truth[1:]))
    assert graph.optimize() == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(graph.poses, truth, atol=1e-9)


def test_the_jacobian_is_the_residuals_derivative():
    truth, estimate, steps = square_loop(n_side=4)
    graph = graph_of(estimate, steps)
    graph.add_edge(0, 16, relative_pose(truth[0], truth[16]), SIGMA)
    i = np.array([e.i for e in graph.edges])
    j = np.array([e.j for e in graph.edges])
    z = np.array([e.measurement for e in graph.edges])
    w = 1.0 / np.array([e.sigma for e in graph.edges])
    poses = graph.poses
    analytic = mut._jacobian(poses, i, j, w, len(poses)).toarray()
    numeric = np.zeros_like(analytic)
    for column in range(analytic.shape[1]):
        moved = poses.copy()
        moved[1 + column // 3, column % 3] += 1e-7
        difference = mut._residuals(moved, i, j, z, w) - mut._residuals(poses, i, j, z, w)
        numeric[:, column] = difference.reshape(-1) / 1e-7
    np.testing.assert_allclose(analytic, numeric, atol=1e-4)


def test_bad_nodes_and_edges_are_refused():
    graph = mut.PoseGraph()
    with pytest.raises(ValueError, match="3 finite"):
        graph.add_node([0.0, math.nan, 0.0])
    graph.add_node([0.0, 0.0, 0.0])
    graph.add_node([1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="two different nodes"):
        graph.add_edge(0, 2, [1.0, 0.0, 0.0], SIGMA)
    with pytest.raises(ValueError, match="two different nodes"):
        graph.add_edge(1, 1, [1.0, 0.0, 0.0], SIGMA)
    with pytest.raises(ValueError, match="sigma"):
        graph.add_edge(0, 1, [1.0, 0.0, 0.0], [0.1, 0.0, 0.1])
    with pytest.raises(ValueError, match="measurement"):
        graph.add_edge(0, 1, [1.0, math.inf, 0.0], SIGMA)
    with pytest.raises(ValueError, match="loss"):
        graph.optimize(loss="tukey")
    assert graph.optimize() == 0.0  # no edges: nothing to do


def test_a_copy_is_independent_of_the_graph_it_came_from():
    """As Drake's state is copied at every scan: optimising or growing the copy leaves the
    original's nodes and edges as they were."""
    truth, estimate, steps = square_loop()
    graph = graph_of(estimate, steps)
    last = len(truth) - 1
    twin = graph.copy()
    twin.add_edge(0, last, relative_pose(truth[0], truth[last]), SIGMA)
    twin.optimize()
    twin.add_node([9.0, 9.0, 0.0])
    assert len(graph) == len(estimate) and len(graph.edges) == len(steps)
    np.testing.assert_array_equal(graph.poses, estimate)
    np.testing.assert_array_equal(graph.pose(last), estimate[last])
    assert np.hypot(*twin.pose(last)[:2]) < 0.02
