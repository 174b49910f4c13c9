"""Adaptive Monte Carlo localisation on a known map: the particle filter of ROS's ``amcl``.

Its parameters (``AmclConfig``, ROS's names) are in ``drake_sim.systems.estimation.amcl``.

The algorithm of Probabilistic Robotics (Thrun, Burgard, Fox 2005) as the ROS ``amcl`` node
runs it, vectorised with numpy (no Python loop over particles or beams; the likelihood field's
loop over particles x beams is one compiled numba kernel, cached on disk):

* motion: ``sample_motion_model_odometry`` (Table 5.6), ROS's ``diff-corrected`` model: the
  odometry's motion since the last filter update is split into a turn, a straight move and a
  turn, each perturbed by zero-mean Gaussian noise whose variance mixes ``odom_alpha1..4``;
* sensor: the likelihood field (Table 6.3): a beam's end point at distance ``d`` from the
  nearest occupied cell scores ``pz = z_hit * exp(-d^2 / (2 sigma_hit^2)) + z_rand /
  range_max`` (the Gaussian unnormalised, as in ROS); ``laser_max_beams`` beams evenly spread
  over the scan, beams at or beyond the maximum range (or ``inf``, or below the minimum) are
  skipped; a particle's weight is multiplied by ``1 + sum(pz^3)`` (ROS's combination, which
  is less overconfident than the product). ``d`` comes from a Euclidean distance transform of
  the map's occupied cells, computed once and capped at ``laser_likelihood_max_dist``; points
  off the map take that cap;
* resampling every ``resample_interval`` updates with a particle count chosen by KLD sampling
  (Fox 2003): ``n`` grows until it exceeds the bound for the number ``k`` of histogram bins
  (0.5 m x 0.5 m x 10 degrees, as ROS) that the new set occupies, between ``min_particles``
  and ``max_particles``; the set is a random ordering of a low-variance (systematic) sample
  (Table 4.4), cut at ``n``;
* recovery (Table 8.3): averages ``w_slow`` and ``w_fast`` of the measurement likelihood;
  each new particle is a random pose in the map's free space with probability
  ``max(0, 1 - w_fast / w_slow)``;
* the estimate is ROS's: the weighted mean of the heaviest cluster of particles (bins of the
  histogram above, neighbours joined, yaw wrapping round), with the covariance of the whole
  set (x, y block and the circular variance of yaw).
* scan-to-map refinement (ours, not ROS's; ``scan_match_refinement``, a common AMCL variant):
  the filter's estimate is good to a few cm only (particles 1 to 2 cm apart, ROS's weak
  likelihood), so after each update the scan's end points (up to ``refinement_max_beams`` of
  the beams in range, in the base frame) are matched against the map from the estimate with
  ``scan_matcher.match_scan`` (Gauss-Newton, coarse to fine, on likelihood fields built once
  from the map, ``_match_pyramid``). The match becomes the estimate if it converged (one more
  step moves less than ``refinement_tolerance``), moved less than the gate
  (``refinement_max_correction`` m, ``refinement_max_correction_a`` rad) and its end points
  score at least ``refinement_min_score`` on the finest level; along a corridor (the scan's
  normals all one way, ``scan_matcher.normal_spread``) the filter's position along it stays.
  With ``refinement_shift_particles`` the whole set then moves rigidly by the correction
  (about the old estimate), which keeps its spread, weights and covariance and lets the next
  update start from the refined pose; without it, the particles stay where the filter put
  them and a rejected match leaves the filter's bias (measured in the warehouse, navigation to
  10 goals: worst goal 2.1 cm with the shift, 2.6 to 5.3 cm without).

Deliberate differences from ROS: the update threshold ``update_min_d`` applies to the distance
moved (ROS compares |dx| and |dy| separately); ``w_avg`` is the expected likelihood of the scan
(Probabilistic Robotics; ROS divides it by the particle count as well); global localisation
draws positions uniformly inside free cells (ROS uses the cells' centres); with
``selective_resampling``, a resampling also runs when recovery is due (a kidnapped robot's
particles are all equally bad, so the effective sample size alone would never resample). As in
ROS, ``kld_z`` is used as the normal quantile itself.

Cost (``benchmarks/amcl_benchmark.py``, 2 cores): 1.2 to 1.9 ms median per update with 2000
particles and 60 beams (the sensor model about 0.4 ms, the clustered estimate 0.5 ms), plus
about 1.5 ms for the scan-to-map refinement (180 beams).
"""

