"""The complementary filter for pitch (drake_sim.systems.estimation.pitch_estimator)."""

import math

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

import drake_sim.systems.estimation.pitch_estimator as mut
from drake_sim.systems.sensors.imu import IMU_SIZE

G = 9.81
RADIUS = 0.05


def _imu(theta=0.0, rate=0.0, acceleration=0.0):
    """An IMU reading on the axle of a body pitched ``theta`` (rad), turning at ``rate``
    (rad/s) while the axle accelerates at ``acceleration`` (m/s^2) along the ground."""
    c, s = math.cos(theta), math.sin(theta)
    f = [c * acceleration - s * G, 0.0, s * acceleration + c * G]
    return np.r_[1.0, 0, 0, 0, 0, rate, 0, f]


def _estimate_after(seconds, imu, config=None):
    dut = mut.PitchEstimator(wheel_radius=RADIUS, config=config or mut.PitchEstimatorConfig())
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    dut.GetInputPort("imu").FixValue(context, imu)
    dut.GetInputPort("wheel_state").FixValue(context, np.zeros(4))
    simulator.AdvanceTo(seconds)
    return dut.GetOutputPort("pitch").Eval(context)


@pytest.mark.parametrize("degrees", [-20.0, -3.0, 0.0, 2.0, 30.0])
def test_reads_a_still_lean_at_once(degrees):
    """A robot held still: the first samples are averaged, so the lean is known within the
    first update, without waiting for the filter's time constant."""
    theta = math.radians(degrees)
    theta_hat, rate = _estimate_after(0.0, _imu(theta))
    assert theta_hat == pytest.approx(theta, abs=1e-9)
    assert rate == 0.0
    assert _estimate_after(1.0, _imu(theta))[0] == pytest.approx(theta, abs=1e-9)


def _run_diagram(imu_source, wheel_source, seconds, config=None):
    builder = DiagramBuilder()
    dut = builder.AddSystem(
        mut.PitchEstimator(wheel_radius=RADIUS, config=config or mut.PitchEstimatorConfig())
    )
    builder.Connect(imu_source(builder), dut.GetInputPort("imu"))
    builder.Connect(wheel_source(builder), dut.GetInputPort("wheel_state"))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(seconds)
    return dut.GetOutputPort("pitch").Eval(dut.GetMyContextFromRoot(simulator.get_context()))


def _constant(value):
    return lambda builder: builder.AddSystem(
        ConstantVectorSource(np.asarray(value))
    ).get_output_port()


def test_accelerating_robot_is_not_read_as_a_lean():
    """Upright, the axle accelerating at 2 m/s^2: its wheels speed up at 2 / r rad/s^2. The
    accelerometer alone reads a lean of atan(-2 / g) (11 degrees); the compensated filter
    stays upright."""
    a, seconds = 2.0, 2.0
    imu = _constant(_imu(0.0, 0.0, a))
    rate = a / RADIUS * seconds
    ramp = PiecewisePolynomial.FirstOrderHold(
        [0.0, seconds], np.array([[0, 0, 0, 0], [0, 0, rate, rate]]).T
    )

    def wheels(builder):
        return builder.AddSystem(TrajectorySource(ramp)).get_output_port()

    compensated = _run_diagram(imu, wheels, seconds)[0]
    assert abs(compensated) < 1e-3  # What is left of the first sample (taken at rest).
    plain = _run_diagram(
        imu, wheels, seconds, mut.PitchEstimatorConfig(compensate_acceleration=False)
    )
    assert plain[0] == pytest.approx(-math.atan2(a, G), abs=1e-3)


def test_gyro_carries_fast_changes_and_its_bias_stays_small():
    """A gyro bias b with the body still: the estimate settles at about b * time_constant,
    not at the bias integrated over time."""
    bias, config = 0.01, mut.PitchEstimatorConfig(time_constant=0.5)
    theta_hat, rate = _estimate_after(5.0, _imu(0.0, bias), config=config)
    assert rate == bias
    assert theta_hat == pytest.approx(bias * config.time_constant, rel=0.05)


def test_accelerometer_ignored_in_free_fall():
    """A reading far from 1 g (the robot in the air) leaves the gyro alone: the estimate does
    not jump to the nonsense angle of a near-zero specific force."""
    falling = np.r_[1.0, 0, 0, 0, 0, 0, 0, 0.3, 0.0, 0.1]
    assert _estimate_after(0.5, falling)[0] == 0.0
    assert len(falling) == IMU_SIZE
