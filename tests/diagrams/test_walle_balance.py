"""Wall-E on a flat floor: the diagram, and what the robot does in it (diagrams.walle_balance).

Headless, simulated time, seeded IMU noise. The 10 s balance runs are in the default suite;
the 60 s ones are marked slow.
"""

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.geometry import Meshcat
from pydrake.multibody.tree import BodyIndex
from pydrake.systems.analysis import Simulator

import diagrams.walle_balance as mut
from diagrams.walle_balance_scenario import Push, WalleStart, load_walle_balance_scenario
from drake_sim.base.resources import config_dir
from drake_sim.robots.walle import (
    CASTER_LINKS,
    WHEEL_JOINTS,
    default_robot_file,
    linearize_upright,
)
from drake_sim.robots.walle_params import load_walle_params
from drake_sim.systems.axle import axle_yaw_and_pitch

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


@pytest.mark.parametrize("pitch", [0.0, 5.0, -30.0])
def test_start_pose_stands_the_wheels_on_the_floor(robot, pitch):
    X_WB = mut.walle_start_pose(WalleStart(x=1.0, y=-2.0, yaw=90.0, pitch=pitch), robot)
    p_WA = X_WB @ np.array([0.0, 0.0, robot.axle_z])
    np.testing.assert_allclose(p_WA, [1.0, -2.0, robot.wheel.radius], atol=1e-12)
    R = X_WB.rotation().matrix()
    np.testing.assert_allclose(R[:, 1], [-1.0, 0.0, 0.0], atol=1e-12)  # The axle along -x.
    yaw, lean = axle_yaw_and_pitch(R)
    assert math.degrees(lean) == pytest.approx(pitch)
    assert math.degrees(yaw) == pytest.approx(90.0)


def test_push_schedule_adds_overlapping_pushes(robot):
    pushes = [Push(time=1.0, force=[1.0, 0, 0], duration=0.5), Push(1.2, [0, 2.0, 0], 0.1)]
    dut = mut.PushSchedule(body_index=BodyIndex(3), p_BoBq_B=[0, 0, robot.top_z], pushes=pushes)
    np.testing.assert_array_equal(dut.force_at(0.99), [0, 0, 0])
    np.testing.assert_array_equal(dut.force_at(1.25), [1.0, 2.0, 0])
    np.testing.assert_array_equal(dut.force_at(1.5), [0, 0, 0])
    context = dut.CreateDefaultContext()
    context.SetTime(1.1)
    (force,) = dut.get_output_port().Eval(context)
    assert int(force.body_index) == 3
    np.testing.assert_allclose(force.p_BoBq_B, [0, 0, robot.top_z])
    np.testing.assert_allclose(force.F_Bq_W.translational(), [1.0, 0, 0])
    np.testing.assert_allclose(force.F_Bq_W.rotational(), [0, 0, 0])


def test_wheel_encoders_read_the_wheel_joints(robot, scenario):
    diagram = mut.make_walle_diagram(scenario, robot)
    plant = diagram.GetSubsystemByName("plant")
    context = plant.CreateDefaultContext()
    instance = plant.GetModelInstanceByName(mut.ROBOT_NAME)
    for i, name in enumerate(WHEEL_JOINTS):
        joint = plant.GetJointByName(name, instance)
        joint.set_angle(context, 1.0 + i)
        joint.set_angular_rate(context, -3.0 - i)
    state = plant.GetPositionsAndVelocities(context)
    np.testing.assert_array_equal(mut.wheel_encoders(plant, instance) @ state, [1, 2, -3, -4])


@pytest.mark.parametrize("driver", ["balance", "diff_drive", "none"])
def test_ports_for_each_driver(robot, scenario, driver):
    dut = mut.make_walle_diagram(_with(scenario, driver=driver), robot)
    outputs = {dut.get_output_port(i).get_name() for i in range(dut.num_output_ports())}
    expected = {"walle.state", "imu", "wheel_state", "pitch_estimate", "wheel_torques"}
    assert outputs == expected | ({"status"} if driver == "balance" else set())
    assert dut.HasInputPort("cmd_vel") == (driver != "none")
    plant = dut.GetSubsystemByName("plant")
    assert all(plant.HasBodyNamed(name) == (driver == "diff_drive") for name in CASTER_LINKS)
    assert not dut.HasSubsystemNamed("pushes")  # Only built when there are pushes.


def test_draws_in_meshcat(robot, scenario):
    """With a Meshcat, the robot (and its sensor mounts) is drawn; a short run publishes."""
    meshcat = Meshcat()
    diagram = mut.make_walle_diagram(scenario, robot, meshcat=meshcat)
    simulator = Simulator(diagram)
    diagram.GetInputPort("cmd_vel").FixValue(simulator.get_mutable_context(), [0.0, 0.0])
    simulator.AdvanceTo(0.1)
    assert meshcat.HasPath("/drake/illustration/walle/base_link")
    assert meshcat.HasPath("/drake/illustration/walle/camera_link")


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


def test_cmd_vel_port_drives_the_diagram(robot, scenario):
    """The exported ``cmd_vel`` is the balance controller's command (what the line follower
    will connect to)."""
    diagram = mut.make_walle_diagram(scenario, robot)
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    diagram.GetInputPort("cmd_vel").FixValue(context, [0.2, 0.0])
    simulator.AdvanceTo(1.0)
    fallen, s, s_ref, _, _ = diagram.GetOutputPort("status").Eval(context)
    assert fallen == 0.0 and s > 0.05 and s_ref > 0.05
