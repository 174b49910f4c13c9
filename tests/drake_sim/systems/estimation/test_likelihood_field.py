"""drake_sim.systems.estimation.likelihood_field: the distance field's table (capped, one more
entry for points off the map) and ROS's particle weight 1 + sum(pz^3) from the kernel, against
the same computed by hand, on a rotated map."""

import math

import numpy as np
import pytest

import drake_sim.systems.estimation.likelihood_field as mut
from drake_sim.base.map_files import OccupancyMap
from drake_sim.systems.estimation.amcl_config import AmclConfig

CONFIG = AmclConfig(laser_sigma_hit=0.2, laser_likelihood_max_dist=0.5)


def one_wall_map() -> OccupancyMap:
    """2 m x 1 m of 0.1 m cells, its corner at (1, 2) and turned 90 degrees; one occupied
    column at cells' x index 10 (map frame x in [1.0, 1.1))."""
    cells = np.zeros((10, 20), dtype=np.int8)
    cells[:, 10] = 100
    return OccupancyMap(cells, 0.1, (1.0, 2.0, math.pi / 2))


def test_table_is_the_capped_distance_gaussian_with_the_cap_last():
    grid = one_wall_map()
    table, resolution = mut.likelihood_table(grid, CONFIG)
    assert resolution == 0.1 and table.shape == (10 * 20 + 1,)
    field = table[:-1].reshape(10, 20)
    d = np.minimum(np.abs(np.arange(20) - 10) * 0.1, 0.5)
    np.testing.assert_allclose(field, np.tile(np.exp(-(d**2) / (2 * 0.2**2)), (10, 1)))
    assert table[-1] == pytest.approx(math.exp(-(0.5**2) / (2 * 0.2**2)))  # off the map
    empty = OccupancyMap(np.zeros((3, 3), dtype=np.int8), 0.1)
    np.testing.assert_allclose(mut.likelihood_table(empty, CONFIG)[0], table[-1])


def test_weight_is_ros_sum_of_cubed_beam_likelihoods():
    grid = one_wall_map()
    table, resolution = mut.likelihood_table(grid, CONFIG)
    particles = np.array([[0.53, 2.47, math.pi / 2], [0.53, 2.47, 0.2], [-3.0, 0.0, 0.3]])
    bx, by = np.array([0.58, 0.33, 1.21]), np.array([0.013, 0.117, -0.31])  # base frame
    z_hit, z_rand_term = 0.95, 0.05 / 3.5
    dut = mut.scan_likelihood(
        particles, bx, by, table, grid.origin, resolution, grid.shape, z_hit, z_rand_term
    )
    expected = []
    for x, y, yaw in particles:
        ends = np.stack(
            [
                x + bx * math.cos(yaw) - by * math.sin(yaw),
                y + bx * math.sin(yaw) + by * math.cos(yaw),
            ],
            -1,
        )
        rows, cols = grid.cell_of(ends)
        index = np.where(grid.inside(rows, cols), rows * 20 + cols, 200)
        pz = z_hit * table[index] + z_rand_term
        expected.append(1.0 + np.sum(pz**3))
    np.testing.assert_allclose(dut, expected, rtol=1e-12)
    assert dut[0] > 1.5 > dut[1]  # facing the wall, one beam ends on it
    assert dut[2] == pytest.approx(1.0 + 3 * (z_hit * table[-1] + z_rand_term) ** 3)  # off map
