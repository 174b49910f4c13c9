import numpy as np
import pytest
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import Simulator

import diagrams.navigation as mut
from drake_sim.worlds.arena import load_arena
from tests import navigation_helpers as nh

OUTPUTS = (
    "true_pose",
    "odometry_pose",
    "estimated_pose",
    "covariance",
    "particles",
    "scan",
    "cmd_vel",
    "navigation_status",
)


def _drive_east(scenario, occupancy_map, **kwargs):
    """The room's diagram (on ``occupancy_map``, None: no map) simulated 3 s towards a goal
    east of the start; returns (diagram, context, truth, estimate, meshcat)."""
    arena = load_arena(nh.arena_file("room"))
    start = np.array(arena.start_pose())
    meshcat = Meshcat()
    dut = mut.make_navigation_diagram(
        scenario, nh.robot(), arena, occupancy_map, start=start,
        goals=[nh.pose_deg(-1.0, -1.8, 0.0)], meshcat=meshcat, **kwargs,
    )  # fmt: skip
    assert all(dut.HasOutputPort(name) for name in OUTPUTS)
    simulator = Simulator(dut)
    simulator.AdvanceTo(3.0)
    context = simulator.get_context()
    truth = dut.GetOutputPort("true_pose").Eval(context)
    estimate = dut.GetOutputPort("estimated_pose").Eval(context)
    assert truth[0] - start[0] > 0.3  # on its way east to the goal
    status = dut.GetOutputPort("navigation_status").Eval(context)
    assert status.state in ("following", "rotating_to_goal", "planning", "arrived")
    dut.ForcedPublish(context)
    return dut, context, truth, estimate, meshcat


def test_the_robot_is_localised_and_driven_to_a_goal(tmp_path):
    occupancy_map, _ = nh.saved_truth_map("room", tmp_path)
    start = np.array(load_arena(nh.arena_file("room")).start_pose())
    dut, context, truth, estimate, meshcat = _drive_east(
        nh.scenario(), occupancy_map, initial_estimate=start
    )
    assert estimate[:2] == pytest.approx(truth[:2], abs=0.05)
    assert dut.GetOutputPort("covariance").Eval(context).shape == (9,)
    assert len(dut.GetOutputPort("particles").Eval(context)) >= 100
    for path in ("/navigation/map", "/navigation/particles", "/navigation/costmap"):
        assert meshcat.HasPath(path), path


def test_unknown_map_covers_the_points_and_a_margin():
    dut = mut.unknown_map([[0.0, 0.0], [3.0, -1.0]], 0.1, margin=2.0)
    assert dut.origin == pytest.approx((-2.0, -3.0, 0.0))
    assert dut.shape == (50, 70)  # rows along y: 5 m; columns along x: 7 m
    assert np.all(dut.cells == -1)


@pytest.mark.parametrize("localization", ["slam", "odometry"])
def test_with_no_map_the_robot_drives_on_what_it_sees(localization):
    """No saved map: no AMCL; the SLAM's (or the odometry's) pose drives the navigator on a
    map of unknown cells its obstacle layer fills."""
    scenario = nh.scenario()
    scenario.no_map_localization = localization
    dut, context, truth, estimate, meshcat = _drive_east(scenario, None)
    assert dut.HasSubsystemNamed("slam") == (localization == "slam")
    assert not dut.HasSubsystemNamed("amcl")
    assert estimate[:2] == pytest.approx(truth[:2], abs=0.02)
    assert len(dut.GetOutputPort("particles").Eval(context)) == 0
    assert meshcat.HasPath("/navigation/costmap")


def test_with_no_map_the_slams_map_holds_the_navigators_map():
    """A start in the corner of a large place (``map_extent``, as the explorer gives it): the
    SLAM's square reaches its far walls, not only ``map_size`` / 2 round the start."""
    arena = load_arena(nh.arena_file("room"))
    scenario = nh.scenario()
    scenario.no_map_localization = "slam"
    scenario.slam.map_size = 8.0
    start = np.array(arena.start_pose())
    dut = mut.make_navigation_diagram(
        scenario, nh.robot(), arena, None, start=start, map_extent=[[9.0, 7.0], [-3.0, -3.0]],
        map_margin=1.0,
    )  # fmt: skip
    slam_system = dut.GetSubsystemByName("slam")
    context = slam_system.GetMyContextFromRoot(dut.CreateDefaultContext())
    grid = slam_system.slam(context).grids[0]
    low = np.array(grid.origin[:2])
    high = low + np.array(grid.log_odds.shape[::-1]) * grid.resolution
    assert np.all(low <= [-4.0, -4.0]) and np.all(high >= [9.8, 7.8]), (low, high)
