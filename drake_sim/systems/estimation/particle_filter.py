"""Adaptive Monte Carlo localisation on a known map: the particle filter of ROS's ``amcl``.

Its parameters (``AmclConfig``, ROS's names) are in ``drake_sim.systems.estimation.amcl_config``;
``drake_sim.systems.estimation.amcl`` runs it as a Drake system. This module holds the filter
and its update steps; the odometry motion model is in ``motion_model``, the sensor model's
likelihood field in ``likelihood_field``, the pose histogram (KLD sampling, the clustered
estimate) in ``pose_histogram`` and the scan-to-map refinement in ``map_refinement``.

The algorithm of Probabilistic Robotics (Thrun, Burgard, Fox 2005) as the ROS ``amcl`` node
runs it, vectorised with numpy (no Python loop over particles or beams; the likelihood field's
loop over particles x beams is one compiled numba kernel, cached on disk):

* motion: ``sample_motion_model_odometry`` (Table 5.6) with ROS's ``odom_model_type``
  variants (``motion_model``);
* sensor: the likelihood field (Table 6.3): a beam's end point at distance ``d`` from the
  nearest occupied cell scores ``pz = z_hit * exp(-d^2 / (2 sigma_hit^2)) + z_rand /
  range_max`` (the Gaussian unnormalised, as in ROS); ``laser_max_beams`` beams evenly spread
  over the scan, beams at or beyond the maximum range (or ``inf``, or below the minimum) are
  skipped; a particle's weight is multiplied by ``1 + sum(pz^3)`` (ROS's combination, which
  is less overconfident than the product). ``d`` comes from a Euclidean distance transform of
  the map's occupied cells, computed once and capped at ``laser_likelihood_max_dist``; points
  off the map take that cap. With ``laser_no_return_beams`` (ours) the beams that saw nothing
  count too (``likelihood_field.no_return_factor``): a 3.5 m lidar in a 30 m hall sees almost
  nothing, and "no wall within range here" is then most of what the scan says. With fewer than
  ``laser_trace_hits_below`` hits (ours) their rays are traced as well
  (``likelihood_field.traced_hit_likelihood``): an end point behind a face then scores as one
  as far in front of it, where the field alone pulls the estimate towards the few things in
  view (nav2's depot, a 2.3 m drive with exact odometry: 0.15 m towards them, about 0.01 m
  traced; the few cm left lie across, where position and yaw trade off); a scan with more
  hits is not traced (16 to 33 times the cost per beam; it pins the estimate anyway);
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
  from the map, ``map_refinement.match_pyramid``). The match becomes the estimate if it
  converged (one more step moves less than ``refinement_tolerance``), moved less than the gate
  (``refinement_max_correction`` m, ``refinement_max_correction_a`` rad) and its end points
  score at least ``refinement_min_score`` on the finest level; along a corridor (the scan's
  normals all one way, ``scan_matcher.normal_spread``) the filter's position along it stays.
  With ``refinement_shift_particles`` the whole set then moves rigidly by the correction
  (about the old estimate), which keeps its spread, weights and covariance and lets the next
  update start from the refined pose; without it, the particles stay where the filter put
  them and a rejected match leaves the filter's bias (measured in the warehouse, navigation to
  10 goals: worst goal 2.1 cm with the shift, 2.6 to 5.3 cm without). Where a scan has no
  beam in range at all (open floor, nothing within the lidar's reach), the filter has only the
  no-return beams, which cut its wide cloud on one side and so move its mean though not the
  truth (nav2's warehouse: 0.24 m off at a goal where the wheel odometry alone was 2.5 cm off).
  With ``refinement_blind_odometry`` the estimate is then the last matched pose carried by the
  odometry since; a scan with a few returns (too few to match) gives the filter's own estimate
  again, and a rejected match ends the carrying. The particles stay the filter's (moved with
  the carried pose they were no better: after 7.5 m of blind travel in nav2's warehouse the
  first matches settled 6.5 cm off). Goals across open floor still end 1 to 7 cm off in single
  runs, which goal the worst changing with small changes here (docs/navigation.md).

Global localisation on a large map (ours): ``global_localization_density`` particles per m^2
of free space (nav2's depot: 90,000), weighed by the first update and resampled to
``max_particles``; ``localized`` tells when the cloud has settled. Measured in the depot and
the warehouse: it converges once the robot has seen enough structure, but a wrong pose among
repeated shelves can win (recovery cannot help: it fits as well as the truth).

Deliberate differences from ROS: the update threshold ``update_min_d`` applies to the distance
moved (ROS compares |dx| and |dy| separately); ``w_avg`` is the expected likelihood of the scan
(Probabilistic Robotics; ROS divides it by the particle count as well); global localisation
draws positions uniformly inside free cells (ROS uses the cells' centres); with
``selective_resampling``, a resampling also runs when recovery is due (a kidnapped robot's
particles are all equally bad, so the effective sample size alone would never resample). As in
ROS, ``kld_z`` is used as the normal quantile itself.

Cost (``benchmarks/amcl_benchmark.py``, 2 cores): 1.2 to 1.9 ms median per update with 2000
particles and 60 beams, plus about 1.5 ms for the refinement (180 beams).
"""

