"""Geometry of the wheel axle, the frame in which a flipping robot's motion is simple.

When the robot flips over its axle, the body's x axis reverses but the axle (the body's y axis)
keeps its direction in the world. So heading and travel are measured in the *axle frame* A:
its y axis is the axle, its x axis the horizontal direction a positive wheel rotation rolls
the robot towards, its z axis up. The body's *pitch about the axle* is the angle from A's x
axis to the body's x axis, turning about the axle: 0 upright, +-pi upside down.
"""

import math

import numpy as np


def axle_yaw_and_pitch(R_WB: np.ndarray) -> tuple[float, float]:
    """Returns (yaw of the axle frame, body pitch about the axle), both in radians.

    Args:
        R_WB: the body's 3x3 rotation matrix in the world.

    The yaw is the heading of A's x axis in the world (z up); it is unchanged by a flip. The
    pitch grows when the body's rear swings up over the axle (the motor reaction to a reverse
    wheel torque). If the axle is vertical (the robot lies on a wheel) both are ill-defined and
    the body's own heading and pitch 0 are returned.
    """
    a = R_WB[:, 1]  # The axle, in the world.
    f = np.array([a[1], -a[0], 0.0])  # a x z_W: horizontal, perpendicular to the axle.
    norm = math.hypot(f[0], f[1])
    if norm < 1e-6:
        x = R_WB[:, 0]
        return math.atan2(x[1], x[0]), 0.0
    f /= norm
    x_B = R_WB[:, 0]
    pitch = math.atan2(-x_B[2], float(x_B @ f))
    return math.atan2(f[1], f[0]), pitch


def up_sign(R_WB: np.ndarray) -> float:
    """+1 when the body's z axis points up (upright), -1 when upside down."""
    return 1.0 if R_WB[2, 2] >= 0 else -1.0


def wrap_angle(angle: float) -> float:
    """Wraps an angle to [-pi, pi)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi
