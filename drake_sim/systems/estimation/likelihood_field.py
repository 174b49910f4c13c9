"""AMCL's sensor model: the likelihood field of a map (Probabilistic Robotics, Table 6.3) and
the weight ROS's ``amcl`` gives each particle for a scan on it, one compiled numba kernel over
particles x beams (cached on disk). Part of the particle filter
(``drake_sim.systems.estimation.particle_filter``, whose docstring gives the model).
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


def likelihood_table(occupancy_map: OccupancyMap, config: AmclConfig):
    """(table, resolution): exp(-d^2 / (2 sigma_hit^2)) per cell (flattened, row-major),
    ``d`` the distance (m) to the nearest occupied cell capped at laser_likelihood_max_dist,
    with one more entry at the cap for points off the map."""
    occupied = occupancy_map.occupied()
    cap = config.laser_likelihood_max_dist
    if occupied.any():
        distance = ndimage.distance_transform_edt(~occupied) * occupancy_map.resolution
        distance = np.minimum(distance, cap)
    else:
        distance = np.full(occupied.shape, cap)
    d = np.append(distance.ravel(), cap)
    return np.exp(-(d * d) / (2.0 * config.laser_sigma_hit**2)), occupancy_map.resolution
