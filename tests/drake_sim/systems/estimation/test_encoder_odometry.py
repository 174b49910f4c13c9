"""Encoder odometry with calibration error and slip, and the planar ground truth
(drake_sim.systems.estimation.encoder_odometry)."""

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

import drake_sim.systems.estimation.encoder_odometry as mut
from drake_sim.base.errors import ConfigError
from tests.drake_sim.robots.test_turtlebot3 import simulate_drive

R, W = 0.033, 0.287  # The Waffle's wheel radius and separation, m.


def _wheel_trajectory(moves):
    """Joint angles for ``moves``, a list of ``(seconds, distance m, turn rad)`` of the base
    (a straight drive, a turn on the spot or an arc), each at a constant rate."""
    times, q = [0.0], [np.zeros(4)]
    for seconds, distance, turn in moves:
        left = (distance - turn * W / 2) / R
        right = (distance + turn * W / 2) / R
        times.append(times[-1] + seconds)
        q.append(q[-1] + [left, right, 0.0, 0.0])
    return PiecewisePolynomial.FirstOrderHold(times, np.array(q).T), times[-1]


def _run(moves, config, *, seed=0, initial_pose=(0.0, 0.0, 0.0)):
    """Feeds the joint angles of ``moves`` to the odometry; returns its pose at the end and
    its twist halfway."""
    trajectory, end = _wheel_trajectory(moves)
    builder = DiagramBuilder()
    source = builder.AddSystem(TrajectorySource(trajectory))
    dut = builder.AddSystem(
        mut.EncoderOdometry(
            wheel_radius=R,
            wheel_separation=W,
            config=config,
            initial_pose=initial_pose,
            seed=seed,
        )
    )
    builder.Connect(source.get_output_port(), dut.GetInputPort("wheel_state"))
    simulator = Simulator(builder.Build())
    context = dut.GetMyContextFromRoot(simulator.get_context())
    simulator.AdvanceTo(end / 2)
    twist = dut.GetOutputPort("twist").Eval(context).copy()
    simulator.AdvanceTo(end + 1.5 / config.rate)  # Past the update at the end.
    return dut.GetOutputPort("pose").Eval(context).copy(), twist


SQUARE = [(5.0, 1.0, 0.0), (1.0, 0.0, math.pi / 2)] * 4  # 1 m sides, turning left.


def test_quantise_reads_whole_ticks():
    tick = 2 * math.pi / 4096
    q = np.array([0.0, 0.9 * tick, 1.0 * tick, -0.1 * tick, 123.456])
    dut = mut.quantise(q, 4096)
    np.testing.assert_allclose(dut[:4], [0.0, 0.0, tick, -tick], atol=1e-15)
    assert 0 <= q[4] - dut[4] < tick
    np.testing.assert_allclose(dut / tick, np.round(dut / tick), atol=1e-9)


def test_exact_odometry_follows_the_wheels():
    """No calibration error or slip: a 1 m square comes back to its start, and an arc ends
    where the closed form says, within the encoders' resolution."""
    pose, _ = _run(SQUARE, mut.EncoderOdometryConfig.exact(), initial_pose=(1.0, 2.0, 0.5))
    np.testing.assert_allclose(pose, [1.0, 2.0, 0.5], atol=1e-3)
    radius, angle = 1.0, math.pi / 3
    pose, twist = _run([(4.0, radius * angle, angle)], mut.EncoderOdometryConfig.exact())
    expected = [radius * math.sin(angle), radius * (1 - math.cos(angle)), angle]
    np.testing.assert_allclose(pose, expected, atol=1e-3)
    # Over one update, a tick more or less on either wheel is 7 % of the turn rate.
    np.testing.assert_allclose(twist, [radius * angle / 4, angle / 4], rtol=0.1)


