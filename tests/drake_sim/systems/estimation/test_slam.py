import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder, LeafSystem

import drake_sim.systems.estimation.slam as mut
from drake_sim.base import planar
from drake_sim.base.resources import config_dir
from drake_sim.systems.estimation.slam_config import SlamConfig
from drake_sim.systems.sensors.lidar import LaserScan
from drake_sim.worlds.arena import arena_footprints, load_arena
from drake_sim.worlds.footprints import cast_rays

RATE = 5.0
SENSOR = (0.1, 0.0, 0.0)  # X_base_sensor
ANGLES = -np.pi + 2 * np.pi * np.arange(360) / 360


def true_pose(t: float) -> np.ndarray:
    """Drives 0.2 m/s along x from (-2, -1.5), turning slowly left."""
    return np.array([-2.0 + 0.2 * t, -1.5 + 0.004 * t**2, 0.02 * t])


def odometry_pose(t: float) -> np.ndarray:
    """The truth with a 5 % scale error and a yaw drift: 0.1 m off after 10 s."""
    x, y, yaw = true_pose(t)
    return np.array([-2.0 + 1.05 * (x + 2.0), -1.5 + 1.05 * (y + 1.5), yaw + 0.01 * t])


class ScriptedSensors(LeafSystem):
    """Exact scans of the room at ``true_pose`` every 1/RATE s, and the drifting odometry."""

    def __init__(self, footprints):
        super().__init__()
        self._footprints = footprints
        self._scan = self.DeclareAbstractState(AbstractValue.Make(mut.NO_SCAN))
        self.DeclarePeriodicUnrestrictedUpdateEvent(1.0 / RATE, 0.0, self._take)
        self.DeclareStateOutputPort("scan", self._scan)
        self.DeclareVectorOutputPort(
            "odometry", 3, lambda c, out: out.SetFromVector(odometry_pose(c.get_time()))
        )

    def _take(self, context, state):
        t = context.get_time()
        x, y, yaw = planar.compose(true_pose(t), SENSOR)
        ranges = cast_rays(self._footprints, np.array([[x, y]]), ANGLES + yaw, 3.5)[0]
        scan = LaserScan(
            time=t,
            angle_min=ANGLES[0],
            angle_increment=ANGLES[1] - ANGLES[0],
            range_min=0.12,
            range_max=3.5,
            ranges=ranges,
        )
        state.get_mutable_abstract_state(self._scan).set_value(scan)


@pytest.fixture(scope="module")
def finished():
    return run_system(SlamConfig())


def run_system(config: SlamConfig):
    """The SLAM system on the scripted drive for 10.1 s: (system, its context)."""
    arena = load_arena(config_dir() / "arenas" / "room.yaml")
    builder = DiagramBuilder()
    sensors = builder.AddSystem(ScriptedSensors(arena_footprints(arena, height=0.17)))
    dut = builder.AddSystem(
        mut.SlamSystem(
            config=config,
            period=1.0 / RATE,
            initial_pose=true_pose(0.0),
            X_base_sensor=SENSOR,
        )
    )
    builder.Connect(sensors.GetOutputPort("scan"), dut.GetInputPort("scan"))
    builder.Connect(sensors.GetOutputPort("odometry"), dut.GetInputPort("odometry"))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(10.1)
    return dut, dut.GetMyContextFromRoot(simulator.get_context())


def test_every_scan_is_matched_once_at_its_own_time(finished):
    dut, context = finished
    history = dut.history(context)
    assert history.shape == (51, 7)  # scans at 0, 0.2, ..., 10 s
    assert history[:, 0] == pytest.approx(np.arange(51) / RATE)
    # Each row's odometry is read SCAN_DELAY after the scan (a held, discrete odometry has
    # then its value of the scan's instant).
    for row in history[::10]:
        assert row[4:] == pytest.approx(odometry_pose(row[0] + mut.SCAN_DELAY))


