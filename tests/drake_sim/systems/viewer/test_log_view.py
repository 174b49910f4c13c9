"""The Meshcat view of a log's SLAM run (drake_sim.systems.viewer.log_view): the map, the scan
at its pose, the arrow and the trail, drawn by the log's clock; the final map and trajectory."""

import numpy as np
from pydrake.geometry import Meshcat

import drake_sim.systems.viewer.log_view as mut
from drake_sim.base.map_files import OccupancyMap


class FakeSlam:
    """What the view reads of a SLAM: its pose, sensor pose and map."""

    def __init__(self):
        self.pose = np.array([1.0, 2.0, 0.5])
        self.X_base_sensor = np.zeros(3)
        self.maps = 0

    def map(self):
        self.maps += 1
        cells = np.zeros((10, 10), np.int8)
        cells[0] = 100
        return OccupancyMap(cells, 0.05)


def test_the_log_s_clock_sets_what_is_drawn():
    meshcat = Meshcat()
    view = mut.LogView(meshcat, map_period=10.0, scan_period=0.5)
    slam = FakeSlam()
    angles = np.linspace(-1.5, 1.5, 31)
    ranges = np.full(31, 2.0)
    ranges[3] = np.inf  # no return: not drawn
    for k in range(101):  # 20 s of a 5 Hz log
        view.update(slam, 100.0 + 0.2 * k, ranges, angles, 0.1, 30.0)
    assert slam.maps == 3  # at 0, 10 and 20 s
    for path in ("map", "scan", "trail", "estimate/shaft"):
        assert meshcat.HasPath(f"{mut.ROOT}/{path}"), path


def test_finish_draws_the_final_map_and_trajectory_and_clears_the_scan():
    meshcat = Meshcat()
    view = mut.LogView(meshcat)
    slam = FakeSlam()
    view.update(slam, 0.0, np.full(5, 1.0), np.linspace(-1, 1, 5), 0.1, 30.0)
    view.finish(slam, np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 1.0, 0.3]]))
    assert slam.maps == 2 and meshcat.HasPath(f"{mut.ROOT}/trail")
    assert not meshcat.HasPath(f"{mut.ROOT}/scan")
