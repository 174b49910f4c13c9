"""The particles' pose histogram (ROS's ``pf_kdtree`` bins), and the two things AMCL reads off it:
how many particles KLD sampling keeps (Fox 2003) and ROS's estimate, the heaviest cluster's
weighted mean. Part of the particle filter (``drake_sim.systems.estimation.particle_filter``).
"""

import math

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from drake_sim.base.planar import wrap_angle
from drake_sim.systems.estimation.amcl_config import AmclConfig

BIN_XY = 0.5
"""m: the KLD histogram's (and the clusters') bin size in x and y, as ROS's ``pf_kdtree``."""
BIN_YAW = math.radians(10.0)
"""rad: the histogram's bin size in yaw."""
YAW_BINS = 36
"""Yaw bins of the histogram (a full turn)."""

LOCALIZED_SHARE = 0.95
"""``settled``'s default: the least share of the weight in the heaviest cluster."""
LOCALIZED_STD = 0.1
"""m: ``settled``'s default: the most standard deviation of that cluster's positions."""


def kld_limit(k, config: AmclConfig) -> np.ndarray:
    """The KLD bound (Fox 2003, ROS's ``pf_resample_limit``): particles needed when the set
    occupies ``k`` histogram bins, clipped to [min_particles, max_particles]."""
    k = np.asarray(k, dtype=float)
    km1 = np.maximum(k - 1.0, 1.0)
    b = 2.0 / (9.0 * km1)
    n = np.ceil(km1 / (2.0 * config.kld_err) * (1.0 - b + np.sqrt(b) * config.kld_z) ** 3)
    n = np.where(k <= 1, config.max_particles, n)
    return np.clip(n, config.min_particles, config.max_particles).astype(np.int64)


def kld_count(poses: np.ndarray, config: AmclConfig) -> int:
    """How many of ``poses`` (in order) KLD sampling keeps: the first count that exceeds the
    bound for the bins its poses occupy (ROS's resampling loop), at least min_particles."""
    keys = bin_keys(poses)
    flat = (keys[:, 0] * 1_000_003 + keys[:, 1]) * (YAW_BINS + 1) + keys[:, 2]
    _, first = np.unique(flat, return_index=True)
    new_bin = np.zeros(len(poses), dtype=bool)
    new_bin[first] = True
    counts = np.arange(1, len(poses) + 1)
    over = counts > kld_limit(np.cumsum(new_bin), config)
    n = int(np.argmax(over)) + 1 if over.any() else len(poses)
    return max(n, min(config.min_particles, len(poses)))


def bin_keys(poses: np.ndarray) -> np.ndarray:
    """(n, 3) integer histogram bins of poses: x, y in BIN_XY, yaw in BIN_YAW from -pi."""
    ix = np.floor(poses[:, 0] / BIN_XY)
    iy = np.floor(poses[:, 1] / BIN_XY)
    ia = np.clip(np.floor((wrap_angle(poses[:, 2]) + math.pi) / BIN_YAW), 0, YAW_BINS - 1)
    return np.stack([ix, iy, ia], -1).astype(np.int64)


def cluster_estimate(particles: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """ROS's estimate: the heaviest cluster's mean, the whole set's covariance."""
    best, _ = heaviest_cluster(particles, weights)
    w = weights[best] / weights[best].sum()
    p = particles[best]
    mean_yaw = math.atan2(float(w @ np.sin(p[:, 2])), float(w @ np.cos(p[:, 2])))
    pose = np.array([float(w @ p[:, 0]), float(w @ p[:, 1]), mean_yaw])
    w = weights / weights.sum()
    xy = particles[:, :2] - w @ particles[:, :2]
    covariance = np.zeros((3, 3))
    covariance[:2, :2] = (xy * w[:, None]).T @ xy
    resultant = math.hypot(float(w @ np.sin(particles[:, 2])), float(w @ np.cos(particles[:, 2])))
    covariance[2, 2] = -2.0 * math.log(max(resultant, 1e-300))
    return pose, covariance


def heaviest_cluster(particles: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, float]:
    """(mask (n,) of the heaviest cluster's particles, its share of the total weight)."""
    labels = clusters(particles)
    totals = np.bincount(labels, weights=weights)
    label = int(np.argmax(totals))
    return labels == label, float(totals[label] / totals.sum())


def settled(particles, weights, share=LOCALIZED_SHARE, std=LOCALIZED_STD) -> bool:
    """Whether the heaviest cluster holds at least ``share`` of the weight and its positions'
    weighted standard deviation (x and y together) is at most ``std`` m."""
    best, held = heaviest_cluster(particles, weights)
    w = weights[best] / weights[best].sum()
    xy = particles[best, :2] - w @ particles[best, :2]
    return held >= share and math.sqrt(float(w @ np.sum(xy * xy, axis=1))) <= std


def clusters(particles: np.ndarray) -> np.ndarray:
    """Labels (n,) of clusters: particles in the same or neighbouring histogram bins (26
    neighbours, yaw wrapping round) share a label."""
    keys = bin_keys(particles)
    keys[:, :2] -= keys[:, :2].min(axis=0)
    shape = (*(keys[:, :2].max(axis=0) + 1), YAW_BINS + 1)
    grid = np.zeros(shape, dtype=bool)
    grid[keys[:, 0], keys[:, 1], keys[:, 2]] = True
    grid[..., YAW_BINS] = grid[..., 0]  # a copy of the first yaw bin after the last
    labels, count = ndimage.label(grid, structure=np.ones((3, 3, 3), dtype=bool))
    a, b = labels[..., 0].ravel(), labels[..., YAW_BINS].ravel()
    same = (a > 0) & (b > 0)
    graph = coo_matrix((np.ones(int(same.sum())), (a[same], b[same])), shape=(count + 1,) * 2)
    _, merged = connected_components(graph, directed=False)
    return merged[labels[keys[:, 0], keys[:, 1], keys[:, 2]]]