import math
from typing import TYPE_CHECKING

import numba
import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap
from drake_sim.systems.estimation.scan_matcher import (
    MatchMap,
    MatchResult,
    match_scan,
    normal_spread,
    transform_points,
)

if TYPE_CHECKING:  # the parameters live with the system, which imports this module
    from drake_sim.systems.estimation.amcl import AmclConfig

BIN_XY = 0.5
"""m: the KLD histogram's (and the clusters') bin size in x and y, as ROS's ``pf_kdtree``."""
BIN_YAW = math.radians(10.0)
"""rad: the histogram's bin size in yaw."""
_YAW_BINS = 36


def wrap(angle):
    """Wraps angles (rad) to [-pi, pi)."""
    return (np.asarray(angle) + math.pi) % (2.0 * math.pi) - math.pi


class ParticleFilter:
    """AMCL's particle filter on ``occupancy_map`` (see the module docstring).

    Args:
        occupancy_map: the map; its occupied cells (>= 65) make the likelihood field, its free
            cells (<= 25) are where global localisation and recovery put particles.
        config: the parameters, an ``AmclConfig`` that ``check_amcl_config`` accepted.
        seed: seed of the filter's own random generator.

    Attributes:
        particles: (n, 3) poses [x, y, yaw] (m, m, rad) in the map's world frame.
        weights: (n,) normalised weights.
        refinements: [accepted, rejected] scan-to-map refinements so far.
        last_match: the last refinement's ``MatchResult`` (base pose in the map's own frame),
            None before the first.
    """

    def __init__(self, occupancy_map: OccupancyMap, config: "AmclConfig", seed=0):
        self.config = config
        self.map = occupancy_map
        self._rng = np.random.default_rng(seed)
        self._field = _likelihood_table(occupancy_map, self.config)
        self._pyramid = (
            _match_pyramid(occupancy_map, config) if config.scan_match_refinement else []
        )
        self.last_match: MatchResult | None = None  # The last refinement's match, if any.
        self.refinements = [0, 0]  # Refinements [accepted, rejected] so far.
        free_rows, free_cols = np.nonzero(occupancy_map.free())
        self._free_cells = np.stack([free_cols, free_rows], -1).astype(float)
        self._odom = None  # odometry [x, y, yaw] at the last update; None: take the next one's
        self._resample_count = 0
        self._w_slow = self._w_fast = 0.0
        self.updates = 0  # Filter updates so far.
        self.set_pose(self.config.initial_pose(), self.config.initial_covariance())

    def copy(self) -> "ParticleFilter":
        """Returns an independent copy (the map and the likelihood field are shared)."""
        other = ParticleFilter.__new__(ParticleFilter)
        other.__dict__.update(self.__dict__)
        other._rng = np.random.default_rng()
        other._rng.bit_generator.state = self._rng.bit_generator.state
        other.particles, other.weights = self.particles.copy(), self.weights.copy()
        other.refinements = list(self.refinements)
        if self._odom is not None:
            other._odom = self._odom.copy()
        return other

    def __deepcopy__(self, memo):
        return self.copy()

    def set_pose(self, pose, covariance, odom_pose=None) -> None:
        """Starts again from ``max_particles`` particles drawn from N(pose, covariance).

        Args:
            pose: [x, y, yaw] (m, m, rad) in the map frame.
            covariance: (3, 3) symmetric positive semi-definite (m^2, rad^2).
            odom_pose: the odometry at that pose: the next update applies the motion since;
                None: the next update takes its odometry as the reference and applies none.
        The next update always runs.

        Raises:
            ConfigError: a pose or covariance that is not finite, or a covariance that is
                not symmetric positive semi-definite.
        """
        pose, covariance = _check_pose(pose, covariance)
        n = self.config.max_particles
        particles = self._rng.multivariate_normal(pose, covariance, size=n, method="eigh")
        particles[:, 2] = wrap(particles[:, 2])
        self._restart(particles, odom_pose)

    def global_localization(self) -> None:
        """Starts again from ``max_particles`` poses uniform over the map's free space (ROS's
        ``global_localization`` service). The next update always runs."""
        self._restart(self._random_poses(self.config.max_particles), None)

    def update(
        self, odom_pose, ranges, angles, *, range_max, range_min=0.0, X_base_sensor=(0, 0, 0)
    ) -> bool:
        """Takes one scan with the odometry of the same instant.

        Runs a filter update (motion, sensor, and every ``resample_interval`` updates a
        resampling, with ``selective_resampling`` only when the effective sample size is
        below half the count or recovery is due) when the odometry has moved
        ``update_min_d`` or turned ``update_min_a`` since the last update, and always for
        the first scan after a (re)start.

        Args:
            odom_pose: [x, y, yaw] of the base from wheel odometry (m, m, rad), any fixed frame.
            ranges: (k,) m, ``inf`` (or >= the maximum range) where a beam saw nothing.
            angles: (k,) rad, each beam's direction in the sensor frame.
            range_max, range_min: the scan's limits (m).
            X_base_sensor: [x, y, yaw] of the sensor in the base frame (m, m, rad).

        Returns:
            True if the filter updated.
        """
        odom = np.asarray(odom_pose, dtype=float).reshape(3)
        if self._odom is not None:
            delta = odom - self._odom
            moved = math.hypot(delta[0], delta[1]) >= self.config.update_min_d
            turned = abs(float(wrap(delta[2]))) >= self.config.update_min_a
            if not (self._force or moved or turned):
                return False
            self._move(self._odom, odom)
        scan = (
            np.asarray(ranges, dtype=float),
            np.asarray(angles, dtype=float),
            float(range_max),
            float(range_min),
            np.asarray(X_base_sensor, dtype=float),
        )
        self._sense(*scan)
        self._resample_count += 1
        if self._resample_count % self.config.resample_interval == 0 and self._degenerate():
            self._resample()
        self._odom, self._force = odom.copy(), False
        self.updates += 1
        self._estimate = _estimate(self.particles, self.weights)
        if self._pyramid:
            self._refine(*scan)
        return True

    def estimate(self) -> tuple[np.ndarray, np.ndarray]:
        """Returns (pose [x, y, yaw], covariance (3, 3)): the heaviest cluster's weighted mean
        and the whole set's covariance (m, rad)."""
        pose, covariance = self._estimate
        return pose.copy(), covariance.copy()

    # The steps of an update.

    def _restart(self, particles: np.ndarray, odom_pose) -> None:
        self.particles = particles
        self.weights = np.full(len(particles), 1.0 / len(particles))
        self._odom = None if odom_pose is None else np.asarray(odom_pose, float).reshape(3).copy()
        self._force = True
        self._resample_count = 0
        self._w_slow = self._w_fast = 0.0
        self._estimate = _estimate(self.particles, self.weights)

    def _move(self, old, new) -> None:
        """sample_motion_model_odometry, ROS's diff-corrected model."""
        c = self.config
        dx, dy = new[0] - old[0], new[1] - old[1]
        trans = math.hypot(dx, dy)
        rot1 = 0.0 if trans < 0.01 else float(wrap(math.atan2(dy, dx) - old[2]))
        rot2 = float(wrap(new[2] - old[2] - rot1))
        # Backwards motion is a small turn, not a half turn, in the noise model.
        rot1_noise = min(abs(rot1), abs(float(wrap(rot1 - math.pi))))
        rot2_noise = min(abs(rot2), abs(float(wrap(rot2 - math.pi))))
        n = len(self.particles)
        noise = self._rng.standard_normal((3, n))
        rot1_hat = rot1 - noise[0] * math.sqrt(
            c.odom_alpha1 * rot1_noise**2 + c.odom_alpha2 * trans**2
        )
        trans_hat = trans - noise[1] * math.sqrt(
            c.odom_alpha3 * trans**2 + c.odom_alpha4 * (rot1_noise**2 + rot2_noise**2)
        )
        rot2_hat = rot2 - noise[2] * math.sqrt(
            c.odom_alpha1 * rot2_noise**2 + c.odom_alpha2 * trans**2
        )
        p = self.particles
        heading = p[:, 2] + rot1_hat
        p[:, 0] += trans_hat * np.cos(heading)
        p[:, 1] += trans_hat * np.sin(heading)
        p[:, 2] = wrap(heading + rot2_hat)

    def _sense(self, ranges, angles, range_max, range_min, sensor) -> None:
        """Likelihood-field sensor model; reweights the particles, updates w_slow and w_fast."""
        c = self.config
        if c.laser_max_range > 0:
            range_max = min(range_max, c.laser_max_range)
        if c.laser_min_range > 0:
            range_min = max(range_min, c.laser_min_range)
        beams = np.unique(np.linspace(0, len(ranges) - 1, c.laser_max_beams).round().astype(int))
        r, a = ranges[beams], angles[beams]
        ok = np.isfinite(r) & (r < range_max) & (r > range_min)
        r, a = r[ok], a[ok]
        if r.size == 0:
            return
        # Beam end points in the base frame.
        bx = sensor[0] + r * np.cos(sensor[2] + a)
        by = sensor[1] + r * np.sin(sensor[2] + a)
        table, resolution = self._field
        likelihood = _scan_likelihood(
            self.particles,
            bx,
            by,
            table,
            self.map.origin,
            resolution,
            self.map.shape,
            c.laser_z_hit,
            c.laser_z_rand / range_max,
        )
        weighted = self.weights * likelihood
        w_avg = float(np.sum(weighted))  # the scan's expected likelihood
        self.weights = weighted / w_avg
        if self._w_slow == 0.0:
            self._w_slow = self._w_fast = w_avg
        else:
            self._w_slow += c.recovery_alpha_slow * (w_avg - self._w_slow)
            self._w_fast += c.recovery_alpha_fast * (w_avg - self._w_fast)

    def _refine(self, ranges, angles, range_max, range_min, sensor) -> None:
        """Scan-to-map refinement (ours, not ROS's): matches the scan's end points against
        the map from the filter's estimate and, if the match is good, takes it as the
        estimate (and moves the particles with it when ``refinement_shift_particles``)."""
        c = self.config
        if c.laser_max_range > 0:
            range_max = min(range_max, c.laser_max_range)
        if c.laser_min_range > 0:
            range_min = max(range_min, c.laser_min_range)
        hit = np.isfinite(ranges) & (ranges < range_max) & (ranges > range_min)
        if hit.sum() < c.refinement_min_points:
            self.refinements[1] += 1
            return
        r, a = ranges[hit], angles[hit]
        if len(r) > c.refinement_max_beams:  # evenly spread
            keep = np.unique(np.linspace(0, len(r) - 1, c.refinement_max_beams).round())
            r, a = r[keep.astype(int)], a[keep.astype(int)]
        points = np.stack(
            [sensor[0] + r * np.cos(sensor[2] + a), sensor[1] + r * np.sin(sensor[2] + a)], -1
        )
        pose, covariance = self._estimate
        start = _relative(self.map.origin, pose)  # matching runs in the map's own frame
        result = match_scan(self._pyramid, points, start, iterations=c.refinement_iterations)
        self.last_match = result
        refined = result.pose
        values, vectors = normal_spread(points)
        if not (values[1] > 0 and values[0] >= c.refinement_degenerate_ratio * values[1]):
            # Surfaces all facing one way (a corridor): keep the filter's position along them.
            along = transform_points((0.0, 0.0, refined[2]), vectors[:, 0][None, :])[0]
            refined = refined.copy()
            refined[:2] -= along * (along @ (refined[:2] - start[:2]))
        offset = _relative(start, refined)
        if (
            math.hypot(offset[0], offset[1]) > c.refinement_max_correction
            or abs(offset[2]) > c.refinement_max_correction_a
            or result.scores[0] < c.refinement_min_score
            or not _converged(self._pyramid[0], points, result.pose, c.refinement_tolerance)
        ):
            self.refinements[1] += 1
            return
        self.refinements[0] += 1
        new_pose = _compose(self.map.origin, refined)
        if c.refinement_shift_particles:
            # The rigid motion taking the old estimate to the new one, applied to every particle.
            moved = _relative(pose, self.particles.T).T
            self.particles = _compose(new_pose, moved.T).T
        self._estimate = (new_pose, covariance)

    def _degenerate(self) -> bool:
        """True unless selective resampling finds the effective sample size large enough (and
        no recovery is due: a kidnapped robot's particles are all equally bad)."""
        if not self.config.selective_resampling or self._injection() > 0:
            return True
        return 1.0 / float(np.sum(self.weights**2)) < 0.5 * len(self.weights)

    def _injection(self) -> float:
        """Probability that a new particle is a random one: max(0, 1 - w_fast / w_slow)."""
        return max(0.0, 1.0 - self._w_fast / self._w_slow) if self._w_slow > 0 else 0.0

    def _resample(self) -> None:
        """KLD-sized low-variance resampling with random particles for recovery."""
        c = self.config
        inject = self._injection()
        m = c.max_particles
        cumulative = np.cumsum(self.weights)
        cumulative[-1] = 1.0
        start = self._rng.random() / m
        chosen = np.searchsorted(cumulative, start + np.arange(m) / m, side="right")
        chosen = np.minimum(chosen, len(self.weights) - 1)[self._rng.permutation(m)]
        new = self.particles[chosen]
        if inject > 0:
            random = self._rng.random(m) < inject
            new[random] = self._random_poses(int(random.sum()))
        n = _kld_count(new, c)
        self.particles = new[:n].copy()
        self.weights = np.full(n, 1.0 / n)
        if inject > 0:
            self._w_slow = self._w_fast = 0.0  # as ROS: start the averages again

    def _random_poses(self, count: int) -> np.ndarray:
        """``count`` poses uniform over the map's free cells (and in yaw)."""
        if len(self._free_cells) == 0:
            raise ConfigError("AMCL: the map has no free cells to put particles in")
        cells = self._free_cells[self._rng.integers(len(self._free_cells), size=count)]
        local = (cells + self._rng.random((count, 2))) * self.map.resolution
        x0, y0, yaw0 = self.map.origin
        c0, s0 = math.cos(yaw0), math.sin(yaw0)
        x = x0 + c0 * local[:, 0] - s0 * local[:, 1]
        y = y0 + s0 * local[:, 0] + c0 * local[:, 1]
        yaw = self._rng.uniform(-math.pi, math.pi, count)
        return np.stack([x, y, yaw], -1)


