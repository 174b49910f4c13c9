"""The parameters of AMCL (``AmclConfig``: the ROS ``amcl`` node's names, meanings and defaults,
plus our ``refinement_*`` keys), their checks and their loader; the shipped values are in
``config/amcl.yaml``.

They stand apart from both users: the particle filter (``particle_filter``, the algorithm) and
the Drake system that runs it (``amcl``), so that the algorithm never imports the system.
"""

import dataclasses as dc
import math
from pathlib import Path

import numpy as np

from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir

ODOM_MODELS = ("diff-corrected", "diff", "omni-corrected", "omni")
"""ROS amcl's odometry models (``odom_model_type``)."""


@dc.dataclass
class AmclConfig:
    """Parameters of the ROS ``amcl`` node (names and defaults are ROS's; the values used
    here are in ``config/amcl.yaml``)."""

    min_particles: int = 100  # Fewest particles, >= 1.
    max_particles: int = 5000  # Most particles, >= min_particles.
    # Ours: a global spread (global localisation) puts this many particles per m^2 of free
    # space (at least max_particles): a large map needs more to put some near the truth, as
    # KLD sampling's bound grows with the bins a uniform spread covers. The first update
    # weighs them all and resamples max_particles. >= 0; 0: max_particles, as ROS.
    global_localization_density: float = 0.0
    kld_err: float = 0.01  # KLD bound on the error of the sampled distribution, > 0.
    kld_z: float = 0.99  # Upper standard normal quantile of the KLD bound, > 0.
    update_min_d: float = 0.2  # m moved before a filter update, >= 0.
    update_min_a: float = math.pi / 6  # rad turned before a filter update, >= 0.
    resample_interval: int = 2  # Filter updates per resampling, >= 1.
    # Resample only when the effective sample size 1 / sum(w^2) falls below half the count.
    selective_resampling: bool = False
    recovery_alpha_slow: float = 0.0  # Rate of the slow likelihood average, [0, 1]; 0: off.
    recovery_alpha_fast: float = 0.0  # Rate of the fast average, [0, 1], > slow when on.
    initial_pose_x: float = 0.0  # m, the initial pose's mean in the map frame.
    initial_pose_y: float = 0.0  # m.
    initial_pose_a: float = 0.0  # rad.
    initial_cov_xx: float = 0.5 * 0.5  # m^2, the initial pose's variance in x, >= 0.
    initial_cov_yy: float = 0.5 * 0.5  # m^2.
    initial_cov_aa: float = (math.pi / 12) ** 2  # rad^2.
    laser_min_range: float = -1.0  # m; <= 0: the scan's range_min.
    laser_max_range: float = -1.0  # m; <= 0: the scan's range_max.
    laser_max_beams: int = 30  # Beams of each scan used, >= 2.
    laser_z_hit: float = 0.95  # Weight of the hit (Gaussian) part, >= 0.
    laser_z_rand: float = 0.05  # Weight of the random part, >= 0; z_hit + z_rand > 0.
    laser_sigma_hit: float = 0.2  # m, std dev of the hit part, > 0.
    laser_likelihood_max_dist: float = 2.0  # m, cap of the distance field, > 0.
    laser_model_type: str = "likelihood_field"  # The only model implemented.
    # Ours, not ROS's (whose likelihood field skips them): also score the beams that saw
    # nothing, by tracing each ray through the map (a hit when it runs free to the maximum
    # range); the evidence that makes global localisation work in large open spaces.
    laser_no_return_beams: bool = False
    # Ours: when fewer than this many of the beams used hit something, trace their rays
    # through the map too; a wall a ray enters short of its end point scores as that shortfall
    # (``likelihood_field.traced_hit_likelihood``). 0: never, as ROS.
    laser_trace_hits_below: int = 0
    # ROS's odometry models: diff-corrected, diff (ROS 1's original: the alphas' mix used as a
    # standard deviation, not a variance), omni-corrected, omni (holonomic: alpha5 strafes).
    odom_model_type: str = "diff-corrected"
    odom_alpha1: float = 0.2  # Rotation noise from rotation, >= 0.
    odom_alpha2: float = 0.2  # Rotation noise from translation, >= 0.
    odom_alpha3: float = 0.2  # Translation noise from translation, >= 0.
    odom_alpha4: float = 0.2  # Translation noise from rotation, >= 0.
    odom_alpha5: float = 0.2  # Strafe noise from translation (omni models only), >= 0.
    # Scan-to-map refinement (ours, not a ROS parameter): after each filter update, match the
    # scan (every beam in range) against the map from the estimate (``scan_matcher``) and take
    # the match as the estimate when it converged, moved less than the gate and scores well.
    scan_match_refinement: bool = False
    refinement_max_correction: float = 0.15  # m, the gate on the position correction, > 0.
    refinement_max_correction_a: float = math.radians(5.0)  # rad, the gate on yaw, > 0.
    refinement_min_score: float = 0.5  # Least mean field value of the end points, [0, 1].
    refinement_min_points: int = 20  # Fewest beams in range to match, >= 3.
    refinement_max_beams: int = 180  # Most beams matched (evenly spread over those in range).
    refinement_levels: int = 1  # Pyramid levels, cells of map resolution * 2^k, >= 1.
    # A finer first level, cells of the map's resolution / this, peaked on obstacles' faces
    # (see ``particle_filter._match_pyramid``), >= 1; 1: none.
    refinement_subdivision: int = 4
    refinement_iterations: int = 3  # Gauss-Newton steps per level, >= 1.
    refinement_field: float = 1.0  # Cells, width of the likelihood field matched on, > 0.
    refinement_tolerance: float = 0.005  # m and rad: converged if one more step is smaller.
    # Along surfaces that all face one way (normal spread ratio below this), keep the filter's
    # position (``scan_matcher.normal_spread``), [0, 1].
    refinement_degenerate_ratio: float = 0.05
    refinement_shift_particles: bool = True  # Move the particles with the correction too.
    # With the refinement on: while scans have no beam in range at all (open floor), the
    # estimate is the last matched pose carried by the odometry since (``particle_filter``).
    refinement_blind_odometry: bool = True

    def initial_pose(self) -> np.ndarray:
        """Returns [x, y, yaw] (m, m, rad) of the configured initial pose."""
        return np.array([self.initial_pose_x, self.initial_pose_y, self.initial_pose_a])

    def initial_covariance(self) -> np.ndarray:
        """Returns the configured initial covariance, diagonal 3x3 (m^2, m^2, rad^2)."""
        return np.diag([self.initial_cov_xx, self.initial_cov_yy, self.initial_cov_aa])