def test_calibration_error_has_the_set_size_and_a_seeded_sign():
    config = mut.EncoderOdometryConfig()
    draws = {
        seed: mut.OdometryCalibration.draw(config, wheel_radius=R, wheel_separation=W, seed=seed)
        for seed in range(16)
    }
    assert draws[3] == mut.OdometryCalibration.draw(
        config, wheel_radius=R, wheel_separation=W, seed=3
    )
    for dut in draws.values():
        mean = 0.5 * (dut.left_radius + dut.right_radius)
        assert abs(mean / R - 1) == pytest.approx(config.wheel_radius_error)
        difference = (dut.right_radius - dut.left_radius) / mean
        assert abs(difference) == pytest.approx(config.wheel_radius_difference, rel=0.02)
        assert abs(dut.separation / W - 1) == pytest.approx(config.wheel_separation_error)
    # Each error takes either sign, depending on the seed.
    assert {d.separation > W for d in draws.values()} == {True, False}
    assert {d.left_radius + d.right_radius > 2 * R for d in draws.values()} == {True, False}
    assert {d.right_radius > d.left_radius for d in draws.values()} == {True, False}
    exact = mut.OdometryCalibration.draw(
        mut.EncoderOdometryConfig.exact(), wheel_radius=R, wheel_separation=W, seed=5
    )
    assert exact == mut.OdometryCalibration(R, R, W)


def test_default_errors_drift_deterministically_per_seed():
    config = mut.EncoderOdometryConfig()
    first, _ = _run(SQUARE, config, seed=1)
    again, _ = _run(SQUARE, config, seed=1)
    other, _ = _run(SQUARE, config, seed=2)
    np.testing.assert_array_equal(first, again)
    assert not np.allclose(first, other, atol=1e-4)
    for pose in (first, other):
        # Drift of a few centimetres and a few tenths of a degree over 4 m and 4 turns.
        assert 0.002 < np.linalg.norm(pose[:2]) < 0.2
        assert 1e-3 < abs(pose[2]) < math.radians(5)


def _route_moves(waypoints, speed=0.2, turn_rate=1.0):
    """Turn on the spot towards each waypoint, then drive to it; returns the moves and the
    final pose."""
    (x, y), yaw, moves = waypoints[0], 0.0, []
    for a, b in waypoints[1:]:
        heading = math.atan2(b - y, a - x)
        turn = math.remainder(heading - yaw, 2 * math.pi)
        distance = math.hypot(a - x, b - y)
        moves += [(abs(turn) / turn_rate + 1e-3, 0.0, turn), (distance / speed, distance, 0.0)]
        x, y, yaw = a, b, yaw + turn
    return moves, (x, y, yaw)


def test_default_drift_over_a_room_route_is_what_slam_must_correct():
    """A 37 m lawnmower route with 13 turns in a 6 m x 5 m room: the default errors drift by
    tens of centimetres to a couple of metres and tens of degrees: a poorly calibrated robot's
    odometry, the kind that needs SLAM."""
    waypoints = [(-2, -1.5), (2, -1.5), (2, -0.5), (-2, -0.5), (-2, 0.5), (2, 0.5), (2, 1.5)]
    waypoints += [(-2, 1.5), (-2, -1.5), (0, 0), (2, -1.5), (2, 1.5), (-2, 1.5), (-2, -1.5)]
    moves, (x, y, yaw) = _route_moves(waypoints)
    drifts, yaw_errors = [], []
    for seed in range(4):
        pose, _ = _run(moves, mut.EncoderOdometryConfig(), seed=seed, initial_pose=(-2, -1.5, 0))
        drifts.append(math.hypot(pose[0] - x, pose[1] - y))
        yaw_errors.append(abs(math.degrees(math.remainder(pose[2] - yaw, 2 * math.pi))))
    assert 0.2 < np.median(drifts) < 1.5 and max(drifts) < 3.0
    assert 3.0 < np.median(yaw_errors) < 30.0


def test_slip_noise_grows_with_the_square_root_of_distance():
    """Only slip, over 10 m straight: each wheel's distance error has a variance of
    slip_noise^2 per metre, so across seeds the distance's spread is slip_noise * sqrt(10 / 2)
    and the heading's slip_noise * sqrt(2 * 10) / separation, with a heading of zero mean."""
    slip = 0.002
    config = dc.replace(mut.EncoderOdometryConfig.exact(), slip_noise=slip)
    poses = np.array([_run([(10.0, 10.0, 0.0)], config, seed=seed)[0] for seed in range(40)])
    assert np.std(poses[:, 0]) == pytest.approx(slip * math.sqrt(10 / 2), rel=0.35)
    yaw_spread = slip * math.sqrt(2 * 10) / W
    assert np.std(poses[:, 2]) == pytest.approx(yaw_spread, rel=0.35)
    assert abs(np.mean(poses[:, 2])) < 3 * yaw_spread / math.sqrt(40)
    # The distance comes out short on average: the noisy heading wanders off the line.
    assert np.mean(poses[:, 0]) < 10.0