def kld_limit(k, config: "AmclConfig") -> np.ndarray:
    """The KLD bound (Fox 2003, ROS's ``pf_resample_limit``): particles needed when the set
    occupies ``k`` histogram bins, clipped to [min_particles, max_particles]."""
    k = np.asarray(k, dtype=float)
    km1 = np.maximum(k - 1.0, 1.0)
    b = 2.0 / (9.0 * km1)
    n = np.ceil(km1 / (2.0 * config.kld_err) * (1.0 - b + np.sqrt(b) * config.kld_z) ** 3)
    n = np.where(k <= 1, config.max_particles, n)
    return np.clip(n, config.min_particles, config.max_particles).astype(np.int64)


def _kld_count(poses: np.ndarray, config: "AmclConfig") -> int:
    """How many of ``poses`` (in order) KLD sampling keeps: the first count that exceeds the
    bound for the bins its poses occupy (ROS's resampling loop), at least min_particles."""
    keys = _bin_keys(poses)
    flat = (keys[:, 0] * 1_000_003 + keys[:, 1]) * (_YAW_BINS + 1) + keys[:, 2]
    _, first = np.unique(flat, return_index=True)
    new_bin = np.zeros(len(poses), dtype=bool)
    new_bin[first] = True
    counts = np.arange(1, len(poses) + 1)
    over = counts > kld_limit(np.cumsum(new_bin), config)
    n = int(np.argmax(over)) + 1 if over.any() else len(poses)
    return max(n, min(config.min_particles, len(poses)))


