"""Global localisation on large maps (issue #39): the beams that saw nothing
(``likelihood_field.no_return_likelihood``, ``laser_no_return_beams``), the density of a global
spread (``global_localization_density``), the heaviest cluster (``pose_histogram``) and
``ParticleFilter.localized``; on the real TurtleBot3 map when ``../shared`` has it.

Scans here are cast on the map's own grid (its occupied cells are the walls, as in the world
``navigate --map M --start ...`` simulates), 1 cm of noise, every 0.2 mm along each beam.
"""

import dataclasses as dc
import math
from pathlib import Path

import numpy as np
import pytest

import drake_sim.systems.estimation.likelihood_field as field
import drake_sim.systems.estimation.particle_filter as mut
import drake_sim.systems.estimation.pose_histogram as histogram
from drake_sim.base.map_files import OccupancyMap, load_map
from drake_sim.base.planar import compose, wrap_angle
from drake_sim.systems.estimation.amcl_config import AmclConfig, load_amcl_config
from tests.drake_sim.systems.estimation.test_particle_filter import (
    ANGLES,
    RANGE_MAX,
    RANGE_MIN,
    SENSOR,
    SHIPPED,
    drive,
)

TB3_MAP = Path(__file__).resolve().parents[4] / "../shared/real_ros/maps/turtlebot3_main/map.yaml"


def room(size_m: float, resolution=0.05, pillars=()) -> OccupancyMap:
    """A square room of ``size_m`` inside one-cell walls, its corner at (0, 0), with square
    pillars (x, y, side m)."""
    n = int(round(size_m / resolution))
    cells = np.zeros((n, n), dtype=np.int8)
    cells[[0, -1], :] = 100
    cells[:, [0, -1]] = 100
    for x, y, side in pillars:
        r0, c0 = int((y - side / 2) / resolution), int((x - side / 2) / resolution)
        k = int(round(side / resolution))
        cells[r0 : r0 + k, c0 : c0 + k] = 100
    return OccupancyMap(cells, resolution)


def grid_scan(grid: OccupancyMap, pose, rng, step=None) -> np.ndarray:
    """360 ranges (m, ``inf`` for none within RANGE_MAX) of the lidar on the base at ``pose``,
    the map's occupied cells being the walls, found every ``step`` m along each beam (default
    1/250 of a cell)."""
    x, y, yaw = compose(pose, SENSOR)
    steps = np.arange(0.0, RANGE_MAX, step or grid.resolution / 250)
    px = x + np.cos(ANGLES + yaw)[:, None] * steps
    py = y + np.sin(ANGLES + yaw)[:, None] * steps
    rows, cols = grid.cell_of(np.stack([px.ravel(), py.ravel()], -1))
    inside = grid.inside(rows, cols)
    hit = np.zeros(rows.shape, dtype=bool)
    hit[inside] = grid.occupied()[rows[inside], cols[inside]]
    hit = hit.reshape(px.shape)
    ranges = np.where(hit.any(1), steps[hit.argmax(1)], np.inf) + rng.normal(0, 0.01, 360)
    return np.where(ranges < RANGE_MAX, ranges, np.inf)


def test_distance_table_is_what_the_likelihood_table_is_made_of():
    grid = room(3.0, pillars=[(1.5, 1.5, 0.5)])
    config = AmclConfig(laser_sigma_hit=0.2, laser_likelihood_max_dist=0.8)
    distance = field.distance_table(grid, 0.8)
    table, _ = field.likelihood_table(grid, config)
    assert distance.shape == (60 * 60 + 1,) and distance[-1] == 0.8 and distance.max() == 0.8
    np.testing.assert_allclose(table, np.exp(-(distance**2) / (2 * 0.2**2)))
    assert distance[:-1][grid.occupied().ravel()].max() == 0.0


def brute_force_pz(grid, particle, beam, range_max, sigma, z_hit, z_rand_term):
    """pz of one ray traced every 1 mm (off the map: free)."""
    x, y, yaw = compose(particle, (SENSOR[0], SENSOR[1], 0.0))
    s = np.arange(0.0, range_max, 0.001)
    points = np.stack([x + s * math.cos(yaw + beam), y + s * math.sin(yaw + beam)], -1)
    rows, cols = grid.cell_of(points)
    inside = grid.inside(rows, cols)
    blocked = np.zeros(len(s), dtype=bool)
    blocked[inside] = grid.occupied()[rows[inside], cols[inside]]
    short = range_max - s[np.argmax(blocked)] if blocked.any() else 0.0
    return z_hit * math.exp(-(short**2) / (2 * sigma**2)) + z_rand_term


