"""Scan-to-map refinement of AMCL's estimate (ours, not ROS's; ``scan_match_refinement``): the
scan's end points matched against likelihood fields of the map from the filter's estimate, and
the gates a match must pass to replace it. Part of the particle filter
(``drake_sim.systems.estimation.particle_filter``, whose docstring tells why and how well).
"""

import math

import numpy as np
from scipy import ndimage

from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.planar import compose, relative_pose
from drake_sim.systems.estimation.amcl_config import AmclConfig
from drake_sim.systems.estimation.scan_matcher import (
    MatchMap,
    MatchResult,
    match_scan,
    normal_spread,
    transform_points,
)


def in_range(config: AmclConfig, ranges, range_max: float, range_min: float) -> np.ndarray:
    """(k,) bool: the beams that returned within the scan's limits, narrowed by the filter's
    ``laser_max_range`` and ``laser_min_range`` when those are set."""
    if config.laser_max_range > 0:
        range_max = min(range_max, config.laser_max_range)
    if config.laser_min_range > 0:
        range_min = max(range_min, config.laser_min_range)
    ranges = np.asarray(ranges, dtype=float)
    return np.isfinite(ranges) & (ranges < range_max) & (ranges > range_min)


def refine_pose(
    pyramid: list[MatchMap],
    config: AmclConfig,
    origin,
    pose: np.ndarray,
    ranges,
    angles,
    range_max: float,
    range_min: float,
    sensor,
) -> tuple[MatchResult | None, np.ndarray | None]:
    """Matches a scan's end points against the map from the filter's estimate ``pose``.

    Args:
        pyramid: the map's levels from ``match_pyramid``.
        config: the parameters (``laser_*_range`` and ``refinement_*``).
        origin: the map's origin [x, y, yaw] in the world (m, m, rad).
        pose: the filter's estimate [x, y, yaw] in the world.
        ranges, angles: the scan (m, rad in the sensor frame).
        range_max, range_min: the scan's limits (m).
        sensor: [x, y, yaw] of the sensor in the base frame.

    Returns:
        (match, refined): the match (None when too few beams are in range to try one) and the
        refined pose in the world, None unless the match converged, moved less than the gate
        and scores at least ``refinement_min_score``. Along a corridor (the scan's normals all
        one way) the refined pose keeps the filter's position along it.
    """
    c = config
    hit = in_range(c, ranges, range_max, range_min)
    if hit.sum() < c.refinement_min_points:
        return None, None
    r, a = ranges[hit], angles[hit]
    if len(r) > c.refinement_max_beams:  # evenly spread
        keep = np.unique(np.linspace(0, len(r) - 1, c.refinement_max_beams).round())
        r, a = r[keep.astype(int)], a[keep.astype(int)]
    points = np.stack(
        [sensor[0] + r * np.cos(sensor[2] + a), sensor[1] + r * np.sin(sensor[2] + a)], -1
    )
    start = relative_pose(origin, pose)  # matching runs in the map's own frame
    result = match_scan(pyramid, points, start, iterations=c.refinement_iterations)
    refined = result.pose
    values, vectors = normal_spread(points)
    if not (values[1] > 0 and values[0] >= c.refinement_degenerate_ratio * values[1]):
        # Surfaces all facing one way (a corridor): keep the filter's position along them.
        along = transform_points((0.0, 0.0, refined[2]), vectors[:, 0][None, :])[0]
        refined = refined.copy()
        refined[:2] -= along * (along @ (refined[:2] - start[:2]))
    offset = relative_pose(start, refined)
    if (
        math.hypot(offset[0], offset[1]) > c.refinement_max_correction
        or abs(offset[2]) > c.refinement_max_correction_a
        or result.scores[0] < c.refinement_min_score
        or not converged(pyramid[0], points, result.pose, c.refinement_tolerance)
    ):
        return result, None
    return result, compose(origin, refined)