def _bin_keys(poses: np.ndarray) -> np.ndarray:
    """(n, 3) integer histogram bins of poses: x, y in BIN_XY, yaw in BIN_YAW from -pi."""
    ix = np.floor(poses[:, 0] / BIN_XY)
    iy = np.floor(poses[:, 1] / BIN_XY)
    ia = np.clip(np.floor((wrap(poses[:, 2]) + math.pi) / BIN_YAW), 0, _YAW_BINS - 1)
    return np.stack([ix, iy, ia], -1).astype(np.int64)


def _estimate(particles: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """ROS's estimate: the heaviest cluster's mean, the whole set's covariance."""
    labels = _clusters(particles)
    totals = np.bincount(labels, weights=weights)
    best = labels == int(np.argmax(totals))
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


def _clusters(particles: np.ndarray) -> np.ndarray:
    """Labels (n,) of clusters: particles in the same or neighbouring histogram bins (26
    neighbours, yaw wrapping round) share a label."""
    keys = _bin_keys(particles)
    keys[:, :2] -= keys[:, :2].min(axis=0)
    shape = (*(keys[:, :2].max(axis=0) + 1), _YAW_BINS + 1)
    grid = np.zeros(shape, dtype=bool)
    grid[keys[:, 0], keys[:, 1], keys[:, 2]] = True
    grid[..., _YAW_BINS] = grid[..., 0]  # a copy of the first yaw bin after the last
    labels, count = ndimage.label(grid, structure=np.ones((3, 3, 3), dtype=bool))
    a, b = labels[..., 0].ravel(), labels[..., _YAW_BINS].ravel()
    same = (a > 0) & (b > 0)
    graph = coo_matrix((np.ones(int(same.sum())), (a[same], b[same])), shape=(count + 1,) * 2)
    _, merged = connected_components(graph, directed=False)
    return merged[labels[keys[:, 0], keys[:, 1], keys[:, 2]]]


@numba.njit(cache=True)
def _scan_likelihood(particles, bx, by, table, origin, resolution, shape, z_hit, z_rand_term):
    """ROS's likelihood-field weight ``1 + sum(pz^3)`` of each particle (n,) for beam end
    points (bx, by) in the base frame (m); ``table`` from ``_likelihood_table``."""
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


def _likelihood_table(occupancy_map: OccupancyMap, config: "AmclConfig"):
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


def _match_pyramid(occupancy_map: OccupancyMap, config: "AmclConfig") -> list[MatchMap]:
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
            _field_level(surface, seen, occupancy_map.resolution / n, n * config.refinement_field)
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
            _field_level(occ, seen, occupancy_map.resolution * block, config.refinement_field)
        )
    return levels