def test_the_slam_corrects_the_odometry_drift(finished):
    dut, context = finished
    history = dut.history(context)
    truth = np.array([true_pose(t) for t in history[:, 0]])
    slam_error = np.hypot(*(history[:, 1:3] - truth[:, :2]).T)
    odometry_error = np.hypot(*(history[:, 4:6] - truth[:, :2]).T)
    assert odometry_error[-1] > 0.1
    assert slam_error.max() < 0.03
    assert dut.GetOutputPort("scan_pose").Eval(context) == pytest.approx(history[-1, 1:4])


def test_the_pose_output_moves_on_with_the_odometry_between_scans(finished):
    dut, context = finished
    t = context.get_time()  # 10.1: 0.1 s after the last scan
    expected = planar.compose(
        dut.history(context)[-1, 1:4],
        planar.relative_pose(odometry_pose(10.0 + mut.SCAN_DELAY), odometry_pose(t)),
    )
    assert dut.GetOutputPort("pose").Eval(context) == pytest.approx(expected)


def test_the_map_output_holds_the_walls(finished):
    dut, context = finished
    occupancy_map = dut.GetOutputPort("map").Eval(context)
    assert occupancy_map.resolution == pytest.approx(0.05)
    xs, ys = occupancy_map.centres()
    occupied = occupancy_map.occupied()
    # The south wall's inner face is at y = -2.5: mapped there, within a cell.
    south = occupied & (ys < -2.3) & (np.abs(xs) < 2.5)  # not the side walls
    assert south.sum() > 40
    assert np.abs(ys[south] + 2.5).max() < 0.1
    assert dut.slam(context).scans == 51


def test_with_loop_closure_on_the_system_runs_the_pose_graph():
    """``slam.loop_closure.enabled``: the same system keeps a ``GraphSlam`` (copied with Drake's
    state at every scan) and tracks as well; 2 m of drive closes no loop."""
    import dataclasses as dc

    from drake_sim.systems.estimation.graph_slam import GraphSlam

    config = SlamConfig()
    config = dc.replace(config, loop_closure=dc.replace(config.loop_closure, enabled=True))
    dut, context = run_system(config)
    slam = dut.slam(context)
    assert isinstance(slam, GraphSlam) and slam.scans == 51 and slam.loop_closures == 0
    assert len(slam.graph) == slam.map_updates >= 5
    history = dut.history(context)
    truth = np.array([true_pose(t) for t in history[:, 0]])
    assert np.hypot(*(history[:, 1:3] - truth[:, :2]).T).max() < 0.03
    assert dut.GetOutputPort("map").Eval(context).occupied().sum() > 100


def test_a_cloned_context_shares_the_slam_and_an_update_never_changes_it():
    """Drake clones the state (three times a scan): the clones share the SLAM, and a scan
    processed in one context makes a new SLAM, leaving the other context's as it was."""
    arena = load_arena(config_dir() / "arenas" / "room.yaml")
    builder = DiagramBuilder()
    sensors = builder.AddSystem(ScriptedSensors(arena_footprints(arena, height=0.17)))
    dut = builder.AddSystem(
        mut.SlamSystem(
            config=SlamConfig(), period=1.0 / RATE, initial_pose=true_pose(0.0),
            X_base_sensor=SENSOR,
        )
    )  # fmt: skip
    builder.Connect(sensors.GetOutputPort("scan"), dut.GetInputPort("scan"))
    builder.Connect(sensors.GetOutputPort("odometry"), dut.GetInputPort("odometry"))
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(1.1)
    before = simulator.get_context().Clone()
    slam = dut.slam(dut.GetMyContextFromRoot(before))
    assert slam is dut.slam(dut.GetMyContextFromRoot(simulator.get_context()))
    scans, grid = slam.scans, slam.grids[slam.map_level].log_odds.copy()
    simulator.AdvanceTo(3.1)
    after = dut.slam(dut.GetMyContextFromRoot(simulator.get_context()))
    assert after is not slam and after.scans == scans + 10
    assert slam.scans == scans and np.array_equal(slam.grids[slam.map_level].log_odds, grid)
