"""AMCL's sensor model: the likelihood field of a map (Probabilistic Robotics, Table 6.3) and
the weight ROS's ``amcl`` gives each particle for a scan on it, one compiled numba kernel over
particles x beams (cached on disk); and our term for the beams that saw nothing
(``laser_no_return_beams``): each such ray is traced through the map's distance field (sphere
tracing: steps as long as the distance to the nearest occupied cell, so a ray across open floor
takes two or three) and scores as a hit when the map lets it run free to the maximum range;
and, for scans with few hits (``laser_trace_hits_below``), the hits' rays traced the same way
over their last few sigma, so an end point behind a face no longer scores as a hit. Part of
the particle filter (``drake_sim.systems.estimation.particle_filter``, whose docstring gives
the model).
"""

import math

import numba
import numpy as np
from scipy import ndimage

from drake_sim.base.map_files import OccupancyMap
from drake_sim.systems.estimation.amcl_config import AmclConfig


@numba.njit(cache=True)
def scan_likelihood(particles, bx, by, table, origin, resolution, shape, z_hit, z_rand_term):
    """ROS's likelihood-field weight ``1 + sum(pz^3)`` of each particle (n,) for beam end
    points (bx, by) in the base frame (m); ``table`` from ``likelihood_table``."""
    n_rows, n_cols = shape
    x0, y0, yaw0 = origin
    c0, s0 = math.cos(yaw0), math.sin(yaw0)
    outside = n_rows * n_cols
    result = np.empty(particles.shape[0])
    for i in range(particles.shape[0]):
        px, py = particles[i, 0] - x0, particles[i, 1] - y0
        lx, ly = (c0 * px + s0 * py) / resolution, (-s0 * px + c0 * py) / resolution
        cos_t = math.cos(particles[i, 2] - yaw0) / resolution
        sin_t = math.sin(particles[i, 2] - yaw0) / resolution
        total = 1.0
        for j in range(bx.shape[0]):
            col = math.floor(lx + cos_t * bx[j] - sin_t * by[j])
            row = math.floor(ly + sin_t * bx[j] + cos_t * by[j])
            index = outside
            if 0 <= row < n_rows and 0 <= col < n_cols:
                index = row * n_cols + col
            pz = z_hit * table[index] + z_rand_term
            total += pz * pz * pz
        result[i] = total
    return result


@numba.njit(cache=True)
def _sensor_cells(particle, sensor, x0, y0, c0, s0, inv):
    """(lx, ly, cos, sin): the sensor of a base at ``particle`` [x, y, yaw] in the map's cells,
    and the cosine and sine of the base's heading."""
    cos_t, sin_t = math.cos(particle[2]), math.sin(particle[2])
    sx = particle[0] + cos_t * sensor[0] - sin_t * sensor[1] - x0
    sy = particle[1] + sin_t * sensor[0] + cos_t * sensor[1] - y0
    return (c0 * sx + s0 * sy) * inv, (-s0 * sx + c0 * sy) * inv, cos_t, sin_t


@numba.njit(cache=True)
def _direction_cells(ux, uy, cos_t, sin_t, c0, s0, inv):
    """(mx, my): a beam's unit direction (ux, uy) in the base frame, in map cells per m."""
    dx, dy = cos_t * ux - sin_t * uy, sin_t * ux + cos_t * uy
    return (c0 * dx + s0 * dy) * inv, (-s0 * dx + c0 * dy) * inv


