"""drake_sim.systems.estimation.motion_model: AMCL's odometry motion models move particles by
the odometry's motion with the noise their alphas give."""

import math

import numpy as np

import drake_sim.systems.estimation.motion_model as mut
from drake_sim.base.planar import wrap_angle
from drake_sim.systems.estimation.amcl_config import AmclConfig

COUNT = 20000


def _moved(model: str, odom, **alpha) -> np.ndarray:
    """COUNT particles at (1, 0) facing +y after the odometry moved from the origin to
    ``odom``."""
    config = AmclConfig(odom_model_type=model, **alpha)
    particles = np.tile([1.0, 0.0, math.pi / 2], (COUNT, 1))
    mut.sample_motion(particles, np.zeros(3), np.asarray(odom, float), config, _rng())
    return particles


def _rng():
    return np.random.default_rng(3)


def test_diff_corrected_moves_with_the_odometry_noise_of_alpha():
    alpha = dict(odom_alpha1=0.01, odom_alpha2=0.02, odom_alpha3=0.04, odom_alpha4=0.0)
    p = _moved("diff-corrected", [1.0, 0.0, 0.0], **alpha)  # 1 m straight on
    along = p[:, 1]  # the particles face +y
    # The first turn's noise (sqrt(alpha2) * 1 m) bends the move: E[cos] = exp(-alpha2 / 2).
    np.testing.assert_allclose(along.mean(), math.exp(-0.01), atol=0.004)
    np.testing.assert_allclose(along.std(), math.sqrt(0.04), rtol=0.05)  # sqrt(alpha3) * 1 m
    # Rotation noise from translation, sqrt(alpha2) * 1 m, on each of the two turns.
    np.testing.assert_allclose(np.std(wrap_angle(p[:, 2] - math.pi / 2)), 0.2, rtol=0.05)
    np.testing.assert_allclose(np.mean(p[:, 0]), 1.0, atol=0.01)


def test_a_turn_on_the_spot_turns_every_particle_with_rotation_noise_only():
    alpha = dict(odom_alpha1=0.01, odom_alpha2=0.0, odom_alpha3=0.0, odom_alpha4=0.0)
    p = _moved("diff-corrected", [0.0, 0.0, 1.0], **alpha)
    np.testing.assert_allclose(p[:, :2], np.tile([1.0, 0.0], (COUNT, 1)), atol=1e-12)
    turned = wrap_angle(p[:, 2] - math.pi / 2)
    np.testing.assert_allclose(turned.mean(), 1.0, atol=0.005)
    np.testing.assert_allclose(turned.std(), 0.1, rtol=0.05)  # sqrt(alpha1) * 1 rad


def test_backwards_motion_is_noisy_like_forwards_motion():
    alpha = dict(odom_alpha1=0.05, odom_alpha2=0.0, odom_alpha3=0.01, odom_alpha4=0.0)
    back = _moved("diff-corrected", [-1.0, 0.0, 0.0], **alpha)
    np.testing.assert_allclose(back[:, 1].mean(), -1.0, atol=0.01)
    # Not a half turn in the noise model: no rotation noise, as straight on.
    np.testing.assert_allclose(np.std(wrap_angle(back[:, 2] - math.pi / 2)), 0.0, atol=1e-12)


def test_ros1_diff_takes_the_alphas_mix_as_the_standard_deviation():
    """ROS 1's original ``diff``: 2 m straight on with alpha3 0.04 spreads the distance by
    alpha3 * (2 m)^2 = 0.16 m, where diff-corrected spreads it by sqrt(0.04 * 4) = 0.4 m."""
    alpha = dict(odom_alpha1=0.0, odom_alpha2=0.0, odom_alpha3=0.04, odom_alpha4=0.0)
    along = _moved("diff", [2.0, 0.0, 0.0], **alpha)[:, 1]
    np.testing.assert_allclose(along.mean(), 2.0, atol=0.01)
    np.testing.assert_allclose(along.std(), 0.16, rtol=0.05)
    corrected = _moved("diff-corrected", [2.0, 0.0, 0.0], **alpha)[:, 1]
    np.testing.assert_allclose(corrected.std(), 0.4, rtol=0.05)


def test_omni_moves_sideways_with_alpha5():
    """The odometry moves 1 m to the robot's left (a holonomic robot): the particles, facing
    +y, move 1 m to -x, spread along it by sqrt(alpha3) and across it by sqrt(alpha5)."""
    alpha = dict(odom_alpha1=0.0, odom_alpha2=0.0, odom_alpha3=0.01, odom_alpha4=0.0)
    p = _moved("omni-corrected", [0.0, 1.0, 0.0], odom_alpha5=0.04, **alpha)
    np.testing.assert_allclose([p[:, 0].mean(), p[:, 1].mean()], [0.0, 0.0], atol=0.01)
    np.testing.assert_allclose(p[:, 0].std(), 0.1, rtol=0.05)  # along the move
    np.testing.assert_allclose(p[:, 1].std(), 0.2, rtol=0.05)  # sideways
    np.testing.assert_allclose(np.std(wrap_angle(p[:, 2] - math.pi / 2)), 0.0, atol=1e-12)
    raw = _moved("omni", [0.0, 2.0, 0.0], odom_alpha5=0.04, **alpha)  # ROS 1: the mix as sigma
    np.testing.assert_allclose(raw[:, 1].std(), 0.04 * 4, rtol=0.05)


def test_a_small_move_while_turning_keeps_its_direction():
    """The base shifts 8 mm to its left while turning on the spot by 0.1 rad (a diff drive's
    final turn): ROS drops the direction of a move under 1 cm and moves the particles along
    their heading; here they move to their left, with ROS's noise."""
    alpha = dict(odom_alpha1=0.0, odom_alpha2=0.0, odom_alpha3=0.0, odom_alpha4=0.0)
    p = _moved("diff-corrected", [0.0, 0.008, 0.1], **alpha)  # the particles face +y
    np.testing.assert_allclose(p[:, :2], np.tile([1.0 - 0.008, 0.0], (COUNT, 1)), atol=1e-12)
    np.testing.assert_allclose(p[:, 2], math.pi / 2 + 0.1, atol=1e-12)
    noisy = _moved("diff-corrected", [0.0, 0.008, 0.1], **{**alpha, "odom_alpha1": 0.01})
    # All of the turn's noise in one turn, as ROS: sqrt(alpha1) * 0.1 rad.
    np.testing.assert_allclose(np.std(noisy[:, 2]), 0.01, rtol=0.05)
