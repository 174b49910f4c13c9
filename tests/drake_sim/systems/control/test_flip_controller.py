"""The flip controller's state machine, and the flipping robot end to end."""

import dataclasses as dc

import numpy as np
import pytest

import drake_sim.systems.control.flip_controller as mut
from drake_sim.systems.control.flip_controller import FlipMode
from tests.flip_helpers import default_robot, flip_scenario, run_for

MODE, SIGN, FLIPS, FAILED, RECOVERIES, ATTEMPTS = range(6)


def _mode_sequence(run):
    """The modes in the order visited (consecutive repeats dropped), with the travel sign."""
    status = run.log("status").data()
    changes = np.r_[True, np.diff(status[MODE]) != 0]
    return [(FlipMode(int(m)), int(s)) for m, s in status[[MODE, SIGN]][:, changes].T]


def test_drive_flip_settle_drive():
    run = run_for(4.0)
    sequence = _mode_sequence(run)
    assert [m for m, _ in sequence[:4]] == [
        FlipMode.DRIVE,
        FlipMode.FLIP,
        FlipMode.SETTLE,
        FlipMode.DRIVE,
    ]
    status = run.log("status").data()
    assert status[SIGN, 1] == 1  # Upright, driving towards the wheels...
    after_first_flip = np.flatnonzero(status[FLIPS] == 1)
    assert status[SIGN, after_first_flip[len(after_first_flip) // 2]] == -1  # ...then upside down.
    assert status[FLIPS, -1] >= 1 and status[FAILED, -1] == 0


def test_one_command_for_both_wheels_and_the_same_speed():
    """The controller has a single torque output; the wheels' drivers keep both wheels at the
    same speed, through drives and flips."""
    robot = default_robot()
    dut = mut.FlipController(robot=robot, config=mut.FlipConfig())
    assert dut.GetOutputPort("wheel_torque").size() == 1
    run = run_for(4.0)
    torques = run.log("wheel_torques").data()
    assert np.max(np.abs(torques)) == pytest.approx(robot.motor.max_torque)
    wheel_state = run.log("wheel_state").data()
    assert np.max(np.abs(wheel_state[2] - wheel_state[3])) < 0.05  # rad/s


def test_starts_upside_down():
    run = run_for(6.0, scenario=flip_scenario(upside_down=True))
    status = run.log("status").data()
    assert status[SIGN, 1] == -1
    assert status[FLIPS, -1] >= 2 and status[FAILED, -1] == 0


def test_a_flip_that_fails_is_recovered():
    """Motors too weak to lift the body: each flip times out, the controller rocks the robot
    back down and drives on; it never gets stuck and never produces NaN."""
    weak = dc.replace(default_robot(), motor=dc.replace(default_robot().motor, max_torque=1.0))
    run = run_for(8.0, robot=weak)
    report = run.report()
    assert report.failed_flips >= 2
    assert report.recoveries >= 2
    assert report.flips == 0
    assert report.finite
    modes = {m for m, _ in _mode_sequence(run)}
    assert modes == {FlipMode.DRIVE, FlipMode.FLIP, FlipMode.RECOVER}


def test_flip_torque_follows_the_robot():
    light, heavy = default_robot().scaled(mass=0.7), default_robot().scaled(mass=1.5)
    config = mut.FlipConfig()
    a = mut.FlipController(robot=light, config=config)
    b = mut.FlipController(robot=heavy, config=config)
    # Holding the body level (progress 0, no rate error) takes torque in proportion to mass.
    rate = config.flip_rate
    assert b._flip_torque(0.0, rate) == pytest.approx(a._flip_torque(0.0, rate) * 1.5 / 0.7)


def _check_flipping(report, *, flips, drift):
    assert report.finite
    assert report.flips >= flips
    assert report.max_lateral_deviation_m <= drift
    assert report.travel_extent_m >= 1.0
    assert not report.stuck
    assert report.failed_flips <= report.recoveries + 1  # Every failure is recovered.


def test_default_scenario_acceptance():
    """20 s in the street world: at least 10 flips, on the line, odometry within 5 %."""
    run = run_for(20.0, scenario=flip_scenario(world=True))
    report = run.report()
    _check_flipping(report, flips=10, drift=0.25)
    assert report.failed_flips == 0
    assert report.longest_time_without_flip_s < 4.0
    assert report.odometry_error_m <= 0.05 * report.distance_travelled_m
    assert report.naive_odometry_error_m > 5 * report.odometry_error_m


@pytest.mark.parametrize(
    "length, mass",
    [(0.8, 1.0), (1.25, 1.0), (1.0, 0.7), (1.0, 1.5)],
    ids=["lengths-x0.8", "lengths-x1.25", "masses-x0.7", "masses-x1.5"],
)
def test_scaled_robots_still_flip(tmp_path, length, mass):
    """The same controller file drives robots of other sizes (written to YAML and read back,
    as a user would)."""
    from drake_sim.robots.ddrive_params import load_robot_params, write_robot_params

    path = tmp_path / "robot.yaml"
    write_robot_params(default_robot().scaled(length=length, mass=mass), path)
    run = run_for(20.0, robot=load_robot_params(path), scenario=flip_scenario(world=True))
    _check_flipping(run.report(), flips=5, drift=0.5)
