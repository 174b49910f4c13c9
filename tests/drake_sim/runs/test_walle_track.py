"""drake_sim.runs.walle_track: the ground truth read from a Wall-E diagram's log, and what the
robot does in headless runs on a flat floor (``run_walle``): it falls without control, balances
with IMU noise, recovers from pushes, tracks a command, and drives on its casters.

Headless, simulated time, seeded IMU noise. The 10 s balance runs are in the default suite;
the 60 s ones are marked slow.
"""

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

import drake_sim.runs.walle_track as mut
from diagrams.walle_balance import make_walle_diagram
from diagrams.walle_balance_scenario import Push, WalleStart, load_walle_balance_scenario
from drake_sim.base.resources import config_dir
from drake_sim.robots.walle import default_robot_file, linearize_upright
from drake_sim.robots.walle_params import load_walle_params

CONTROLLERS = ("lqr", "pid")
SCALES = [(0.8, 0.7), (0.8, 1.5), (1.25, 0.7), (1.25, 1.5)]


@pytest.fixture(scope="module")
def robot():
    return load_walle_params(default_robot_file())


@pytest.fixture(scope="module")
def scenario():
    return load_walle_balance_scenario(config_dir() / "walle_balance.yaml")


def _with(scenario, controller=None, **changes):
    if controller is not None:
        changes["balance"] = dc.replace(scenario.balance, controller=controller)
    return dc.replace(scenario, **changes)


def _speed_and_yaw_rate(track, after):
    keep = track.t >= after
    t, p, yaw = track.t[keep], track.p_WA[:, keep], track.yaw[keep]
    path = np.sum(np.linalg.norm(np.diff(p, axis=1), axis=0))
    return path / (t[-1] - t[0]), (yaw[-1] - yaw[0]) / (t[-1] - t[0])


def test_track_reads_the_axle_heading_and_lean_from_the_log(robot, scenario):
    """The follow variant standing still on its casters at a start pose: every sample is the
    start (the axle's midpoint, the heading, level), one per log period."""
    start = WalleStart(x=1.0, y=-2.0, yaw=90.0)
    diagram = make_walle_diagram(_with(scenario, driver="diff_drive", start=start), robot)
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    diagram.GetInputPort("cmd_vel").FixValue(context, [0.0, 0.0])
    simulator.AdvanceTo(0.5)
    dut = mut.walle_track(diagram, context, robot)
    assert dut.p_WA.shape == (2, len(dut.t)) and dut.yaw.shape == dut.pitch.shape == dut.t.shape
    np.testing.assert_allclose(np.diff(dut.t), scenario.log_period, rtol=1e-9)
    np.testing.assert_allclose(dut.p_WA.T, np.tile([1.0, -2.0], (len(dut.t), 1)), atol=2e-3)
    np.testing.assert_allclose(dut.yaw, math.radians(90.0), atol=1e-3)
    assert np.degrees(np.abs(dut.pitch)).max() < 1.0


def test_run_reports_what_it_simulated(robot, scenario):
    dut = mut.run_walle(_with(scenario, "lqr"), robot, 0.5, settle_time=0.2, seed=3)
    assert dut.sim_time_s == 0.5 and dut.wall_time_s > 0
    assert dut.real_time_factor == pytest.approx(0.5 / dut.wall_time_s)
    assert dut.track.t[-1] == pytest.approx(0.5) and not dut.fell
    assert dut.max_abs_pitch_deg < 2.0 and dut.max_drift_m < 0.05


def test_falls_in_about_a_second_without_control(robot, scenario):
    """Motors off from a 0.5 degree lean: it lies on the floor within a second, and its lean
    grows as the planar model says, by e in 1 / sqrt(a) s."""
    run = mut.run_walle(_with(scenario, driver="none", start=WalleStart(pitch=0.5)), robot, 1.5)
    pitch, t = np.abs(np.degrees(run.track.pitch)), run.track.t
    lying = t[np.argmax(pitch > 80)]
    assert pitch[t <= 0.3].max() < 10 and 0.5 < lying < 1.0
    growth = math.sqrt(linearize_upright(robot)[0][3, 1])
    ten_fold = t[np.argmax(pitch > 20)] - t[np.argmax(pitch > 2)]
    assert ten_fold == pytest.approx(math.log(10) / growth, rel=0.15)
    assert run.fell


def _assert_balanced(run):
    assert not run.fell
    assert run.max_abs_pitch_deg < 2.0
    assert run.max_drift_m < 0.05


@pytest.mark.parametrize("controller", CONTROLLERS)
def test_balances_with_imu_noise(robot, scenario, controller):
    """From a 2 degree lean, 10 s with the IMU's noise and bias: upright within 2 degrees and
    within 5 cm of the start after the first second."""
    _assert_balanced(
        mut.run_walle(_with(scenario, controller, start=WalleStart(pitch=2.0)), robot, 10.0)
    )


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_balances_for_a_minute(robot, scenario, controller, seed):
    _assert_balanced(mut.run_walle(_with(scenario, controller), robot, 60.0, seed=seed))


@pytest.mark.parametrize("direction", [1.0, -1.0], ids=["forward", "backward"])
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_recovers_from_a_push(robot, scenario, controller, direction):
    """0.3 m g at the top of the body for 0.2 s: it runs with the push, stays up, and stands
    still and upright again within a few seconds."""
    force = [direction * 0.3 * robot.total_mass * 9.81, 0.0, 0.0]
    pushed = _with(scenario, controller, pushes=[Push(time=1.0, force=force, duration=0.2)])
    run = mut.run_walle(pushed, robot, 6.0)
    track = run.track
    assert not run.fell
    assert np.max(direction * track.p_WA[0]) > 0.2  # It was pushed along.
    last = track.t >= 5.0
    assert np.degrees(np.abs(track.pitch[last])).max() < 2.0
    speed, _ = _speed_and_yaw_rate(track, after=5.0)
    assert speed < 0.15


@pytest.mark.parametrize("length, mass", SCALES)
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_scaled_robots_balance_with_the_same_config(robot, scenario, controller, length, mass):
    scaled = robot.scaled(length=length, mass=mass)
    run = mut.run_walle(_with(scenario, controller, start=WalleStart(pitch=2.0)), scaled, 5.0)
    _assert_balanced(run)


@pytest.mark.parametrize("controller", CONTROLLERS)
def test_tracks_speed_and_yaw_rate(robot, scenario, controller):
    run = mut.run_walle(_with(scenario, controller), robot, 6.0, cmd_vel=[0.3, 0.5])
    speed, yaw_rate = _speed_and_yaw_rate(run.track, after=3.0)
    assert speed == pytest.approx(0.3, rel=0.05)
    assert yaw_rate == pytest.approx(0.5, rel=0.05)
    assert not run.fell and run.max_abs_pitch_deg < 2.0


def test_follow_variant_drives_on_its_casters(robot, scenario):
    run = mut.run_walle(_with(scenario, driver="diff_drive"), robot, 4.0, cmd_vel=[0.3, 1.0])
    speed, yaw_rate = _speed_and_yaw_rate(run.track, after=2.0)
    assert speed == pytest.approx(0.3, rel=0.02)
    assert yaw_rate == pytest.approx(1.0, rel=0.02)
    assert run.max_abs_pitch_deg < 1.0  # Level on its casters, never rocking onto one.
