"""Geometry of the wheel axle, the frame in which a flipping robot's motion is simple.

When the robot flips over its axle, the body's x axis reverses but the axle (the body's y axis)
keeps its direction in the world. So heading and travel are measured in the *axle frame* A:
its y axis is the axle, its x axis the horizontal direction a positive wheel rotation rolls
the robot towards, its z axis up. The body's *pitch about the axle* is the angle from A's x
axis to the body's x axis, turning about the axle: 0 upright, +-pi upside down.
"""

import math

import numpy as np

__all__ = ["axle_yaw_and_pitch", "up_sign"]


def axle_yaw_and_pitch(R_WB: np.ndarray) -> tuple[float, float]:
    """Returns (yaw of the axle frame, body pitch about the axle), both in radians.

    Args:
        R_WB: the body's 3x3 rotation matrix in the world.

    The yaw is the heading of A's x axis in the world (z up); it is unchanged by a flip. The
    pitch grows when the body's rear swings up over the axle (the motor reaction to a reverse
    wheel torque). If the axle is vertical (the robot lies on a wheel) both are ill-defined and
    the body's own heading and pitch 0 are returned.
    """
    (x0, a0, _), (x1, a1, _), (x2, _, _) = R_WB.tolist()  # Columns x_B and a = y_B.
    norm = math.hypot(a0, a1)  # Of f = a x z_W: horizontal, perpendicular to the axle.
    if norm < 1e-6:
        return math.atan2(x1, x0), 0.0
    f0, f1 = a1 / norm, -a0 / norm
    pitch = math.atan2(-x2, x0 * f0 + x1 * f1)
    return math.atan2(f1, f0), pitch


def up_sign(R_WB: np.ndarray) -> float:
    """+1 when the body's z axis points up (upright), -1 when upside down."""
    return 1.0 if R_WB[2, 2] >= 0 else -1.0
