"""The balance controllers and their gains (drake_sim.systems.control.balance_controller)."""

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.systems.analysis import DiscreteTimeApproximation, Simulator
from pydrake.systems.primitives import LinearSystem

import drake_sim.systems.control.balance_controller as mut
from drake_sim.robots.walle import default_robot_file, linearize_upright
from drake_sim.robots.walle_params import load_walle_params

SCALES = [(1.0, 1.0), (0.8, 0.7), (0.8, 1.5), (1.25, 0.7), (1.25, 1.5)]


@pytest.fixture(scope="module")
def robot():
    return load_walle_params(default_robot_file())


def _outputs(robot, config, *, pitch=(0.0, 0.0), wheels=(0, 0, 0, 0), command=(0, 0), t=0.0):
    dut = mut.BalanceController(robot=robot, config=config)
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    dut.GetInputPort("command").FixValue(context, np.asarray(command, float))
    dut.GetInputPort("pitch").FixValue(context, np.asarray(pitch, float))
    dut.GetInputPort("wheel_state").FixValue(context, np.asarray(wheels, float))
    simulator.AdvanceTo(t)
    torques = dut.GetOutputPort("wheel_torques").Eval(context)
    status = dict(zip(mut.STATUS_FIELDS, dut.GetOutputPort("status").Eval(context), strict=True))
    return torques, status


@pytest.mark.parametrize("controller", mut.CONTROLLERS)
def test_drives_under_a_lean_within_the_limits(robot, controller):
    """Leaning forward, both wheels drive forward to get back under the body; leaning back,
    backward; never beyond what the tyres can push (``max_traction``) nor the motors."""
    config = mut.BalanceConfig(controller=controller)
    limit = mut.max_total_torque(robot, config.max_traction) / 2
    forward, _ = _outputs(robot, config, pitch=(math.radians(2), 0.0))
    assert forward[0] == forward[1] > 0
    back, _ = _outputs(robot, config, pitch=(math.radians(-2), -0.5))
    assert back[0] == back[1] < 0
    far, _ = _outputs(robot, config, pitch=(math.radians(30), 3.0))
    np.testing.assert_allclose(far, [limit, limit])
    assert limit <= robot.motor.max_torque


def test_turns_with_opposite_torques(robot):
    torques, status = _outputs(robot, mut.BalanceConfig(), command=(0.0, 1.0), t=0.1)
    assert torques[1] > 0 > torques[0]
    assert torques[1] == pytest.approx(-torques[0])
    assert status["yaw_ref"] > 0


def test_falls_for_good(robot):
    """Past the fallen pitch the motors go off and stay off, even back upright."""
    config = mut.BalanceConfig()
    dut = mut.BalanceController(robot=robot, config=config)
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    dut.GetInputPort("command").FixValue(context, [0.0, 0.0])
    dut.GetInputPort("wheel_state").FixValue(context, np.zeros(4))
    pitch = dut.GetInputPort("pitch").FixValue(context, [math.radians(50), 0.0])
    simulator.AdvanceTo(0.02)
    pitch.GetMutableData().set_value([math.radians(1), 0.0])
    simulator.AdvanceTo(0.1)
    np.testing.assert_array_equal(dut.GetOutputPort("wheel_torques").Eval(context), [0, 0])
    assert dut.GetOutputPort("status").Eval(context)[0] == 1.0


def test_nan_command_stops_and_limits_clip(robot):
    config = mut.BalanceConfig()
    stopped, status = _outputs(robot, config, command=(math.nan, 1.0), t=0.5)
    still, _ = _outputs(robot, config, t=0.5)
    np.testing.assert_array_equal(stopped, still)
    assert status["s_ref"] == 0.0
    _, fast = _outputs(robot, config, command=(10.0, 0.0), t=2.0)
    # Ramped at max_linear_acceleration to max_linear_velocity, held max_position_error ahead.
    assert fast["s_ref"] == pytest.approx(config.max_position_error, abs=1e-9)


def test_unknown_controller(robot):
    with pytest.raises(ValueError, match="unknown controller"):
        mut.BalanceController(robot=robot, config=mut.BalanceConfig(controller="mpc"))


