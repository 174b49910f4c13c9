"""Flip-aware odometry and its ground truth (drake_sim.systems.estimation.odometry)."""

import math

import numpy as np
import pytest
from pydrake.math import RollPitchYaw, RotationMatrix

import drake_sim.systems.estimation.odometry as mut
from tests.flip_helpers import default_robot, run_for

G_UP = np.array([0.0, 0.0, 9.81])


class _SyntheticSensors:
    """Drives a lone WheelOdometry with hand-made encoder and IMU signals, one update at a
    time (the odometry runs at 100 Hz)."""

    def __init__(self, config=None):
        self.robot = default_robot()
        self.dut = mut.WheelOdometry(robot=self.robot, config=config or mut.OdometryConfig())
        self.context = self.dut.CreateDefaultContext()
        self.dt = 0.01
        self.delta_v = np.zeros(3)
        self.delta_angle = np.zeros(3)
        self.R_WB = RotationMatrix()
        self._set(q=(0.0, 0.0))
        self.dut.ExecuteInitializationEvents(self.context)

    def _set(self, *, q):
        imu = np.r_[self.R_WB.ToQuaternion().wxyz(), np.zeros(3), self.R_WB.inverse() @ G_UP]
        self.dut.GetInputPort("wheel_state").FixValue(self.context, np.r_[q, 0.0, 0.0])
        self.dut.GetInputPort("imu").FixValue(self.context, imu)
        self.dut.GetInputPort("delta_velocity").FixValue(self.context, self.delta_v)
        self.dut.GetInputPort("delta_angle").FixValue(self.context, self.delta_angle)

    def step(self, *, q, pitch=0.0, a_W=(0.0, 0.0, 0.0)):
        """One update: the wheel joints are at ``q``, the body pitched by ``pitch`` about its
        y axis, and the axle accelerated at ``a_W`` (world) since the last update."""
        R_new = RotationMatrix(RollPitchYaw(0, pitch, 0))
        self.delta_angle = self.delta_angle + np.array([0.0, 1.0, 0.0]) * self._turn(R_new)
        self.delta_v = self.delta_v + R_new.inverse() @ (np.asarray(a_W) + G_UP) * self.dt
        self.R_WB = R_new
        self._set(q=q)
        self.context.SetTime(self.context.get_time() + self.dt)
        update = self.dut.EvalUniquePeriodicDiscreteUpdate(self.context)
        self.context.SetDiscreteState(0, update.get_vector(0).value())

    def _turn(self, R_new):
        """The rotation angle about y from the current orientation to R_new (small)."""
        R_rel = self.R_WB.inverse().multiply(R_new).matrix()
        return math.atan2(R_rel[0, 2], R_rel[0, 0])

    def output(self, name):
        return self.dut.GetOutputPort(name).Eval(self.context)


def test_straight_roll_and_growing_covariance():
    sensors = _SyntheticSensors()
    r = sensors.robot.wheel.radius
    traces = []
    for k in range(1, 101):  # 1 s at 1.5 m/s^2 from rest: 0.75 m straight ahead.
        s = 0.75 * (k * sensors.dt) ** 2
        sensors.step(q=(s / r, s / r), a_W=np.array([1.5, 0.0, 0.0]))
        traces.append(np.trace(sensors.output("covariance").reshape(3, 3)))
    np.testing.assert_allclose(sensors.output("pose"), [0.75, 0, 0], atol=1e-9)
    assert sensors.output("distance")[0] == pytest.approx(0.75)
    assert np.all(np.diff(traces) > 0)  # The uncertainty grows with the distance travelled.
    assert sensors.output("slipping")[0] == 0


def test_flip_in_place_is_not_travel():
    """The body turns half a turn over the axle while the wheels stay put on the ground: the
    joints turn by -pi relative to the body. The naive odometry counts r * pi of travel."""
    sensors = _SyntheticSensors()
    r = sensors.robot.wheel.radius
    steps = 60
    for k in range(1, steps + 1):
        pitch = math.pi * k / steps
        sensors.step(q=(-pitch, -pitch), pitch=pitch)
    np.testing.assert_allclose(sensors.output("pose")[:2], [0, 0], atol=1e-9)
    assert sensors.output("naive_pose")[0] == pytest.approx(-math.pi * r)


def test_slipping_wheels_hand_the_distance_to_the_imu():
    """The wheels spin backwards (slipping) while the tyres' friction pushes the axle forward
    at 6 m/s^2, as in a flip: the odometry follows the IMU and flags the slip."""
    sensors = _SyntheticSensors()
    for k in range(1, 21):  # 0.2 s: 0.12 m and 1.2 m/s.
        sensors.step(q=(-0.5 * k, -0.5 * k), a_W=np.array([6.0, 0, 0]))
    assert sensors.output("slipping")[0] == 1
    assert sensors.output("pose")[0] == pytest.approx(0.12, abs=1e-9)
    assert sensors.output("twist")[0] == pytest.approx(1.2, abs=1e-9)
    assert sensors.output("naive_pose")[0] < -0.5


def test_odometry_straight_in_simulation():
    run = run_for(3.0, controller="cmd_vel", cmd_vel=[0.5, 0.0])
    report = run.report()
    assert report.distance_travelled_m > 1.0
    assert report.max_odometry_error_m < 0.01


def test_odometry_across_flips_in_simulation():
    """Across real flips, the naive odometry is off by about r * pi after each flip from
    upright; the flip-aware, slip-aware odometry stays within a few centimetres."""
    run = run_for(8.0)
    report = run.report()
    assert report.flips >= 3
    assert report.max_odometry_error_m < 0.1
    assert report.max_naive_odometry_error_m > 0.5
    assert report.max_naive_odometry_error_m > 8 * report.max_odometry_error_m
    # The odometry's covariance grew with the distance travelled.
    covariance = run.diagram.GetOutputPort("odometry_covariance").Eval(run.context)
    assert np.trace(covariance.reshape(3, 3)) > 1e-4 * report.distance_travelled_m


def test_ground_truth_is_the_axle_midpoint():
    run = run_for(0.01, controller="cmd_vel", cmd_vel=[0.0, 0.0])
    truth = run.diagram.GetOutputPort("true_pose").Eval(run.context)
    odometry = run.diagram.GetOutputPort("odometry_pose").Eval(run.context)
    start = run.diagram.GetSubsystemByName("plant")
    del start
    np.testing.assert_allclose(truth, odometry, atol=1e-3)
