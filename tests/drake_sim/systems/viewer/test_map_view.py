import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.geometry import Meshcat
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantValueSource, ConstantVectorSource

import drake_sim.systems.viewer.map_view as mut
from drake_sim.base.map_files import OccupancyMap
from drake_sim.systems.sensors.lidar import LaserScan


def _map():
    cells = np.full((4, 5), -1, dtype=np.int8)
    cells[1, 1:4] = 0
    cells[2, 2] = 100
    return OccupancyMap(cells=cells, resolution=0.1, origin=(1.0, 2.0, 0.0))


def test_map_mesh_has_one_square_per_known_cell_coloured_by_occupancy():
    vertices, faces, colors = mut.map_mesh(_map(), height=0.01)
    assert vertices.shape == (3, 16) and faces.shape == (3, 8) and colors.shape == (3, 16)
    assert faces.dtype == np.int32 and faces.min() == 0 and faces.max() == 15
    dark = colors[0] < 0.5
    assert dark.sum() == 4  # the occupied cell's four corners
    # The occupied cell [2, 2]: centre (1.25, 2.25), 0.1 m square.
    assert vertices[0, dark].min() == pytest.approx(1.2) and vertices[
        0, dark
    ].max() == pytest.approx(1.3)
    assert vertices[1, dark].min() == pytest.approx(2.2) and vertices[
        1, dark
    ].max() == pytest.approx(2.3)
    assert vertices[2] == pytest.approx(0.01)
    # Every triangle has its three corners in one cell, and covers half of it.
    corners = vertices[:2, faces]  # (2, 3, 8)
    area = 0.5 * np.abs(
        (corners[0, 1] - corners[0, 0]) * (corners[1, 2] - corners[1, 0])
        - (corners[0, 2] - corners[0, 0]) * (corners[1, 1] - corners[1, 0])
    )
    assert area == pytest.approx(0.005)


def test_keyframes_show_each_drawing_from_its_time_on():
    meshcat = Meshcat()
    dut = mut.MapView(meshcat=meshcat, map_period=1.0, scan_period=0.2, keyframes=True)
    dut._put("map", mut.map_mesh(_map()), None, None, 0.0)
    dut._put("map", mut.map_mesh(_map()), None, None, 1.0)
    assert meshcat.HasPath("/mapping/map/0") and meshcat.HasPath("/mapping/map/1")


def test_publishing_draws_the_map_the_scan_and_the_pose():
    meshcat = Meshcat()
    builder = DiagramBuilder()
    dut = builder.AddSystem(
        mut.MapView(meshcat=meshcat, map_period=1.0, scan_period=0.2, X_base_sensor=(0.1, 0, 0))
    )
    scan = LaserScan(
        time=0.0,
        angle_min=0.0,
        angle_increment=np.pi / 2,
        range_min=0.1,
        range_max=3.0,
        ranges=[1.0, np.inf, 2.0, 1.5],
    )
    sources = (
        ConstantValueSource(AbstractValue.Make(_map())),
        ConstantValueSource(AbstractValue.Make(scan)),
        ConstantVectorSource(np.array([1.0, 2.0, np.pi / 2])),
    )
    for source, port in zip(sources, ("map", "scan", "pose"), strict=True):
        builder.Connect(builder.AddSystem(source).get_output_port(), dut.GetInputPort(port))
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    diagram.ForcedPublish(context)
    for path in ("/mapping/map", "/mapping/scan", "/mapping/estimate"):
        assert meshcat.HasPath(path), path
