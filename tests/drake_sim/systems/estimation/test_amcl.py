"""drake_sim.systems.estimation.amcl: the Amcl system in a small diagram with scripted scans
of the room and drifting odometry."""

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder, LeafSystem

import drake_sim.systems.estimation.amcl as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.planar import compose, relative_pose, wrap_angle
from drake_sim.systems.estimation.amcl_config import (
    AmclConfig,
    default_amcl_config_file,
    load_amcl_config,
)
from drake_sim.systems.sensors.lidar import LaserScan
from tests.drake_sim.systems.estimation.test_particle_filter import (
    ANGLES,
    RANGE_MAX,
    RANGE_MIN,
    RATE,
    SENSOR,
    scan_at,
    world,
)

START = np.array([-2.2, -1.8, 0.0])  # the room's start
SPEED, OMEGA = 0.2, 0.05  # m/s, rad/s: an arc of radius 4 m between the room's boxes


def true_pose(t: float) -> np.ndarray:
    """The robot drives the arc from START."""
    radius, angle = SPEED / OMEGA, OMEGA * t
    return START + [radius * math.sin(angle), radius * (1 - math.cos(angle)), angle]


def odometry_pose(t: float) -> np.ndarray:
    """Wheel odometry of that drive (from START): 1 % too long and turning 0.005 rad/s too
    fast, so it drives a tighter arc."""
    speed, omega = 1.01 * SPEED, OMEGA + 0.005
    radius, angle = speed / omega, omega * t
    return START + [radius * math.sin(angle), radius * (1 - math.cos(angle)), angle]


class ScriptedSensors(LeafSystem):
    """Noisy scans of the room at ``true_pose`` every 1/RATE s, and the drifting odometry."""

    def __init__(self, footprints, seed=0):
        super().__init__()
        self._footprints = footprints
        self._rng = np.random.default_rng(seed)
        self._scan = self.DeclareAbstractState(AbstractValue.Make(mut.NO_SCAN))
        self.DeclarePeriodicUnrestrictedUpdateEvent(1.0 / RATE, 0.0, self._take)
        self.DeclareStateOutputPort("scan", self._scan)
        self.DeclareVectorOutputPort(
            "odometry", 3, lambda c, out: out.SetFromVector(odometry_pose(c.get_time()))
        )

    def _take(self, context, state):
        t = context.get_time()
        scan = LaserScan(
            time=t,
            angle_min=ANGLES[0],
            angle_increment=ANGLES[1] - ANGLES[0],
            range_min=RANGE_MIN,
            range_max=RANGE_MAX,
            ranges=scan_at(self._footprints, true_pose(t), self._rng),
        )
        state.get_mutable_abstract_state(self._scan).set_value(scan)


def build(seed=0, **kwargs):
    """(simulator, dut, dut's context) with the room's ground-truth map."""
    _, footprints, grid, _ = world("room")
    builder = DiagramBuilder()
    sensors = builder.AddSystem(ScriptedSensors(footprints, seed))
    kwargs.setdefault("initial_pose", START + [0.3, -0.4, math.radians(30)])
    kwargs.setdefault("initial_covariance", np.diag([0.25, 0.25, math.radians(30) ** 2]))
    dut = builder.AddSystem(
        mut.Amcl(map=grid, period=1.0 / RATE, X_base_sensor=SENSOR, seed=seed, **kwargs)
    )
    builder.Connect(sensors.GetOutputPort("scan"), dut.GetInputPort("scan"))
    builder.Connect(sensors.GetOutputPort("odometry"), dut.GetInputPort("odometry"))
    simulator = Simulator(builder.Build())
    return simulator, dut, dut.GetMyContextFromRoot(simulator.get_context())


@pytest.fixture(scope="module")
def finished():
    simulator, dut, context = build()
    simulator.AdvanceTo(12.1)
    return simulator, dut, context


def test_pose_converges_to_the_truth(finished):
    _, dut, context = finished
    history = dut.history(context)
    truth = np.array([true_pose(t) for t in history[:, 0]])
    error = np.hypot(*(history[:, 1:3] - truth[:, :2]).T)
    assert error[0] > 0.2  # it started 0.5 m off
    late = history[:, 0] >= 10.0
    assert late.sum() >= 5 and error[late].max() < 0.05
    assert np.degrees(np.abs(wrap_angle(history[late, 3] - truth[late, 2]))).max() < 3.0
    pose = dut.GetOutputPort("pose").Eval(context)
    assert math.dist(pose[:2], true_pose(context.get_time())[:2]) < 0.05


def test_updates_come_once_per_scan_when_moved_enough_at_the_scans_time(finished):
    _, dut, context = finished
    times = dut.history(context)[:, 0]
    np.testing.assert_allclose(times[:3], [0.0, 0.4, 0.8])  # 0.04 m a scan, update_min_d 0.05
    assert np.all(np.diff(times) > 0) and len(times) == 31


