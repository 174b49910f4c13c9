"""The odometry display (drake_sim.systems.viewer.trails)."""

import numpy as np
from pydrake.geometry import StartMeshcat
from pydrake.systems.analysis import Simulator

import drake_sim.systems.viewer.trails as mut


def test_trails_are_drawn_and_bounded():
    meshcat = StartMeshcat()
    dut = mut.TrailVisualizer(meshcat=meshcat, period=0.1, max_points=5)
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    dut.GetInputPort("odometry_pose").FixValue(context, [1.0, 2.0, 0.5])
    dut.GetInputPort("true_pose").FixValue(context, [1.1, 2.0, 0.5])
    simulator.AdvanceTo(2.0)
    trails = context.get_abstract_state(0).get_value()
    assert trails.shape == (5, 6)  # The last max_points samples only.
    np.testing.assert_allclose(trails[-1], [1.0, 2.0, 0.5, 1.1, 2.0, 0.5])
    for path in ("/odometry/estimate_trail", "/odometry/truth_trail", "/odometry/arrow/shaft"):
        assert meshcat.HasPath(path)
