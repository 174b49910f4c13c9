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


def test_the_robot_is_localised_and_driven_to_a_goal(tmp_path):
    occupancy_map, _ = nh.saved_truth_map("room", tmp_path)
    arena = load_arena(nh.arena_file("room"))
    start = np.array(arena.start_pose())
    meshcat = Meshcat()
    dut = mut.make_navigation_diagram(
        nh.scenario(),
        nh.robot(),
        arena,
        occupancy_map,
        start=start,
        initial_estimate=start,
        goals=[nh.pose_deg(-1.0, -1.8, 0.0)],
        meshcat=meshcat,
    )
    assert all(dut.HasOutputPort(name) for name in OUTPUTS)
    simulator = Simulator(dut)
    simulator.AdvanceTo(3.0)
    context = simulator.get_context()
    truth = dut.GetOutputPort("true_pose").Eval(context)
    estimate = dut.GetOutputPort("estimated_pose").Eval(context)
    assert truth[0] - start[0] > 0.3  # on its way east to the goal
    assert estimate[:2] == pytest.approx(truth[:2], abs=0.05)
    assert dut.GetOutputPort("covariance").Eval(context).shape == (9,)
    assert len(dut.GetOutputPort("particles").Eval(context)) >= 100
    status = dut.GetOutputPort("navigation_status").Eval(context)
    assert status.state in ("following", "rotating_to_goal", "planning", "arrived")
    dut.ForcedPublish(context)
    for path in ("/navigation/map", "/navigation/particles", "/navigation/costmap"):
        assert meshcat.HasPath(path), path