BAD = {
    "rate": ({"rate": 0.0}, "rate"),
    "ticks": ({"ticks_per_revolution": 0}, "ticks_per_revolution"),
    "nan": ({"slip_noise": math.nan}, "slip_noise"),
    "negative-slip": ({"slip_noise": -0.1}, "slip_noise"),
    "negative-error": ({"wheel_radius_error": -0.01}, "wheel_radius_error"),
    "huge-error": ({"wheel_separation_error": 0.5}, "wheel_separation_error"),
}


@pytest.mark.parametrize("edits, key", BAD.values(), ids=BAD.keys())
def test_bad_config_names_the_field(edits, key):
    config = dc.replace(mut.EncoderOdometryConfig(), **edits)
    with pytest.raises(ConfigError, match=key):
        mut.EncoderOdometry(wheel_radius=R, wheel_separation=W, config=config)
    with pytest.raises(ConfigError, match=f"^scenario.yaml: 'odometry.{key}' must be"):
        mut.check_config(config, "scenario.yaml", prefix="odometry.")


def test_planar_ground_truth_reads_the_body_pose():
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    body = plant.AddRigidBody("box", SpatialInertia.SolidBoxWithMass(1.0, 0.1, 0.1, 0.1))
    plant.Finalize()
    dut = builder.AddSystem(mut.PlanarGroundTruth(plant=plant, body=body))
    builder.Connect(plant.get_body_poses_output_port(), dut.GetInputPort("body_poses"))
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    X_WB = RigidTransform(RollPitchYaw(0.0, 0.0, 2.5), [1.0, -2.0, 0.3])
    plant.SetFreeBodyPose(plant.GetMyMutableContextFromRoot(context), body, X_WB)
    pose = dut.GetOutputPort("pose").Eval(dut.GetMyContextFromRoot(context))
    np.testing.assert_allclose(pose, [1.0, -2.0, 2.5], atol=1e-12)
    np.testing.assert_allclose(mut.planar_pose(X_WB), pose)


ROUTE = [(5.0, 0.2, 0.0), (2.0, 0.0, math.pi / 4), (5.0, 0.2, 0.0), (2.0, 0.0, -math.pi / 4)]
ROUTE += [(5.0, 0.2, 0.0)]  # About 3 m with two turns on the spot, driven by cmd_vel.


def test_exact_odometry_matches_the_simulated_robot():
    """Only the simulated contact's own creep and scrub (a few tenths of a percent) is left."""
    run = simulate_drive(ROUTE, odometry=mut.EncoderOdometryConfig.exact(), start=(-1, 1, 0))
    assert np.linalg.norm(run.truth[:2, -1] - [-1, 1]) > 2.0
    # The odometry is held between its updates (50 Hz), so while turning at 0.8 rad/s it
    # lags the truth by up to a degree: compare the heading where the robot is not turning.
    error = np.linalg.norm(run.odometry[:2] - run.truth[:2], axis=0)
    assert np.max(error) < 0.01
    steady = np.abs(np.gradient(np.unwrap(run.truth[2]), run.times)) < 0.01
    assert np.count_nonzero(steady) > len(steady) / 2
    yaw_error = np.angle(np.exp(1j * (run.odometry[2] - run.truth[2])))[steady]
    assert np.max(np.abs(yaw_error)) < math.radians(1.0)


def test_default_odometry_drifts_on_the_simulated_robot():
    runs = [simulate_drive(ROUTE, seed=seed) for seed in (7, 7, 8)]
    np.testing.assert_array_equal(runs[0].odometry, runs[1].odometry)
    assert not np.allclose(runs[0].odometry[:, -1], runs[2].odometry[:, -1], atol=1e-4)
    for run in (runs[0], runs[2]):
        drift = np.linalg.norm(run.odometry[:2] - run.truth[:2], axis=0)
        assert 0.01 < np.max(drift) < 0.15
