"""diagrams.flip: make_flip_diagram exports the ports it documents for each controller, logs
``LOGGED``, reads the wheel encoders with ``wheel_state_selector``, and a short run on bare
ground stays finite."""

import numpy as np
import pytest
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import Simulator

import diagrams.flip as mut
from drake_sim.robots.ddrive import LEFT_WHEEL_JOINT, RIGHT_WHEEL_JOINT
from drake_sim.systems.control.flip_controller import STATUS_FIELDS
from drake_sim.systems.sensors.imu import IMU_SIZE
from tests.flip_helpers import default_robot, flip_scenario

OUTPUTS = (
    "imu",
    "wheel_state",
    "odometry_pose",
    "odometry_twist",
    "odometry_covariance",
    "naive_pose",
    "distance",
    "true_pose",
    "wheel_torques",
)


@pytest.fixture(scope="module")
def robot():
    return default_robot()


@pytest.fixture(scope="module")
def scenario():
    return flip_scenario()  # bare ground: fast


@pytest.fixture(scope="module")
def meshcat():
    return Meshcat()


def _outputs(diagram) -> set[str]:
    return {diagram.get_output_port(i).get_name() for i in range(diagram.num_output_ports())}


def _inputs(diagram) -> set[str]:
    return {diagram.get_input_port(i).get_name() for i in range(diagram.num_input_ports())}


def test_flip_controller_ports_and_loggers(scenario, robot):
    dut = mut.make_flip_diagram(scenario, robot)
    assert _outputs(dut) == {*OUTPUTS, "status"}
    assert _inputs(dut) == set()
    assert dut.GetOutputPort("status").size() == len(STATUS_FIELDS)
    assert dut.GetOutputPort("imu").size() == IMU_SIZE
    assert dut.GetOutputPort("wheel_state").size() == 4
    assert dut.GetOutputPort("wheel_torques").size() == 2
    for name in mut.LOGGED:
        assert dut.HasSubsystemNamed(f"log_{name}")
    assert dut.HasSubsystemNamed("flip_controller") and not dut.HasSubsystemNamed("diff_drive")
    assert not dut.HasSubsystemNamed("trails")  # no Meshcat, no trails


def test_cmd_vel_controller_ports(scenario, robot):
    dut = mut.make_flip_diagram(scenario, robot, controller="cmd_vel")
    assert _outputs(dut) == set(OUTPUTS)  # no status without the flip controller
    assert _inputs(dut) == {"cmd_vel"}
    assert dut.GetInputPort("cmd_vel").size() == 2
    assert dut.HasSubsystemNamed("diff_drive") and not dut.HasSubsystemNamed("log_status")


def test_teleop_and_viewer_with_meshcat(scenario, robot, meshcat):
    dut = mut.make_flip_diagram(scenario, robot, meshcat=meshcat, controller="teleop")
    assert _inputs(dut) == set() and _outputs(dut) == set(OUTPUTS)
    assert dut.HasSubsystemNamed("teleop") and dut.HasSubsystemNamed("trails")
    flip = mut.make_flip_diagram(scenario, robot, meshcat=meshcat)
    assert flip.HasSubsystemNamed("trails") and not flip.HasSubsystemNamed("teleop")


def test_bad_controller_arguments(scenario, robot):
    with pytest.raises(ValueError, match="unknown controller 'joystick'"):
        mut.make_flip_diagram(scenario, robot, controller="joystick")
    with pytest.raises(ValueError, match="teleop needs a Meshcat"):
        mut.make_flip_diagram(scenario, robot, controller="teleop")


def test_wheel_state_selector_reads_the_encoders(scenario, robot):
    dut = mut.make_flip_diagram(scenario, robot)
    plant = dut.GetSubsystemByName("plant")
    instance = plant.GetModelInstanceByName("ddrive")
    S = mut.wheel_state_selector(plant, instance)
    assert S.shape == (4, plant.num_positions() + plant.num_velocities())
    assert np.all(S.sum(axis=1) == 1.0)  # one joint value per row
    context = dut.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    for joint_name, q, v in ((LEFT_WHEEL_JOINT, 0.3, -1.5), (RIGHT_WHEEL_JOINT, -0.7, 2.0)):
        joint = plant.GetJointByName(joint_name, instance)
        joint.set_angle(plant_context, q)
        joint.set_angular_rate(plant_context, v)
    np.testing.assert_allclose(dut.GetOutputPort("wheel_state").Eval(context), [0.3, -0.7, -1.5, 2])


def test_short_flip_run_stays_finite(scenario, robot):
    dut = mut.make_flip_diagram(scenario, robot)
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    start = dut.GetOutputPort("true_pose").Eval(context).copy()
    np.testing.assert_allclose(dut.GetOutputPort("odometry_pose").Eval(context), start, atol=1e-9)
    simulator.AdvanceTo(0.5)
    for name in _outputs(dut):
        assert np.all(np.isfinite(dut.GetOutputPort(name).Eval(context))), name
    end = dut.GetOutputPort("true_pose").Eval(context)
    assert 0.05 < end[0] - start[0] < 0.5  # drove towards its wheels (+x), at most 0.8 m/s
    assert abs(end[1] - start[1]) < 0.01
    assert dut.GetOutputPort("distance").Eval(context)[0] > 0.05
    log = dut.GetSubsystemByName("log_true_pose").FindLog(context)
    np.testing.assert_allclose(np.diff(log.sample_times()), scenario.log_period)
    assert log.data().shape == (3, 26)  # t = 0, 0.02, ..., 0.5
    assert np.all(np.isfinite(log.data()))


def test_cmd_vel_zero_holds_the_robot(scenario, robot):
    dut = mut.make_flip_diagram(scenario, robot, controller="cmd_vel")
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    dut.GetInputPort("cmd_vel").FixValue(context, np.zeros(2))
    start = dut.GetOutputPort("true_pose").Eval(context).copy()
    simulator.AdvanceTo(0.3)
    end = dut.GetOutputPort("true_pose").Eval(context)
    assert np.all(np.isfinite(end))
    np.testing.assert_allclose(end, start, atol=5e-3)
    np.testing.assert_allclose(dut.GetOutputPort("wheel_state").Eval(context)[2:], 0, atol=0.05)
