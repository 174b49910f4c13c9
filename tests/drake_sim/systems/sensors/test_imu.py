"""The simulated IMU (drake_sim.systems.sensors.imu)."""

import numpy as np
import pytest
from pydrake.common import RandomGenerator
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.multibody.tree import SpatialInertia, UnitInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

import drake_sim.systems.sensors.imu as mut
from tests.flip_helpers import flip_scenario, run_for


def _free_box(config, *, time_step=1e-3):
    """A free 1 kg body with an IMU, no contact: it falls, so it reads zero specific force."""
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlantSceneGraph(builder, time_step=time_step)
    body = plant.AddRigidBody("box", SpatialInertia(1.0, np.zeros(3), UnitInertia(0.1, 0.1, 0.1)))
    plant.Finalize()
    dut = mut.add_imu(builder, plant, body, config)
    builder.ExportOutput(dut.GetOutputPort("imu"), "imu")
    builder.ExportOutput(dut.GetOutputPort("delta_velocity"), "delta_velocity")
    return builder.Build(), plant, body


def _noise_free():
    return mut.ImuConfig(
        orientation_noise=0,
        angular_velocity_noise=0,
        linear_acceleration_noise=0,
        angular_velocity_bias=0,
        linear_acceleration_bias=0,
    )


def test_robot_upside_down_at_rest():
    """The robot lying on its top caster: the IMU reports it upside down, with the specific
    force (9.81 m/s^2 up in the world) along the body's -z axis, and no rotation."""
    run = run_for(
        0.5, scenario=flip_scenario(upside_down=True), controller="cmd_vel", cmd_vel=[0.0, 0.0]
    )
    imu = run.diagram.GetOutputPort("imu").Eval(run.context)
    R_WB = mut.rotation_from_imu(imu)
    assert R_WB[2, 2] < -0.999  # body z points down
    config = flip_scenario().imu
    tol = 5 * np.hypot(config.linear_acceleration_noise, config.linear_acceleration_bias)
    np.testing.assert_allclose(imu[mut.LINEAR_ACCELERATION], [0, 0, -9.81], atol=tol)
    gyro_tol = 5 * np.hypot(config.angular_velocity_noise, config.angular_velocity_bias)
    np.testing.assert_allclose(imu[mut.ANGULAR_VELOCITY], 0, atol=gyro_tol)


def test_free_fall_delta_velocity_is_zero_and_noise_is_seeded():
    diagram, plant, body = _free_box(mut.ImuConfig())
    samples = []
    for seed in (1, 1, 2):
        simulator = Simulator(diagram)
        diagram.SetRandomContext(simulator.get_mutable_context(), RandomGenerator(seed))
        simulator.AdvanceTo(0.05)
        samples.append(diagram.GetOutputPort("imu").Eval(simulator.get_context()).copy())
    np.testing.assert_array_equal(samples[0], samples[1])  # same seed, same noise
    assert not np.array_equal(samples[0], samples[2])
    # In free fall the specific force is zero: only noise and bias remain (a few sigma).
    config = mut.ImuConfig()
    sigma = np.hypot(config.linear_acceleration_noise, config.linear_acceleration_bias)
    assert np.all(np.abs(samples[0][mut.LINEAR_ACCELERATION]) < 5 * sigma)


def test_delta_velocity_integrates_at_every_step():
    """Falling for 1 s, the integral of the specific force stays zero (no gravity in it), and
    held still it grows by g per second."""
    diagram, plant, body = _free_box(_noise_free())
    simulator = Simulator(diagram)
    simulator.AdvanceTo(1.0)
    dv = diagram.GetOutputPort("delta_velocity").Eval(simulator.get_context())
    np.testing.assert_allclose(dv, 0, atol=1e-9)
    assert plant.EvalBodyPoseInWorld(
        plant.GetMyContextFromRoot(simulator.get_context()), body
    ).translation()[2] == pytest.approx(-0.5 * 9.81, rel=0.01)