@numba.njit(cache=True)
def _free_run(lx, ly, mx, my, start, limit, distance, n_rows, n_cols, resolution, bisect):
    """How far (m) a ray from (lx, ly) (cells) along (mx, my) (cells per m), looked at from
    ``start`` (m) on, runs before it enters an occupied cell of the map: ``limit`` at most,
    ``start`` when it starts in one. Sphere tracing (steps as long as the distance to the
    nearest occupied cell, half a cell at least: the entry is passed by half a cell at most),
    then with ``bisect`` the entry found to 1/32 of a cell; a ray that leaves the map runs
    free."""
    # A point in a cell whose centre is d from an occupied cell's centre is at least
    # d - sqrt(2) cells from that cell: steps that long cannot pass over it.
    margin, least = 1.5 * resolution, 0.5 * resolution
    s, before = start, start
    while s < limit:
        col = math.floor(lx + mx * s)
        row = math.floor(ly + my * s)
        if not (0 <= row < n_rows and 0 <= col < n_cols):
            return limit  # off the map (which is convex): nothing more to meet
        if distance[row * n_cols + col] <= 0.0:
            for _ in range(4 if bisect else 0):  # the entry lies in (before, s]
                middle = 0.5 * (before + s)
                col = math.floor(lx + mx * middle)
                row = math.floor(ly + my * middle)
                if distance[row * n_cols + col] <= 0.0:
                    s = middle
                else:
                    before = middle
            return s
        before = s
        s += max(distance[row * n_cols + col] - margin, least)
    return limit


@numba.njit(cache=True)
def no_return_likelihood(
    particles,
    sensor,
    ux,
    uy,
    distance,
    origin,
    resolution,
    shape,
    range_max,
    sigma,
    z_hit,
    z_rand_term,
):
    """Sum over the beams that saw nothing (no return within ``range_max``) of ``pz^3``, per
    particle (n,), with ``pz = z_hit * exp(-s^2 / (2 sigma^2)) + z_rand_term``: ``s`` (m) is how
    far short of ``range_max`` the ray meets an occupied cell of the map (0 when it runs free).

    Args:
        particles: (n, 3) poses [x, y, yaw] of the base in the world.
        sensor: [x, y] of the sensor in the base frame (m).
        ux, uy: (k,) unit directions of the beams in the base frame.
        distance: from ``distance_table``: m to the nearest occupied cell's centre per cell
            (flattened, row-major), capped. A ray that leaves the map runs free.
        origin, resolution, shape: the map's.
    """
    n_rows, n_cols = shape
    x0, y0, yaw0 = origin
    c0, s0 = math.cos(yaw0), math.sin(yaw0)
    inv = 1.0 / resolution
    result = np.zeros(particles.shape[0])
    for i in range(particles.shape[0]):
        lx, ly, cos_t, sin_t = _sensor_cells(particles[i], sensor, x0, y0, c0, s0, inv)
        total = 0.0
        for j in range(ux.shape[0]):
            mx, my = _direction_cells(ux[j], uy[j], cos_t, sin_t, c0, s0, inv)
            s = _free_run(
                lx, ly, mx, my, 0.0, range_max, distance, n_rows, n_cols, resolution, False
            )
            short = max(range_max - s, 0.0)
            pz = z_hit * math.exp(-(short * short) / (2.0 * sigma * sigma)) + z_rand_term
            total += pz * pz * pz
        result[i] = total
    return result


