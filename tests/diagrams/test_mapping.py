import numpy as np
import pytest
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import Simulator

import diagrams.mapping as mut
from diagrams.mapping_scenario import MappingScenario
from drake_sim.base.resources import config_dir
from drake_sim.robots.turtlebot3 import default_turtlebot3_file
from drake_sim.robots.turtlebot3_params import load_turtlebot3_params
from drake_sim.worlds.arena import load_arena

OUTPUTS = ("true_pose", "odometry_pose", "slam_pose", "scan", "map", "command", "route_done")


@pytest.fixture(scope="module")
def robot():
    return load_turtlebot3_params(default_turtlebot3_file())


@pytest.fixture(scope="module")
def arena():
    return load_arena(config_dir() / "arenas" / "room.yaml")


def test_the_robot_starts_at_the_arena_start_and_drives_the_route(robot, arena):
    dut = mut.make_mapping_diagram(MappingScenario(), robot, arena, [[-1.0, -1.8]])
    assert all(dut.HasOutputPort(name) for name in OUTPUTS)
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    start = np.array(arena.start_pose())
    assert dut.GetOutputPort("true_pose").Eval(context) == pytest.approx(start, abs=1e-6)
    simulator.AdvanceTo(3.01)  # the scan at 3 s is taken
    truth = dut.GetOutputPort("true_pose").Eval(context)
    assert truth[0] - start[0] > 0.4  # driving towards the waypoint at 0.2 m/s
    scan = dut.GetOutputPort("scan").Eval(context)
    assert scan.time == pytest.approx(3.0) and len(scan.ranges) == 360
    assert np.isfinite(scan.ranges).mean() > 0.5  # the near walls and the obstacles
    slam = dut.GetOutputPort("slam_pose").Eval(context)
    assert slam[:2] == pytest.approx(truth[:2], abs=0.03)
    occupancy_map = dut.GetOutputPort("map").Eval(context)
    assert occupancy_map.occupied().sum() > 50


def test_teleop_needs_no_route_and_adds_the_views(robot, arena):
    meshcat = Meshcat()
    dut = mut.make_mapping_diagram(
        MappingScenario(), robot, arena, [], meshcat=meshcat, teleop=True
    )
    assert not dut.HasOutputPort("route_done")
    simulator = Simulator(dut)
    simulator.AdvanceTo(0.5)
    command = dut.GetOutputPort("command").Eval(simulator.get_context())
    assert np.allclose(command, 0.0)  # no key pressed
    dut.ForcedPublish(simulator.get_context())
    for path in ("/mapping/map", "/mapping/scan", "/mapping/estimate", "/drake/visualizer"):
        assert meshcat.HasPath(path), path


def test_the_slams_map_holds_an_arena_entered_at_its_corner(robot, tmp_path):
    """An 18 x 14 m hall started in its corner: the SLAM's square holds all of it (30 m
    centred on the start reached 7 m of the far wall's 9 and lost the hall beyond)."""
    hall = tmp_path / "hall.yaml"
    hall.write_text("size: [18.0, 14.0]\nstart: {x: -8.0, y: -6.0, yaw: 45}\n")
    dut = mut.make_mapping_diagram(MappingScenario(), robot, load_arena(hall), [[-7.0, -5.0]])
    slam_system = dut.GetSubsystemByName("slam")
    context = slam_system.GetMyContextFromRoot(dut.CreateDefaultContext())
    for grid in slam_system.slam(context).grids:
        low = np.array(grid.origin[:2])
        high = low + np.array(grid.log_odds.shape[::-1]) * grid.resolution
        assert np.all(low <= [-9.05, -7.05]) and np.all(high >= [9.05, 7.05]), (low, high)
