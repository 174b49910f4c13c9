"""Axle-frame geometry: yaw and pitch about the axle (unchanged yaw through a flip), which way
up the body is."""

import math

import numpy as np
import pytest
from pydrake.math import RollPitchYaw, RotationMatrix

import drake_sim.systems.axle as mut
from drake_sim.base.planar import wrap_angle


def R(roll=0.0, pitch=0.0, yaw=0.0) -> np.ndarray:
    """R_WB = Rz(yaw) Ry(pitch) Rx(roll)."""
    return RotationMatrix(RollPitchYaw(roll, pitch, yaw)).matrix()


def test_upright_body_has_its_own_heading_and_no_pitch():
    assert mut.axle_yaw_and_pitch(np.eye(3)) == (0.0, 0.0)
    for yaw in (0.5, -2.0, 3.0):
        assert mut.axle_yaw_and_pitch(R(yaw=yaw)) == pytest.approx((yaw, 0.0))


@pytest.mark.parametrize("yaw", [0.0, 0.7, -2.5])
def test_pitch_about_the_axle_keeps_the_yaw_through_a_flip(yaw):
    """Turning about the axle (the body's y axis) by any angle, upside down included, changes
    the pitch by that angle and leaves the axle frame's yaw alone."""
    for pitch in np.linspace(-math.pi + 0.01, math.pi - 0.01, 25):
        got_yaw, got_pitch = mut.axle_yaw_and_pitch(R(pitch=pitch, yaw=yaw))
        assert wrap_angle(got_yaw - yaw) == pytest.approx(0.0, abs=1e-12)
        assert got_pitch == pytest.approx(pitch, abs=1e-12)


def test_upside_down_is_pitch_pi_with_the_same_yaw():
    yaw, pitch = mut.axle_yaw_and_pitch(R(pitch=math.pi, yaw=0.4))
    assert yaw == pytest.approx(0.4) and abs(pitch) == pytest.approx(math.pi)


def test_rear_swinging_up_is_positive_pitch():
    """Positive pitch about y tips the body's x axis (its front) down and its rear up."""
    R_WB = R(pitch=0.3)
    assert R_WB[2, 0] < 0.0  # the front goes down
    assert mut.axle_yaw_and_pitch(R_WB)[1] == pytest.approx(0.3)


def test_a_tilted_axle_still_gives_the_heading():
    """Rolling about the body's x axis tilts the axle but not the direction of travel."""
    for roll in (-0.4, 0.3):
        assert mut.axle_yaw_and_pitch(R(roll=roll, yaw=1.1)) == pytest.approx((1.1, 0.0))


def test_vertical_axle_falls_back_to_the_body_heading():
    """Lying on a wheel: the axle points up, and the body's own heading is returned."""
    R_WB = R(roll=math.pi / 2, yaw=0.8)
    np.testing.assert_allclose(R_WB[:, 1], [0, 0, 1], atol=1e-12)
    assert mut.axle_yaw_and_pitch(R_WB) == pytest.approx((0.8, 0.0))


def test_up_sign():
    assert mut.up_sign(np.eye(3)) == 1.0
    assert mut.up_sign(R(pitch=math.pi)) == -1.0
    assert mut.up_sign(R(roll=2.0)) == -1.0
    assert mut.up_sign(R(pitch=math.pi / 2)) == 1.0  # on its end: counts as upright
    assert mut.up_sign(R(pitch=1.0, yaw=2.0)) == 1.0