@numba.njit(cache=True)
def traced_hit_likelihood(
    particles, sensor, ux, uy, ranges, distance, origin, resolution, shape, sigma, z_hit,
    z_rand_term,
):  # fmt: skip
    """ROS's weight ``1 + sum(pz^3)`` of each particle (n,) for the beams that hit something,
    each beam's ray traced through the map as well (ours, ``laser_trace_hits_below``):
    ``pz = z_hit * exp(-e^2 / (2 sigma^2)) + z_rand_term``, ``e`` (m) the larger of the end
    point's distance to the nearest occupied cell's face (its centre's less half a cell) and how
    far short of the end point the ray enters an occupied cell (looked for over the last
    ``3 sigma``: further back, pz is at its floor anyway). The likelihood field alone scores an
    end point inside or behind an obstacle as well as one on its face, so with few beams in
    range the estimate creeps towards what the robot sees; the traced ray tells them apart, as
    the beam model does, and the face (not the centre) makes both sides of a face score alike.

    Args:
        particles: (n, 3) poses [x, y, yaw] of the base in the world.
        sensor: [x, y] of the sensor in the base frame (m).
        ux, uy, ranges: (k,) unit directions of the beams in the base frame and their ranges (m).
        distance: from ``distance_table``; origin, resolution, shape: the map's.
    """
    n_rows, n_cols = shape
    x0, y0, yaw0 = origin
    c0, s0 = math.cos(yaw0), math.sin(yaw0)
    inv, half = 1.0 / resolution, 0.5 * resolution
    window = 3.0 * sigma  # beyond it, pz is the floor whatever the ray meets
    outside = n_rows * n_cols
    result = np.empty(particles.shape[0])
    for i in range(particles.shape[0]):
        lx, ly, cos_t, sin_t = _sensor_cells(particles[i], sensor, x0, y0, c0, s0, inv)
        total = 1.0
        for j in range(ux.shape[0]):
            mx, my = _direction_cells(ux[j], uy[j], cos_t, sin_t, c0, s0, inv)
            col = math.floor(lx + mx * ranges[j])
            row = math.floor(ly + my * ranges[j])
            index = outside
            if 0 <= row < n_rows and 0 <= col < n_cols:
                index = row * n_cols + col
            e = max(distance[index] - half, 0.0)
            r = ranges[j]
            start = max(r - window, 0.0)
            run = _free_run(lx, ly, mx, my, start, r, distance, n_rows, n_cols, resolution, True)
            e = max(e, r - run)
            pz = z_hit * math.exp(-(e * e) / (2.0 * sigma * sigma)) + z_rand_term
            total += pz * pz * pz
        result[i] = total
    return result


def no_return_factor(
    particles, angles, sensor, distance, occupancy_map: OccupancyMap, config: AmclConfig, range_max
) -> np.ndarray:
    """The factor (n,) in (0, 1] by which the beams at ``angles`` (rad, base frame) that saw
    nothing weigh each particle: ROS's combination ``1 + sum(pz^3)`` of ``no_return_likelihood``
    for them apart, over its value when every ray runs free, so the hits keep their strength.

    Args:
        sensor: [x, y, yaw] of the sensor in the base frame; ``distance``: ``distance_table``.
    """
    z_rand_term = config.laser_z_rand / range_max
    free = 1.0 + len(angles) * (config.laser_z_hit + z_rand_term) ** 3
    total = no_return_likelihood(
        particles,
        np.asarray(sensor[:2], dtype=float),
        np.cos(angles),
        np.sin(angles),
        distance,
        occupancy_map.origin,
        occupancy_map.resolution,
        occupancy_map.shape,
        range_max,
        config.laser_sigma_hit,
        config.laser_z_hit,
        z_rand_term,
    )
    return (1.0 + total) / free


def distance_table(occupancy_map: OccupancyMap, cap: float) -> np.ndarray:
    """The distance (m) from each cell's centre to the nearest occupied cell's centre, capped at
    ``cap``, flattened row-major, with one more entry (``cap``) for points off the map."""
    occupied = occupancy_map.occupied()
    if occupied.any():
        distance = ndimage.distance_transform_edt(~occupied) * occupancy_map.resolution
        distance = np.minimum(distance, cap)
    else:
        distance = np.full(occupied.shape, cap)
    return np.append(distance.ravel(), cap)


def likelihood_table(occupancy_map: OccupancyMap, config: AmclConfig, distance=None):
    """(table, resolution): exp(-d^2 / (2 sigma_hit^2)) per cell (flattened, row-major),
    ``d`` the distance (m) to the nearest occupied cell capped at laser_likelihood_max_dist,
    with one more entry at the cap for points off the map; ``distance``: that
    ``distance_table`` when the caller has it already."""
    d = distance
    if d is None:
        d = distance_table(occupancy_map, config.laser_likelihood_max_dist)
    return np.exp(-(d * d) / (2.0 * config.laser_sigma_hit**2)), occupancy_map.resolution