def check_amcl_config(
    config: AmclConfig, where: str = "AmclConfig", prefix: str = ""
) -> AmclConfig:
    """Returns ``config`` if its values are in range; raises ``ConfigError`` naming ``where``
    and the first bad key, as ``prefix`` + key (e.g. ``prefix="amcl."`` in a scenario file)."""

    def fail(key, rule):
        value = getattr(config, key)
        raise ConfigError(f"{where}: '{prefix}{key}' must be {rule}, got {value!r}")

    for field in dc.fields(config):
        value = getattr(config, field.name)
        if isinstance(value, float) and not math.isfinite(value):
            fail(field.name, "finite")
    if config.global_localization_density < 0:
        fail("global_localization_density", "non-negative")
    if config.min_particles < 1:
        fail("min_particles", "at least 1")
    if config.max_particles < config.min_particles:
        fail("max_particles", f"at least min_particles ({config.min_particles})")
    for key in ("kld_err", "kld_z", "laser_sigma_hit", "laser_likelihood_max_dist"):
        if not getattr(config, key) > 0:
            fail(key, "positive")
    for key in ("update_min_d", "update_min_a", "laser_z_hit", "laser_z_rand"):
        if getattr(config, key) < 0:
            fail(key, "non-negative")
    for key in ("initial_cov_xx", "initial_cov_yy", "initial_cov_aa"):
        if getattr(config, key) < 0:
            fail(key, "non-negative")
    for key in ("odom_alpha1", "odom_alpha2", "odom_alpha3", "odom_alpha4", "odom_alpha5"):
        if getattr(config, key) < 0:
            fail(key, "non-negative")
    if config.laser_z_hit + config.laser_z_rand <= 0:
        fail("laser_z_rand", "positive when laser_z_hit is 0")
    if config.resample_interval < 1:
        fail("resample_interval", "at least 1")
    if config.laser_max_beams < 2:
        fail("laser_max_beams", "at least 2")
    if config.laser_trace_hits_below < 0:
        fail("laser_trace_hits_below", "at least 0")
    for key in ("recovery_alpha_slow", "recovery_alpha_fast"):
        if not 0.0 <= getattr(config, key) <= 1.0:
            fail(key, "in [0, 1]")
    if config.recovery_alpha_slow > 0 and config.recovery_alpha_fast <= config.recovery_alpha_slow:
        fail("recovery_alpha_fast", "above recovery_alpha_slow (or both 0)")
    if 0 < config.laser_max_range <= config.laser_min_range:
        fail("laser_max_range", "above laser_min_range (or <= 0: the scan's)")
    for key in (
        "refinement_max_correction",
        "refinement_max_correction_a",
        "refinement_field",
        "refinement_tolerance",
    ):
        if not getattr(config, key) > 0:
            fail(key, "positive")
    for key in ("refinement_min_score", "refinement_degenerate_ratio"):
        if not 0.0 <= getattr(config, key) <= 1.0:
            fail(key, "in [0, 1]")
    if config.refinement_max_beams < config.refinement_min_points:
        fail(
            "refinement_max_beams",
            f"at least refinement_min_points ({config.refinement_min_points})",
        )
    if config.refinement_min_points < 3:
        fail("refinement_min_points", "at least 3")
    for key in ("refinement_levels", "refinement_iterations", "refinement_subdivision"):
        if getattr(config, key) < 1:
            fail(key, "at least 1")
    if config.laser_model_type != "likelihood_field":
        fail("laser_model_type", "'likelihood_field' (the only model implemented)")
    if config.odom_model_type not in ODOM_MODELS:
        fail("odom_model_type", f"one of {', '.join(ODOM_MODELS)}")
    return config


def check_pose_covariance(pose, covariance) -> tuple[np.ndarray, np.ndarray]:
    """Returns (pose (3,), covariance (3, 3)) as arrays; ``ConfigError`` unless both are finite
    and the covariance symmetric positive semi-definite."""
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


def load_amcl_config(path: Path | str) -> AmclConfig:
    """Loads and checks an ``AmclConfig`` YAML file (missing keys keep ROS's defaults).

    Raises:
        ConfigError: one line naming the file and the key.
    """
    return check_amcl_config(load_typed(AmclConfig, filename=path), str(path))


def default_amcl_config_file() -> Path:
    """Returns the shipped ``config/amcl.yaml``."""
    return config_dir() / "amcl.yaml"
