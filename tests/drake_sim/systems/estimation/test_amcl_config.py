"""drake_sim.systems.estimation.amcl_config: ROS's defaults, the shipped file, and one
ConfigError naming the file (or the scenario's section) and the key for each bad value."""

import dataclasses as dc
import math
import re

import numpy as np
import pytest

import drake_sim.systems.estimation.amcl_config as mut
from drake_sim.base.errors import ConfigError


@pytest.mark.parametrize(
    "key, value, words",
    [
        ("min_particles", 0, "at least 1"),
        ("max_particles", 50, "at least min_particles"),
        ("kld_err", 0.0, "positive"),
        ("update_min_d", -0.1, "non-negative"),
        ("resample_interval", 0, "at least 1"),
        ("recovery_alpha_fast", 1.5, "in [0, 1]"),
        ("laser_sigma_hit", float("nan"), "finite"),
        ("laser_max_beams", 1, "at least 2"),
        ("odom_alpha3", -1.0, "non-negative"),
        ("odom_model_type", "tricycle", "one of diff-corrected, diff, omni-corrected, omni"),
        ("odom_alpha5", -0.1, "non-negative"),
        ("laser_model_type", "beam", "likelihood_field"),
        ("refinement_max_correction", 0.0, "positive"),
        ("refinement_max_correction_a", -0.1, "positive"),
        ("refinement_field", 0.0, "positive"),
        ("refinement_tolerance", float("inf"), "finite"),
        ("refinement_min_score", 1.5, "in [0, 1]"),
        ("refinement_degenerate_ratio", -0.1, "in [0, 1]"),
        ("refinement_min_points", 2, "at least 3"),
        ("laser_trace_hits_below", -1, "at least 0"),
        ("refinement_levels", 0, "at least 1"),
        ("refinement_iterations", 0, "at least 1"),
        ("global_localization_density", -1.0, "non-negative"),
        ("global_localization_density", float("inf"), "finite"),
    ],
)
def test_bad_values_name_the_key(key, value, words):
    bad = dc.replace(mut.AmclConfig(), **{key: value})
    with pytest.raises(ConfigError, match=rf"^amcl.yaml: '{key}' must be .*{re.escape(words)}"):
        mut.check_amcl_config(bad, "amcl.yaml")
    with pytest.raises(ConfigError, match=rf"^nav.yaml: 'amcl.{key}' must be "):
        mut.check_amcl_config(bad, "nav.yaml", prefix="amcl.")


@pytest.mark.parametrize(
    "text, words",
    [
        ("min_particles: 100\nodom_alpha6: 0.2\n", "unknown key 'odom_alpha6'"),
        ("kld_err: .nan\n", "'kld_err' must be finite"),
        ("laser_max_beams: [1\n", "malformed YAML"),
        ("update_min_a: -1\n", "'update_min_a' must be non-negative"),
        ("max_particles: many\n", "'max_particles' must be a number"),
    ],
)
def test_bad_files_are_one_config_error_naming_file_and_key(tmp_path, text, words):
    path = tmp_path / "amcl.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=str(path)) as error:
        mut.load_amcl_config(path)
    assert words in str(error.value) and "\n" not in str(error.value)


def test_defaults_are_ros_amcl_and_the_shipped_file_loads():
    shipped = mut.load_amcl_config(mut.default_amcl_config_file())
    ros = mut.AmclConfig()
    assert (ros.min_particles, ros.max_particles, ros.kld_err, ros.kld_z) == (100, 5000, 0.01, 0.99)
    assert (ros.update_min_d, ros.update_min_a, ros.resample_interval) == (0.2, math.pi / 6, 2)
    assert (ros.laser_max_beams, ros.laser_z_hit, ros.laser_z_rand) == (30, 0.95, 0.05)
    assert (ros.laser_sigma_hit, ros.laser_likelihood_max_dist) == (0.2, 2.0)
    assert ros.odom_alpha1 == ros.odom_alpha4 == 0.2 and ros.recovery_alpha_slow == 0.0
    assert shipped.max_particles == 8000 and shipped.laser_max_beams == 90
    # The scan-to-map refinement is ours: off by default (ROS's filter), on in the shipped file.
    assert not ros.scan_match_refinement and shipped.scan_match_refinement
    # So are the beams that saw nothing and the density of a global spread: ROS's by default.
    assert not ros.laser_no_return_beams and shipped.laser_no_return_beams
    assert ros.laser_trace_hits_below == 0 < shipped.laser_trace_hits_below
    assert ros.global_localization_density == 0.0 < shipped.global_localization_density
    np.testing.assert_allclose(np.diag(shipped.initial_covariance()), [0.25, 0.25, 0.2742])


def test_check_pose_covariance_takes_finite_poses_and_psd_covariances():
    pose, covariance = mut.check_pose_covariance([1, 2, 0.5], np.eye(3) * 0.1)
    assert pose.dtype == float and pose.shape == (3,) and covariance.shape == (3, 3)
    for bad, words in [
        (([math.nan, 0, 0], np.eye(3)), "3 finite numbers"),
        (([0, 0, 0], np.ones((2, 2))), "finite 3x3"),
        (([0, 0, 0], np.triu(np.ones((3, 3)))), "symmetric"),
        (([0, 0, 0], -np.eye(3)), "positive semi-definite"),
    ]:
        with pytest.raises(ConfigError, match=words):
            mut.check_pose_covariance(*bad)
