"""The compiled TOPP-RA (planning.timing.toppra): Drake's Toppra's durations on the same grid,
the limits held at every grid point, rest to rest, and no answer where a stop is forced."""

import numpy as np
import pytest
from pydrake.multibody.optimization import CalcGridPointsOptions, Toppra

import planning.timing.toppra as mut
from planning.timing.spline_section import chain_plant, drake_spline

V_MAX = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])
A_MAX = np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])


def random_path(seed: int):
    waypoints = np.cumsum(np.random.default_rng(seed).normal(scale=0.3, size=(6, 7)), axis=0)
    path, knots = drake_spline(waypoints)
    grid = Toppra.CalcGridPoints(
        path, CalcGridPointsOptions(max_err=1e-4, max_iter=100, max_seg_length=0.02, min_points=12)
    )
    return path, np.asarray(grid)


@pytest.mark.parametrize("seed", range(4))
def test_the_same_duration_as_drakes_toppra(seed):
    path, grid = random_path(seed)
    drake = Toppra(path, chain_plant(7), grid)
    drake.AddJointVelocityLimit(-V_MAX, V_MAX)
    drake.AddJointAccelerationLimit(-A_MAX, A_MAX)
    expected = drake.SolvePathParameterization().end_time()
    s = mut.parameterize(path, grid, V_MAX, A_MAX)
    assert s.end_time() == pytest.approx(expected, rel=1e-3)


@pytest.mark.parametrize("seed", range(4))
def test_limits_hold_at_the_grid_points_from_rest_to_rest(seed):
    path, grid = random_path(seed)
    s = mut.parameterize(path, grid, V_MAX, A_MAX)
    x = mut.solve(
        grid,
        np.ascontiguousarray(path.MakeDerivative(1).vector_values(grid).T),
        np.ascontiguousarray(path.MakeDerivative(2).vector_values(grid).T),
        V_MAX,
        A_MAX,
    )
    assert x[0] == 0.0 and x[-1] == 0.0 and np.all(x >= 0.0)
    # The grid points' times, then the joint rates there.
    rate = np.sqrt(x)
    times = np.concatenate([[0.0], np.cumsum(2.0 * np.diff(grid) / (rate[:-1] + rate[1:]))])
    np.testing.assert_allclose(s.vector_values(times)[0], grid, atol=1e-9)
    np.testing.assert_allclose(s.MakeDerivative(1).vector_values(times)[0], rate, atol=1e-9)
    u = np.diff(x) / (2.0 * np.diff(grid))  # s_ddot on each interval
    dq = path.MakeDerivative(1).vector_values(grid).T
    ddq = path.MakeDerivative(2).vector_values(grid).T
    assert np.all(np.abs(dq * rate[:, None]) <= V_MAX * (1 + 1e-9))
    for i in range(len(grid) - 1):  # both ends of every interval (interpolation)
        for k in (i, i + 1):
            a = dq[k] * u[i] + ddq[k] * x[k]
            assert np.all(np.abs(a) <= A_MAX * (1 + 1e-6) + 1e-9)
    assert np.all(np.diff(s.vector_values(np.linspace(0, s.end_time(), 500))[0]) >= -1e-12)


def test_a_forced_stop_midway_is_kept_and_a_path_that_cannot_start_has_none():
    from pydrake.trajectories import PiecewisePolynomial

    grid = np.linspace(0.0, 1.0, 11)
    dq = np.tile(np.eye(7)[0], (11, 1))
    ddq = np.zeros((11, 7))
    x = mut.solve(grid, dq, ddq, V_MAX, A_MAX)
    assert len(x) == 11 and np.all(x[1:-1] > 0.0)
    # At s = 0.5 the path stands still in joint 1 and curves in joint 2, which may not
    # accelerate: the motion must stop there, and goes on after.
    dq[5] = 0.0
    ddq[5, 1] = 1.0
    a_max = A_MAX.copy()
    a_max[1] = 0.0
    x = mut.solve(grid, dq, ddq, V_MAX, a_max)
    assert x[5] == 0.0 and x[4] > 0.0 and x[6] > 0.0
    # Joint 1 moves along the whole path but may not accelerate: it can never start.
    line = PiecewisePolynomial.FirstOrderHold([0.0, 1.0], np.vstack([np.zeros(7), np.eye(7)[0]]).T)
    a_max = A_MAX.copy()
    a_max[0] = 0.0
    assert mut.parameterize(line, grid, V_MAX, a_max) is None
