"""Wall-E on a flat floor: the diagram (diagrams.walle_balance): its start pose, encoders, ports
for each driver, drawing and command input. What the robot does in it over whole runs is in
tests/drake_sim/runs/test_walle_track.py."""

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import Simulator

import diagrams.walle_balance as mut
from diagrams.walle_balance_scenario import WalleStart, load_walle_balance_scenario
from drake_sim.base.resources import config_dir
from drake_sim.robots.walle import CASTER_LINKS, WHEEL_JOINTS, default_robot_file
from drake_sim.robots.walle_params import load_walle_params
from drake_sim.systems.axle import axle_yaw_and_pitch


@pytest.fixture(scope="module")
def robot():
    return load_walle_params(default_robot_file())


@pytest.fixture(scope="module")
def scenario():
    return load_walle_balance_scenario(config_dir() / "walle_balance.yaml")


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
    dut = mut.make_walle_diagram(dc.replace(scenario, driver=driver), robot)
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
