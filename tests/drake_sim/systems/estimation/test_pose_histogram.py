"""drake_sim.systems.estimation.pose_histogram: the KLD bound and sample count (Fox 2003), the
histogram's bins and clusters (yaw wrapping round), and ROS's clustered estimate."""

import dataclasses as dc
import math

import numpy as np

import drake_sim.systems.estimation.pose_histogram as mut
from drake_sim.base.planar import wrap_angle
from drake_sim.systems.estimation.amcl_config import AmclConfig


def test_kld_limit_follows_fox_2003():
    config = AmclConfig(min_particles=10, max_particles=100000, kld_err=0.05, kld_z=3.0)
    k = 10
    b = 2 / (9 * (k - 1))
    expected = math.ceil((k - 1) / (2 * 0.05) * (1 - b + math.sqrt(b) * 3.0) ** 3)
    assert mut.kld_limit(k, config) == expected
    limits = mut.kld_limit(np.arange(2, 200), config)
    assert np.all(np.diff(limits) > 0)  # more occupied bins need more particles
    assert mut.kld_limit(1, config) == config.max_particles
    clipped = dc.replace(config, min_particles=500, max_particles=1000)
    assert mut.kld_limit(2, clipped) == 500 and mut.kld_limit(10**4, clipped) == 1000


def _ros_resampling_loop(poses, config) -> int:
    """ROS's loop, one particle at a time: stop at the first count above the bound for the
    bins seen so far."""
    seen = set()
    for i, pose in enumerate(poses):
        seen.add(tuple(mut.bin_keys(pose[None])[0]))
        if i + 1 > mut.kld_limit(len(seen), config):
            return i + 1
    return len(poses)


def test_kld_count_is_ros_resampling_loop():
    config = AmclConfig(min_particles=5, max_particles=2000, kld_err=0.05, kld_z=3.0)
    rng = np.random.default_rng(0)
    for spread in (0.3, 1.0, 5.0):
        poses = np.column_stack(
            [rng.normal(0, spread, 2000), rng.normal(0, spread, 2000), rng.uniform(-3, 3, 2000)]
        )
        n = mut.kld_count(poses, config)
        assert n == max(_ros_resampling_loop(poses, config), config.min_particles)
    # All in one bin: the bound for one bin is max_particles, so every pose is kept.
    one_bin = np.tile([0.1, 0.1, 0.0], (300, 1))
    assert mut.kld_count(one_bin, config) == 300
    # Never below min_particles (nor more than there are).
    few = dc.replace(config, min_particles=50)
    assert mut.kld_count(poses[:20], few) == 20 and mut.kld_count(poses, few) >= 50


def test_bin_keys_are_half_metre_cells_and_ten_degree_yaw_bins():
    poses = np.array([[0.1, -0.1, -math.pi], [0.6, 1.2, 0.0], [-0.4, 0.0, math.pi - 1e-9]])
    keys = mut.bin_keys(poses)
    np.testing.assert_array_equal(keys[:, :2], [[0, -1], [1, 2], [-1, 0]])
    assert keys[0, 2] == 0 and keys[1, 2] == mut.YAW_BINS // 2 and keys[2, 2] == mut.YAW_BINS - 1
    assert mut.BIN_XY == 0.5 and math.radians(10.0) == mut.BIN_YAW


def test_clusters_join_neighbouring_bins_and_wrap_yaw_round():
    poses = np.array(
        [
            [0.1, 0.1, -math.pi + 0.01],  # the first yaw bin ...
            [0.1, 0.1, math.pi - 0.01],  # ... joins the last: one cluster
            [0.6, 0.1, math.pi - 0.01],  # a neighbouring cell: the same cluster
            [3.0, 3.0, 0.0],  # far away: its own
        ]
    )
    labels = mut.clusters(poses)
    assert labels[0] == labels[1] == labels[2] != labels[3]


def test_estimate_is_the_heaviest_clusters_mean_with_yaw_wrapping_round():
    rng = np.random.default_rng(0)
    near_pi = np.column_stack(
        [
            rng.normal(1.0, 0.02, 60),
            rng.normal(2.0, 0.02, 60),
            wrap_angle(math.pi + rng.normal(0.0, 0.05, 60)),
        ]
    )
    elsewhere = np.column_stack(
        [rng.normal(-3.0, 0.02, 40), rng.normal(0.0, 0.02, 40), np.zeros(40)]
    )
    pose, covariance = mut.cluster_estimate(np.vstack([near_pi, elsewhere]), np.full(100, 0.01))
    np.testing.assert_allclose(pose[:2], near_pi[:, :2].mean(0), atol=1e-9)
    assert abs(float(wrap_angle(pose[2] - math.pi))) < 0.02
    assert covariance[0, 0] > 3.0  # the whole set's spread, both clusters
    np.testing.assert_allclose(covariance, covariance.T)
    # Weight decides, not count: the 40 particles win when they weigh more.
    weights = np.concatenate([np.full(60, 0.005), np.full(40, 0.0175)])
    pose, _ = mut.cluster_estimate(np.vstack([near_pi, elsewhere]), weights)
    np.testing.assert_allclose(pose[:2], elsewhere[:, :2].mean(0), atol=1e-9)