def match_pyramid(occupancy_map: OccupancyMap, config: AmclConfig) -> list[MatchMap]:
    """The likelihood-field ``MatchMap`` levels of the map, finest first, in the map's own
    frame (origin (0, 0), no rotation).

    Level k of ``refinement_levels`` has cells of resolution * 2^k, a cell occupied where any
    of its block is, and values exp(-d^2 / (2 s^2)), d the distance (cells) to the nearest
    occupied cell and s = ``refinement_field`` cells. With ``refinement_subdivision`` n > 1 a
    finer level (cells of resolution / n) comes first, whose field peaks on the boundary
    between the map's occupied and free cells (d: the distance to the fine occupied cells
    touching a free one) rather than on the occupied cells' centres: the map marks a cell
    occupied when its centre is inside an obstacle, so an obstacle's face is on average on
    that boundary, while the centres lie half a cell inside it (a bias of up to 2.5 cm with
    0.05 m cells where most beams hit walls on one side)."""
    occupied = occupancy_map.occupied()
    known = ~occupancy_map.unknown()
    levels = []
    n = config.refinement_subdivision
    if n > 1:
        fine = np.kron(occupied, np.ones((n, n), bool))
        free = ~fine
        touching = np.zeros_like(fine)
        touching[1:] |= free[:-1]
        touching[:-1] |= free[1:]
        touching[:, 1:] |= free[:, :-1]
        touching[:, :-1] |= free[:, 1:]
        surface = fine & touching
        seen = ndimage.binary_dilation(np.kron(known, np.ones((n, n), bool)), np.ones((3, 3), bool))
        levels.append(
            field_level(surface, seen, occupancy_map.resolution / n, n * config.refinement_field)
        )
    for k in range(config.refinement_levels):
        block = 2**k
        rows = -(-occupied.shape[0] // block) * block
        cols = -(-occupied.shape[1] // block) * block
        shape = (rows // block, block, cols // block, block)
        occ = np.zeros((rows, cols), bool)
        occ[: occupied.shape[0], : occupied.shape[1]] = occupied
        seen = np.zeros((rows, cols), bool)
        seen[: known.shape[0], : known.shape[1]] = known
        occ, seen = occ.reshape(shape).any(axis=(1, 3)), seen.reshape(shape).any(axis=(1, 3))
        seen = ndimage.binary_dilation(seen, np.ones((3, 3), bool))
        levels.append(
            field_level(occ, seen, occupancy_map.resolution * block, config.refinement_field)
        )
    return levels


def field_level(occupied, seen, resolution, width) -> MatchMap:
    """A ``MatchMap`` of exp(-d^2 / (2 width^2)), d (cells) to the nearest occupied cell."""
    if occupied.any():
        distance = ndimage.distance_transform_edt(~occupied)
        values = np.exp(-0.5 * (distance / width) ** 2)
    else:
        values = np.zeros(occupied.shape)
    return MatchMap(values, resolution, (0.0, 0.0), seen)


def converged(match_map: MatchMap, points, pose, tolerance: float) -> bool:
    """Whether one more Gauss-Newton step of ``match_scan``'s cost (without a prior) on
    ``match_map`` from ``pose`` would move less than ``tolerance`` (m and rad)."""
    world = transform_points(pose, points)
    value, grad = match_map.interpolate(world)
    w = match_map.is_known(world).astype(float)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    d_yaw = grad[:, 0] * (-s * points[:, 0] - c * points[:, 1]) + grad[:, 1] * (
        c * points[:, 0] - s * points[:, 1]
    )
    jacobian = np.stack([grad[:, 0], grad[:, 1], d_yaw], -1)
    weighted = jacobian * w[:, None]
    try:
        step = np.linalg.solve(weighted.T @ jacobian, weighted.T @ (1.0 - value))
    except np.linalg.LinAlgError:
        return False
    return bool(np.all(np.isfinite(step)) and np.abs(step).max() < tolerance)