@pytest.mark.parametrize("length, mass", SCALES)
def test_pid_inner_loop_has_the_asked_poles(robot, length, mass):
    scaled = robot.scaled(length=length, mass=mass)
    config = mut.PidBalanceConfig()
    model, gains = mut.pendulum_model(scaled), mut.pid_gains(scaled, config)
    closed = np.array([[0, 1], [model.a - model.b * gains.kp, -model.b * gains.kd]])
    poles = np.linalg.eigvals(closed)
    w_p = config.pitch_bandwidth * math.sqrt(model.a)
    np.testing.assert_allclose(np.abs(poles), [w_p, w_p])
    assert -poles[0].real / w_p == pytest.approx(config.pitch_damping)
    # The outer loop stays below the non-minimum-phase zero.
    assert math.sqrt(gains.position) < math.sqrt(model.g_eff / model.c)


def test_pendulum_model(robot):
    model = mut.pendulum_model(robot)
    A, B = linearize_upright(robot)
    # s_ddot = g_eff theta - c theta_ddot, for any theta and tau.
    for theta, tau in ((0.1, 0.0), (0.0, 0.3), (-0.05, -0.2)):
        x_dot = A @ [0, theta, 0, 0] + B[:, 0] * tau
        assert x_dot[2] == pytest.approx(model.g_eff * theta - model.c * x_dot[3])
        assert x_dot[3] == pytest.approx(model.a * theta - model.b * tau)
    assert 0 < math.sqrt(model.g_eff / model.c) < math.sqrt(model.a)


@pytest.mark.parametrize("integral", [0.0, 0.5])
@pytest.mark.parametrize("length, mass", SCALES)
def test_lqr_stabilises_the_model(robot, length, mass, integral):
    scaled = robot.scaled(length=length, mass=mass)
    period = 1.0 / mut.BalanceConfig().rate
    config = mut.LqrBalanceConfig(integral_tolerance=integral)
    K = mut.lqr_gain(scaled, config, period, traction=0.7)
    A, B = linearize_upright(scaled)
    discrete = DiscreteTimeApproximation(
        LinearSystem(A, B, np.zeros((0, 4)), np.zeros((0, 1))), period
    )
    Ad, Bd = discrete.A(), discrete.B()
    if integral:
        Ad = np.block([[Ad, np.zeros((4, 1))], [period * np.eye(1, 4), np.eye(1)]])
        Bd = np.vstack([Bd, [[0.0]]])
    assert K.shape == (1, 5 if integral else 4)
    assert max(abs(np.linalg.eigvals(Ad - Bd @ K))) < 1.0
    assert K[0, 1] < 0  # A forward lean drives the wheels forward (tau = -K x).


def test_gains_follow_the_robot(robot):
    """Scaling every mass scales the usable torque (traction) and so every gain alike: the
    closed loop is the same. A bigger robot falls slower and gets gentler pitch gains."""
    config, period = mut.LqrBalanceConfig(), 0.005
    K = mut.lqr_gain(robot, config, period, traction=0.7)
    heavy = mut.lqr_gain(robot.scaled(mass=1.5), config, period, traction=0.7)
    np.testing.assert_allclose(heavy, 1.5 * K, rtol=1e-6)
    assert mut.pendulum_model(robot.scaled(length=1.25)).a < mut.pendulum_model(robot).a


def test_torque_and_inertia_helpers(robot):
    grip = 0.7 * robot.total_mass * 9.81 * robot.wheel.radius
    assert mut.max_total_torque(robot, 0.7) == pytest.approx(min(grip, 2 * robot.motor.max_torque))
    weak = dc.replace(robot, motor=dc.replace(robot.motor, max_torque=0.05))
    assert mut.max_total_torque(weak, 0.7) == pytest.approx(0.1)
    inertia = mut.yaw_inertia(robot)
    b = robot.body
    assert inertia > b.mass * (b.length**2 + b.width**2) / 12  # The wheels add to the body's.
    assert mut.yaw_inertia(robot.scaled(length=1.25)) == pytest.approx(1.25**2 * inertia)