def test_no_return_rays_score_by_how_far_the_map_lets_them_run():
    grid = OccupancyMap(room(4.0, pillars=[(2.5, 2.0, 0.4)]).cells, 0.05, (-1.0, 0.5, 0.3))
    distance = field.distance_table(grid, 2.0)
    rng = np.random.default_rng(3)
    particles = np.column_stack(
        [rng.uniform(-0.5, 2.5, 60), rng.uniform(1.0, 4.0, 60), rng.uniform(-3, 3, 60)]
    )
    rows, cols = grid.cell_of(particles[:, :2])
    particles = particles[grid.inside(rows, cols)][:40]  # a ray leaving the map runs free
    beams = np.array([0.0, 1.0, 2.5, -2.0])
    sigma, z_hit, z_rand_term = 0.3, 0.5, 0.5 / 3.5
    dut = field.no_return_likelihood(
        particles,
        np.array(SENSOR[:2]),
        np.cos(beams),
        np.sin(beams),
        distance,
        grid.origin,
        grid.resolution,
        grid.shape,
        2.0,
        sigma,
        z_hit,
        z_rand_term,
    )
    expected = [
        sum(brute_force_pz(grid, p, b, 2.0, sigma, z_hit, z_rand_term) ** 3 for b in beams)
        for p in particles
    ]
    # The tracing may stop up to half a cell early or late: pz^3 moves by < 0.03 per beam.
    np.testing.assert_allclose(dut, expected, atol=4 * 0.03)
    free = 4 * (z_hit + z_rand_term) ** 3
    assert dut.max() <= free + 1e-12 and dut.min() < 0.5 * free


def test_no_return_beams_tell_open_floor_from_floor_near_walls():
    """In a 10 m room the lidar in the middle sees nothing: without the beams that saw nothing
    the scan says nothing; with them, the particles within range of a wall lose their weight."""
    grid = room(10.0)
    rng = np.random.default_rng(0)
    ranges = grid_scan(grid, (5.0, 5.0, 0.3), rng)
    assert not np.isfinite(ranges).any()
    base = dc.replace(load_amcl_config(SHIPPED), scan_match_refinement=False)
    ratios = []
    for no_return in (False, True):
        config = dc.replace(base, laser_no_return_beams=no_return, global_localization_density=0)
        dut = mut.ParticleFilter(grid, config, seed=1)
        dut.global_localization()
        before = dut.weights.copy()
        dut.update(
            (0, 0, 0),
            ranges,
            ANGLES,
            range_max=RANGE_MAX,
            range_min=RANGE_MIN,
            X_base_sensor=SENSOR,
        )
        if not no_return:
            assert np.array_equal(dut.weights, before)  # nothing to weigh them by
        offset = np.abs(dut.particles[:, :2] - 5.0).max(axis=1)
        clear = offset < 5.0 - 0.05 - RANGE_MAX - 0.07  # the 2.8 m square in the middle
        near = offset > 5.0 - 0.05 - 0.5  # within 0.5 m of a wall
        ratios.append(dut.weights[clear].mean() / dut.weights[near].mean())
    assert ratios[0] == 1.0 and ratios[1] > 2.0, ratios


def test_a_global_spread_has_the_density_asked_and_the_first_update_resamples():
    grid = room(10.0)
    area = float(grid.free().sum()) * 0.05**2
    config = dc.replace(
        load_amcl_config(SHIPPED), global_localization_density=300.0, scan_match_refinement=False
    )
    dut = mut.ParticleFilter(grid, config, seed=2)
    dut.global_localization()
    assert len(dut.particles) == int(300.0 * area) > config.max_particles
    rows, cols = grid.cell_of(dut.particles[:, :2])
    assert np.all(grid.free()[rows, cols])
    assert not dut.localized()
    ranges = grid_scan(grid, (2.0, 3.0, 0.0), np.random.default_rng(2))
    dut.update(
        (0, 0, 0), ranges, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN, X_base_sensor=SENSOR
    )
    assert config.min_particles <= len(dut.particles) <= config.max_particles
    sparse = dc.replace(config, global_localization_density=1.0)
    dut = mut.ParticleFilter(grid, sparse, seed=2)
    dut.global_localization()
    assert len(dut.particles) == config.max_particles  # never fewer than max_particles