import math

import numpy as np

from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.planar import compose, relative_pose, wrap_angle
from drake_sim.systems.estimation.amcl_config import AmclConfig, check_pose_covariance
from drake_sim.systems.estimation.likelihood_field import (
    distance_table,
    likelihood_table,
    no_return_factor,
    scan_likelihood,
    traced_hit_likelihood,
)
from drake_sim.systems.estimation.map_refinement import in_range, match_pyramid, refine_pose
from drake_sim.systems.estimation.motion_model import sample_motion
from drake_sim.systems.estimation.pose_histogram import (
    LOCALIZED_SHARE,
    LOCALIZED_STD,
    cluster_estimate,
    kld_count,
    settled,
)
from drake_sim.systems.estimation.scan_matcher import MatchResult


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

    def __init__(self, occupancy_map: OccupancyMap, config: AmclConfig, seed=0):
        self.config = config
        self.map = occupancy_map
        self._rng = np.random.default_rng(seed)
        self._distance = distance_table(occupancy_map, config.laser_likelihood_max_dist)
        self._field = likelihood_table(occupancy_map, self.config, self._distance)
        self._pyramid = match_pyramid(occupancy_map, config) if config.scan_match_refinement else []
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
        pose, covariance = check_pose_covariance(pose, covariance)
        n = self.config.max_particles
        particles = self._rng.multivariate_normal(pose, covariance, size=n, method="eigh")
        particles[:, 2] = wrap_angle(particles[:, 2])
        self._restart(particles, odom_pose)

    def global_localization(self) -> None:
        """Starts again from poses uniform over the map's free space (ROS's
        ``global_localization`` service): ``global_localization_density`` per m^2 of it (at
        least ``max_particles``), which the next update (it always runs) weighs and resamples
        down to ``max_particles``."""
        area = len(self._free_cells) * self.map.resolution**2
        count = max(int(self.config.global_localization_density * area), self.config.max_particles)
        self._restart(self._random_poses(count), None)

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
            turned = abs(float(wrap_angle(delta[2]))) >= self.config.update_min_a
            if not (self._force or moved or turned):
                return False
            sample_motion(self.particles, self._odom, odom, self.config, self._rng)
        scan = (
            np.asarray(ranges, dtype=float),
            np.asarray(angles, dtype=float),
            float(range_max),
            float(range_min),
            np.asarray(X_base_sensor, dtype=float),
        )
        self._sense(*scan)
        self._resample_count += 1
        crowded = len(self.particles) > self.config.max_particles  # a global spread
        if crowded or (
            self._resample_count % self.config.resample_interval == 0 and self._degenerate()
        ):
            self._resample()
        self._odom, self._force = odom.copy(), False
        self.updates += 1
        self._estimate = cluster_estimate(self.particles, self.weights)
        if self._pyramid:
            self._refine(odom, *scan)
        return True

    def estimate(self) -> tuple[np.ndarray, np.ndarray]:
        """Returns (pose [x, y, yaw], covariance (3, 3)): the heaviest cluster's weighted mean
        and the whole set's covariance (m, rad)."""
        pose, covariance = self._estimate
        return pose.copy(), covariance.copy()

    def localized(self, *, share=LOCALIZED_SHARE, std=LOCALIZED_STD) -> bool:
        """Whether the filter has settled on one pose (``pose_histogram.settled``: the heaviest
        cluster holds ``share`` of the weight, its positions within ``std`` m): what a global
        localisation waits for before driving off, as nav2 users watch the cloud shrink while
        the robot spins. It cannot tell a wrong pose from the right one where the map repeats."""
        return self.updates > 0 and settled(self.particles, self.weights, share, std)

    # The steps of an update.

    def _restart(self, particles: np.ndarray, odom_pose) -> None:
        self.particles = particles
        self.weights = np.full(len(particles), 1.0 / len(particles))
        self._odom = None if odom_pose is None else np.asarray(odom_pose, float).reshape(3).copy()
        self._force = True
        self._resample_count = 0
        self._w_slow = self._w_fast = 0.0
        self._estimate = cluster_estimate(self.particles, self.weights)
        self._fix = None  # (pose, odometry) of the last match; None after a rejected one

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
        none = ~(np.isfinite(r) & (r < range_max))
        if not c.laser_no_return_beams:
            none[:] = False
        a_none = a[none] + sensor[2]
        r, a = r[ok], a[ok]
        if not (len(r) or len(a_none)):
            return
        ux, uy = np.cos(sensor[2] + a), np.sin(sensor[2] + a)  # the hits' directions (base)
        table, resolution = self._field
        args = (self.map.origin, resolution, self.map.shape)
        z_rand_term = c.laser_z_rand / range_max
        if len(r) < c.laser_trace_hits_below:
            likelihood = traced_hit_likelihood(
                self.particles, sensor[:2], ux, uy, r, self._distance, *args,
                c.laser_sigma_hit, c.laser_z_hit, z_rand_term,
            )  # fmt: skip
        else:
            bx, by = sensor[0] + r * ux, sensor[1] + r * uy  # end points in the base frame
            likelihood = scan_likelihood(
                self.particles, bx, by, table, *args, c.laser_z_hit, z_rand_term
            )
        if len(a_none):
            likelihood *= no_return_factor(
                self.particles, a_none, sensor, self._distance, self.map, c, range_max
            )
        weighted = self.weights * likelihood
        w_avg = float(np.sum(weighted))  # the scan's expected likelihood
        self.weights = weighted / w_avg
        if self._w_slow == 0.0:
            self._w_slow = self._w_fast = w_avg
        else:
            self._w_slow += c.recovery_alpha_slow * (w_avg - self._w_slow)
            self._w_fast += c.recovery_alpha_fast * (w_avg - self._w_fast)

    def _refine(self, odom, *scan) -> None:
        """Scan-to-map refinement (ours, not ROS's): matches the scan's end points against
        the map from the filter's estimate and, if the match is good, takes it as the
        estimate (and moves the particles with it when ``refinement_shift_particles``); a scan
        with no beam in range carries the last match by the odometry (module docstring)."""
        pose, covariance = self._estimate
        match, new_pose = refine_pose(self._pyramid, self.config, self.map.origin, pose, *scan)
        if match is not None:
            self.last_match = match
        if new_pose is None:
            self.refinements[1] += 1
            if match is not None:
                self._fix = None
            elif (
                self._fix is not None
                and self.config.refinement_blind_odometry
                and not in_range(self.config, scan[0], scan[2], scan[3]).any()  # no beam
            ):
                fix_pose, fix_odom = self._fix  # the particles stay the filter's
                self._estimate = (compose(fix_pose, relative_pose(fix_odom, odom)), covariance)
            return
        self.refinements[0] += 1
        self._fix = (new_pose, odom.copy())
        if self.config.refinement_shift_particles:
            # The rigid motion taking the old estimate to the new one, applied to every particle.
            # Stored column-major, as it always was: the next estimate's sums run in that order.
            moved = relative_pose(pose, self.particles)
            self.particles = np.asfortranarray(compose(new_pose, moved))
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
        n = kld_count(new, c)
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
