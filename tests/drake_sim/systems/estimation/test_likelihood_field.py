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


def block_map() -> OccupancyMap:
    """4 m x 4 m of 0.05 m cells, its corner at (-1, 0.5) and turned 0.3 rad; a solid block
    1 m deep across the middle (map frame y in [2.0, 3.0))."""
    cells = np.zeros((80, 80), dtype=np.int8)
    cells[40:60, 20:60] = 100
    return OccupancyMap(cells, 0.05, (-1.0, 0.5, 0.3))


def in_world(grid: OccupancyMap, local) -> np.ndarray:
    """Points (k, 2) of the map's own frame in the world."""
    c, s = math.cos(grid.origin[2]), math.sin(grid.origin[2])
    return np.asarray(grid.origin[:2]) + np.asarray(local) @ np.array([[c, s], [-s, c]])


def traced_pz(grid, distance, particle, sensor, beam, r, sigma, z_hit, z_rand_term):
    """pz of one hit beam by hand: its end point's distance to the nearest occupied cell's
    face, and its ray traced every 1 mm for the first occupied cell short of the end point."""
    x, y, yaw = particle
    sx = x + math.cos(yaw) * sensor[0] - math.sin(yaw) * sensor[1]
    sy = y + math.sin(yaw) * sensor[0] + math.cos(yaw) * sensor[1]
    s = np.append(np.arange(0.0, r, 0.001), r)
    points = np.stack([sx + s * math.cos(yaw + beam), sy + s * math.sin(yaw + beam)], -1)
    rows, cols = grid.cell_of(points)
    inside = grid.inside(rows, cols)
    end = rows[-1] * grid.shape[1] + cols[-1] if inside[-1] else len(distance) - 1
    blocked = np.zeros(len(s), dtype=bool)
    blocked[inside] = grid.occupied()[rows[inside], cols[inside]]
    short = r - s[np.argmax(blocked[:-1])] if blocked[:-1].any() else 0.0
    e = max(distance[end] - grid.resolution / 2, short)
    return z_hit * math.exp(-(e**2) / (2 * sigma**2)) + z_rand_term


def test_traced_hits_score_the_end_point_and_how_far_short_the_ray_is_stopped():
    grid = block_map()
    distance = mut.distance_table(grid, 2.0)
    rng = np.random.default_rng(5)
    # Particles below the block (map frame y in [0.3, 1.8]), facing it, give or take.
    local = np.column_stack([rng.uniform(1.2, 2.8, 30), rng.uniform(0.3, 1.8, 30)])
    heading = grid.origin[2] + math.pi / 2 + rng.uniform(-0.4, 0.4, 30)
    particles = np.column_stack([in_world(grid, local), heading])
    sensor = np.array([-0.064, 0.02])
    beams = np.array([-0.3, 0.0, 0.1, 0.35])
    ranges = np.array([1.2, 0.9, 2.5, 1.6])  # some short of the block, some behind its face
    sigma, z_hit, z_rand_term = 0.1, 0.5, 0.5 / 3.5
    dut = mut.traced_hit_likelihood(
        particles, sensor, np.cos(beams), np.sin(beams), ranges, distance,
        grid.origin, grid.resolution, grid.shape, sigma, z_hit, z_rand_term,
    )  # fmt: skip
    expected = [
        1.0 + sum(
            traced_pz(grid, distance, p, sensor, b, r, sigma, z_hit, z_rand_term) ** 3
            for b, r in zip(beams, ranges, strict=True)
        )
        for p in particles
    ]  # fmt: skip
    # The entry is found to 1/32 of a cell (1.6 mm): pz^3 moves by < 0.005 per beam.
    np.testing.assert_allclose(dut, expected, atol=4 * 0.005)
    assert np.ptp(dut) > 0.2  # the beams tell the particles apart


def test_an_end_point_behind_a_face_scores_as_one_as_far_in_front():
    """The likelihood field alone scores an end point inside a solid block as a hit and one in
    front of it as a miss, so the particles nearer the block than the truth win: the estimate
    creeps towards what the robot sees. With the ray traced, the score falls off alike on both
    sides of the truth."""
    grid = block_map()
    distance = mut.distance_table(grid, 2.0)
    table, _ = mut.likelihood_table(grid, AmclConfig(laser_sigma_hit=0.1))
    beams = np.linspace(-0.15, 0.15, 7)
    ranges = 1.512 / np.cos(beams)  # the robot 1.512 m below the block's face, square on
    offsets = np.arange(-0.2, 0.2001, 0.005)  # towards the block (+) or away (-)
    local = np.column_stack([np.full(len(offsets), 2.0), 2.0 - 1.512 + offsets])
    poses = np.column_stack([in_world(grid, local), np.full(len(offsets), grid.origin[2] + 1.5708)])
    args = (grid.origin, grid.resolution, grid.shape)
    ux, uy = np.cos(beams), np.sin(beams)
    field_only = mut.scan_likelihood(poses, ranges * ux, ranges * uy, table, *args, 0.5, 0.1)
    traced = mut.traced_hit_likelihood(
        poses, np.zeros(2), ux, uy, ranges, distance, *args, 0.1, 0.5, 0.1
    )

    def centre(score):  # where the weight lies, m towards the block
        w = score - score.min()
        return float(np.sum(w * offsets) / np.sum(w))

    assert centre(field_only) > 0.05  # the creep
    assert abs(centre(traced)) < 0.01
    assert abs(offsets[np.argmax(traced)]) <= 0.025
