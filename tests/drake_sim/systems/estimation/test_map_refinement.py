"""drake_sim.systems.estimation.map_refinement: the map's likelihood-field pyramid, the
convergence test, and a refinement that corrects a biased estimate, keeps the position along a
corridor, and is refused past its gates (the filter's use of it: test_particle_filter.py)."""

import dataclasses as dc
import math

import numpy as np

import drake_sim.systems.estimation.map_refinement as mut
from drake_sim.base.map_files import OccupancyMap
from drake_sim.systems.estimation.amcl_config import AmclConfig
from tests.drake_sim.systems.estimation.test_particle_filter import (
    ANGLES,
    RANGE_MAX,
    RANGE_MIN,
    SENSOR,
    scan_at,
    world,
)

CONFIG = AmclConfig(scan_match_refinement=True)
TRUTH = np.array([0.3, 0.2, 0.4])  # in the maze
OFFSET = np.array([0.04, -0.03, math.radians(1.5)])


def refine(config, pose, ranges, grid):
    pyramid = mut.match_pyramid(grid, config)
    return mut.refine_pose(
        pyramid, config, grid.origin, pose, ranges, ANGLES, RANGE_MAX, RANGE_MIN, SENSOR
    )


def test_pyramid_levels_a_finer_first_and_halving_resolutions():
    cells = np.zeros((10, 12), dtype=np.int8)
    cells[4, 5] = 100
    grid = OccupancyMap(cells, 0.05, (3.0, -1.0, 0.7))
    config = dc.replace(CONFIG, refinement_levels=3, refinement_subdivision=4)
    levels = mut.match_pyramid(grid, config)
    assert [level.resolution for level in levels] == [0.0125, 0.05, 0.1, 0.2]
    assert all(level.origin == (0.0, 0.0) for level in levels)  # the map's own frame
    assert levels[2].values.shape == (5 + 2, 6 + 2)  # 2x2 blocks, padded by one cell
    # The finest level peaks on the occupied cell's faces (its 4 x 4 fine cells' rim), not
    # inside it.
    fine = levels[0].values[1:-1, 1:-1]
    block = fine[16:20, 20:24]
    assert block[0, 0] == block[3, 1] == block[2, 3] == 1.0
    assert block[1, 1] == block[2, 2] == math.exp(-0.5 * (1 / 4) ** 2)
    no_subdivision = mut.match_pyramid(grid, dc.replace(config, refinement_subdivision=1))
    assert [level.resolution for level in no_subdivision] == [0.05, 0.1, 0.2]


def test_field_level_is_a_gaussian_of_the_distance_in_cells():
    occupied = np.zeros((5, 5), bool)
    occupied[2, 2] = True
    level = mut.field_level(occupied, np.ones((5, 5), bool), 0.1, 2.0)
    values = level.values[1:-1, 1:-1]
    assert values[2, 2] == 1.0
    assert values[2, 4] == math.exp(-0.5 * (2 / 2.0) ** 2)
    assert not mut.field_level(np.zeros((3, 3), bool), None, 0.1, 1.0).values[1:-1, 1:-1].any()


def test_refinement_corrects_a_biased_estimate():
    _, footprints, grid, _ = world("maze")
    ranges = scan_at(footprints, TRUTH, np.random.default_rng(0))
    match, refined = refine(CONFIG, TRUTH + OFFSET, ranges, grid)
    assert match is not None and match.scores[0] > CONFIG.refinement_min_score
    assert math.dist(refined[:2], TRUTH[:2]) < 0.015
    assert abs(refined[2] - TRUTH[2]) < math.radians(0.5)


def test_refinement_refused_past_its_gates_or_without_returns():
    _, footprints, grid, _ = world("maze")
    ranges = scan_at(footprints, TRUTH, np.random.default_rng(0))
    gated = dc.replace(CONFIG, refinement_max_correction=0.02)
    match, refined = refine(gated, TRUTH + OFFSET, ranges, grid)
    assert match is not None and refined is None
    few = np.full(360, np.inf)
    few[:10] = 1.0
    assert refine(CONFIG, TRUTH + OFFSET, few, grid) == (None, None)


def test_converged_at_the_truth_but_not_far_from_it():
    _, footprints, grid, _ = world("maze")
    level = mut.match_pyramid(grid, CONFIG)[0]
    ranges = scan_at(footprints, TRUTH, np.random.default_rng(0))
    hit = np.isfinite(ranges) & (ranges < RANGE_MAX) & (ranges > RANGE_MIN)
    r, a = ranges[hit], ANGLES[hit]
    points = np.stack([SENSOR[0] + r * np.cos(a), SENSOR[1] + r * np.sin(a)], -1)
    match, _ = refine(CONFIG, TRUTH + OFFSET, ranges, grid)
    assert mut.converged(level, points, match.pose, CONFIG.refinement_tolerance)
    far = match.pose + [0.05, 0.0, 0.0]
    assert not mut.converged(level, points, far, CONFIG.refinement_tolerance)