def test_heaviest_cluster_and_localized():
    rng = np.random.default_rng(5)
    near = rng.normal([1.0, 1.0, 0.0], [0.02, 0.02, 0.01], (900, 3))
    far = rng.normal([6.0, 1.0, 2.0], [0.02, 0.02, 0.01], (100, 3))
    particles = np.vstack([near, far])
    weights = np.full(1000, 1e-3)
    mask, share = histogram.heaviest_cluster(particles, weights)
    assert share == pytest.approx(0.9) and mask[:900].all() and not mask[900:].any()
    weights[900:] *= 20.0
    mask, share = histogram.heaviest_cluster(particles, weights / weights.sum())
    assert mask[900:].all() and share == pytest.approx(2.0 / 2.9)
    grid = room(8.0, pillars=[(2.0, 2.0, 0.5), (5.5, 3.0, 0.3)])
    config = dc.replace(load_amcl_config(SHIPPED), scan_match_refinement=False)
    dut = mut.ParticleFilter(grid, config, seed=3)
    assert not dut.localized()  # no update yet
    pose = np.array([3.0, 4.0, 0.5])
    dut.set_pose(pose, np.diag([1e-4, 1e-4, 1e-4]))
    ranges = grid_scan(grid, pose, np.random.default_rng(3))
    dut.update(
        (0, 0, 0), ranges, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN, X_base_sensor=SENSOR
    )
    assert dut.localized() and not dut.localized(std=0.001)
    dut.set_pose(pose, np.diag([1.0, 1.0, 0.1]))
    dut.update(
        (0, 0, 0), ranges, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN, X_base_sensor=SENSOR
    )
    assert not dut.localized()


@pytest.mark.slow
@pytest.mark.skipif(not TB3_MAP.is_file(), reason="../shared/real_ros (TurtleBot3 map) absent")
@pytest.mark.parametrize("seed", [0, 1])
def test_turtlebot3_world_global_localisation_while_spinning_in_place(seed):
    """As a nav2 user does: global localisation, then a spin in place (0.8 rad/s, a scan every
    0.16 rad) until the filter says it is localised, and on for 2 s; the estimate is then the
    truth."""
    grid = load_map(TB3_MAP)
    dut = mut.ParticleFilter(grid, load_amcl_config(SHIPPED), seed)
    dut.global_localization()
    rng = np.random.default_rng(seed)
    pose = np.array([-2.0, -0.5, 0.0])
    settled_at = None
    for k in range(90):  # 18 s at most, over two turns
        truth = pose + [0.0, 0.0, 0.16 * k]
        odometry = truth + [0.0, 0.0, rng.normal(0.0, 0.002)]
        ranges = grid_scan(grid, truth, rng)
        dut.update(
            odometry, ranges, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN, X_base_sensor=SENSOR
        )
        if settled_at is None and dut.localized():
            settled_at = k
        if settled_at is not None and k >= settled_at + 10:
            break
    assert settled_at is not None and settled_at < 70, settled_at  # within 14 s
    estimate, _ = dut.estimate()
    assert dut.localized() and math.dist(estimate[:2], truth[:2]) < 0.05
    assert abs(float(wrap_angle(estimate[2] - truth[2]))) < math.radians(3.0)


def test_tracking_across_open_floor_does_not_creep_towards_what_it_sees():
    """nav2's depot, in small: the robot drives 2.3 m across open floor from a pose estimate
    (the shipped covariance), exact odometry, with only a small hollow shelf near the lidar's
    range in view (5 to 16 beams). Scored by the likelihood field alone, the end points that
    fall inside the shelf count as hits, the estimate creeps towards it (nav2's depot: 0.15 m);
    with the hits' rays traced (``laser_trace_hits_below``), it does not."""
    n = 280  # 14 m of 0.05 m cells, the walls out of range
    cells = np.zeros((n, n), dtype=np.int8)
    cells[[0, -1], :] = cells[:, [0, -1]] = 100
    cells[188:198, 124:136] = 100  # a 0.6 m x 0.5 m shelf, one cell thick
    cells[189:197, 125:135] = 0
    grid = OccupancyMap(cells, 0.05)
    start, goal = (6.0, 6.0, 0.0), (7.83, 7.45)
    poses = drive(start, [goal], 13.0)
    rng = np.random.default_rng(2)
    scans = [grid_scan(grid, pose, rng, step=grid.resolution / 20) for pose in poses]
    hits = [int(np.isfinite(s).sum()) for s in scans]
    assert min(hits) >= 3 and max(hits) <= 20
    shipped = load_amcl_config(SHIPPED)
    errors = {}  # error along y (m) of the final estimate
    for below in (0, shipped.laser_trace_hits_below):
        config = dc.replace(shipped, laser_trace_hits_below=below)
        errors[below] = []
        for seed in range(2):
            dut = mut.ParticleFilter(grid, config, seed=seed)
            dut.set_pose(start, config.initial_covariance())
            for pose, ranges in zip(poses, scans, strict=True):
                dut.update(
                    pose, ranges, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN,
                    X_base_sensor=SENSOR,
                )  # fmt: skip
            estimate, _ = dut.estimate()
            errors[below].append(estimate[1] - poses[-1][1])
    # Towards the shelf's face the lidar sees (+y); across it, position and yaw trade off
    # alike in both (a few cm: the cloud is 0.2 m wide and the odometry was the truth).
    untraced, traced = errors.values()
    assert min(untraced) > 0.08 and max(np.abs(traced)) < 0.03, errors
