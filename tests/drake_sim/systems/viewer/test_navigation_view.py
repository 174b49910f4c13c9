import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.geometry import Meshcat
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantValueSource

import drake_sim.systems.viewer.navigation_view as mut
from drake_sim.base.map_files import OccupancyMap


def test_costmap_mesh_colours_the_inflated_cells_only():
    costs = np.zeros((3, 4), dtype=np.uint8)
    costs[0, 0], costs[1, 2], costs[2, 3] = 254, 100, 255  # lethal, inflated, unknown
    vertices, faces, colors = mut.costmap_mesh(costs, 0.1, (1.0, 2.0, 0.0), height=0.01)
    assert vertices.shape == (3, 8) and faces.shape == (3, 4)
    assert vertices[2] == pytest.approx(0.01)
    assert colors[0, :4] == pytest.approx(1.0)  # the lethal cell is red
    assert colors[2, 4:] == pytest.approx(1 - 100 / 254)
    assert vertices[0, :4].min() == pytest.approx(1.0) and vertices[1, :4].max() == pytest.approx(
        2.1
    )


class _Status:
    path = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    local_trajectory = np.array([[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]])
    goal = np.array([1.0, 1.0, 0.5])
    costmap = None


def test_publishing_draws_the_particles_the_paths_and_the_goal():
    meshcat = Meshcat()
    cells = np.zeros((10, 10), dtype=np.int8)
    cells[0] = 100
    builder = DiagramBuilder()
    dut = builder.AddSystem(
        mut.NavigationView(
            meshcat=meshcat, occupancy_map=OccupancyMap(cells=cells, resolution=0.1), period=0.5
        )
    )
    particles = builder.AddSystem(ConstantValueSource(AbstractValue.Make(np.zeros((20, 3)))))
    status = builder.AddSystem(ConstantValueSource(AbstractValue.Make(_Status())))
    builder.Connect(particles.get_output_port(), dut.GetInputPort("particles"))
    builder.Connect(status.get_output_port(), dut.GetInputPort("navigation_status"))
    diagram = builder.Build()
    diagram.ForcedPublish(diagram.CreateDefaultContext())
    for path in (
        "/navigation/map",
        "/navigation/particles",
        "/navigation/path",
        "/navigation/local_trajectory",
        "/navigation/goal",
    ):
        assert meshcat.HasPath(path), path