def test_covariance_and_particles_outputs(finished):
    _, dut, context = finished
    covariance = np.asarray(dut.GetOutputPort("covariance").Eval(context)).reshape(3, 3)
    np.testing.assert_allclose(covariance, covariance.T)
    assert 0 < covariance[0, 0] < 0.1**2 and 0 < covariance[2, 2] < math.radians(3) ** 2
    particles = dut.GetOutputPort("particles").Eval(context)
    assert particles.ndim == 2 and particles.shape[1] == 3
    assert len(particles) == len(dut.particle_filter(context).particles) < 8000
    np.testing.assert_allclose(particles[:, :2].mean(0), true_pose(12.0)[:2], atol=0.05)


def test_pose_between_updates_is_the_estimate_moved_on_by_the_odometry():
    simulator, dut, context = build()
    simulator.AdvanceTo(5.1)  # 0.1 s after the update at the scan of 4.8 s... and later
    estimate, _ = dut.particle_filter(context).estimate()
    t_update = dut.history(context)[-1, 0]
    at_update = odometry_pose(t_update + mut.SCAN_DELAY)  # the odometry the scan was read with
    moved = relative_pose(at_update, odometry_pose(context.get_time()))
    expected = compose(estimate, moved)
    np.testing.assert_allclose(dut.GetOutputPort("pose").Eval(context), expected, atol=1e-9)
    assert math.dist(expected[:2], estimate[:2]) > 0.01  # it did move


def test_set_pose_restarts_the_filter_at_the_given_pose(finished):
    simulator, dut, original = finished
    root = simulator.get_context().Clone()
    context = dut.GetMyContextFromRoot(root)
    here = np.array([1.5, 1.8, -2.0])
    dut.set_pose(context, here, np.diag([1e-4, 1e-4, 1e-4]))
    np.testing.assert_allclose(dut.GetOutputPort("pose").Eval(context), here, atol=0.05)
    particles = dut.GetOutputPort("particles").Eval(context)
    assert len(particles) == 8000 and np.abs(particles[:, :2] - here[:2]).max() < 0.1
    covariance = dut.GetOutputPort("covariance").Eval(context)
    assert covariance[0] < 1e-3
    with pytest.raises(ConfigError, match="initial pose"):
        dut.set_pose(context, [math.nan, 0.0, 0.0], np.eye(3))
    # The state is the clone's own: the simulator's context still holds the converged filter.
    assert len(dut.GetOutputPort("particles").Eval(original)) < 8000
    assert math.dist(dut.GetOutputPort("pose").Eval(original)[:2], here[:2]) > 1.0


def test_start_global_localization_then_converges_while_driving():
    simulator, dut, context = build(seed=4)
    dut.start_global_localization(context)
    particles = dut.GetOutputPort("particles").Eval(context)
    assert (
        len(particles) == 8000 and np.ptp(particles[:, 0]) > 5.0 and np.ptp(particles[:, 1]) > 4.0
    )
    covariance = dut.GetOutputPort("covariance").Eval(context)
    assert covariance[0] > 1.0
    assert not dut.localized(context)
    simulator.AdvanceTo(14.1)
    pose = dut.GetOutputPort("pose").Eval(context)
    assert math.dist(pose[:2], true_pose(14.1)[:2]) < 0.05
    assert dut.localized(context)


def test_same_seed_same_estimates():
    runs = []
    for _ in range(2):
        simulator, dut, context = build(seed=7)
        simulator.AdvanceTo(2.1)
        runs.append(dut.history(context))
    np.testing.assert_array_equal(runs[0], runs[1])


def test_global_localization_argument_and_config_defaults():
    _, _, grid, _ = world("room")
    dut = mut.Amcl(map=grid, period=0.2, global_localization=True)
    context = dut.CreateDefaultContext()
    assert len(dut.GetOutputPort("particles").Eval(context)) == 8000
    shipped = load_amcl_config(default_amcl_config_file())
    dut = mut.Amcl(map=grid, period=0.2, config=dc.replace(shipped, initial_pose_x=1.0))
    context = dut.CreateDefaultContext()
    pose = dut.GetOutputPort("pose").Eval(context)  # no odometry yet: the estimate itself
    assert abs(pose[0] - 1.0) < 0.1


def test_bad_arguments_are_config_errors():
    _, _, grid, _ = world("room")
    with pytest.raises(ConfigError, match="'laser_sigma_hit' must be positive"):
        mut.Amcl(map=grid, period=0.2, config=AmclConfig(laser_sigma_hit=0.0))
    with pytest.raises(ConfigError, match="positive semi-definite"):
        mut.Amcl(map=grid, period=0.2, initial_pose=START, initial_covariance=-np.eye(3))