def _field_level(occupied, seen, resolution, width) -> MatchMap:
    """A ``MatchMap`` of exp(-d^2 / (2 width^2)), d (cells) to the nearest occupied cell."""
    if occupied.any():
        distance = ndimage.distance_transform_edt(~occupied)
        values = np.exp(-0.5 * (distance / width) ** 2)
    else:
        values = np.zeros(occupied.shape)
    return MatchMap(values, resolution, (0.0, 0.0), seen)


def _converged(match_map: MatchMap, points, pose, tolerance: float) -> bool:
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


def _compose(a, b) -> np.ndarray:
    """Pose(s) ``b`` (3,) or (3, n), given in the frame of pose ``a`` (3,), in a's parent."""
    b = np.asarray(b, dtype=float)
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.stack([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap(a[2] + b[2])], 0)


def _relative(a, b) -> np.ndarray:
    """Pose(s) ``b`` (3,) or (3, n) expressed in the frame of pose ``a`` (3,)."""
    b = np.asarray(b, dtype=float)
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return np.stack([c * dx + s * dy, -s * dx + c * dy, wrap(b[2] - a[2])], 0)


def _check_pose(pose, covariance) -> tuple[np.ndarray, np.ndarray]:
    pose = np.asarray(pose, dtype=float)
    covariance = np.asarray(covariance, dtype=float)
    if pose.shape != (3,) or not np.all(np.isfinite(pose)):
        raise ConfigError(f"initial pose: expected 3 finite numbers [x, y, yaw], got {pose}")
    if covariance.shape != (3, 3) or not np.all(np.isfinite(covariance)):
        raise ConfigError(f"initial covariance: expected a finite 3x3 matrix, got {covariance}")
    if not np.allclose(covariance, covariance.T, atol=1e-12):
        raise ConfigError("initial covariance: must be symmetric")
    if np.linalg.eigvalsh(covariance).min() < -1e-12:
        raise ConfigError("initial covariance: must be positive semi-definite")
    return pose, covariance
