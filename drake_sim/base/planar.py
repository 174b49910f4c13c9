"""Planar geometry: the one convention for angles and poses in the plane.

A pose is ``[x, y, yaw]`` (m, m, rad): where a frame stands in its parent and which way its x
axis points. Arrays of poses hold one pose per row, shape (n, 3) (any leading shape works: the
pose is always the last axis). Angles are wrapped to [-pi, pi).

``wrap_angle`` wraps as ``(a + pi) % (2 pi) - pi``, the formula the estimators, controllers and
planners were measured with. It rounds: adding and taking away pi moves an angle already in
range by up to half an ulp of pi (``wrap_angle(0.3) != 0.3``). Wrapping a difference once, that
does not matter; a state wrapped at every step of an integration (the wheel odometry's yaw)
would add the roundings up, so it uses ``wrap_angle_exact``: the same range, no rounding (an
angle in range comes back unchanged; ``math.remainder(a, 2 pi)``, except that pi maps to -pi),
as does a course's heading, read off its centreline.

A single pose turns with ``math.cos``/``math.sin`` and a scalar angle wraps with Python's float
arithmetic (the values the estimators and controllers were measured with); arrays go through
numpy, elementwise, with the same results.
"""

import math

import numpy as np

_TWO_PI = 2.0 * math.pi


def wrap_angle(angle):
    """Wraps angle(s) (rad) to [-pi, pi).

    Args:
        angle: a number or an array of them.

    Returns:
        A float for a number (a numpy scalar stays one), an array for an array.
    """
    if isinstance(angle, (float, int)):
        return (angle + math.pi) % _TWO_PI - math.pi
    return (np.asarray(angle, dtype=float) + math.pi) % _TWO_PI - math.pi


def wrap_angle_exact(angle):
    """Wraps angle(s) (rad) to [-pi, pi) without rounding: the result is ``angle`` minus a whole
    number of (floating-point) 2 pi turns, exactly; an angle in range comes back unchanged.

    Args:
        angle: a number or an array of them.

    Returns:
        A float for a number, an array for an array.
    """
    # fmod is exact, and so is moving its result in [pi, 2 pi) or (-2 pi, -pi) by 2 pi (Sterbenz).
    if isinstance(angle, (float, int)):
        r = math.fmod(angle, _TWO_PI)
        return r - _TWO_PI if r >= math.pi else r + _TWO_PI if r < -math.pi else r
    r = np.fmod(np.asarray(angle, dtype=float), _TWO_PI)
    return np.where(r >= math.pi, r - _TWO_PI, np.where(r < -math.pi, r + _TWO_PI, r))


def _turn(yaw):
    """cos and sin of ``yaw``: libm's for a number, numpy's for an array."""
    if np.ndim(yaw) == 0:
        return math.cos(yaw), math.sin(yaw)
    return np.cos(yaw), np.sin(yaw)


def compose(a, b) -> np.ndarray:
    """The pose ``b``, given in the frame of pose ``a``, expressed where ``a`` is (a then b).

    Args:
        a: pose(s) (3,) or (..., 3) of the frame that ``b`` is given in.
        b: pose(s) (3,) or (..., 3) in frame ``a``; shapes broadcast.

    Returns:
        The pose(s) in a's parent frame, shape of the broadcast; yaw wrapped.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    c, s = _turn(a[..., 2])
    x = a[..., 0] + c * b[..., 0] - s * b[..., 1]
    y = a[..., 1] + s * b[..., 0] + c * b[..., 1]
    return np.stack(np.broadcast_arrays(x, y, wrap_angle(a[..., 2] + b[..., 2])), -1)


def relative_pose(a, b) -> np.ndarray:
    """The pose ``b`` seen from pose ``a`` (b in a's frame): the inverse of ``compose``, so
    ``compose(a, relative_pose(a, b)) == b`` (to rounding, yaw wrapped).

    Args:
        a: pose(s) (3,) or (..., 3) of the frame to express ``b`` in.
        b: pose(s) (3,) or (..., 3) in the same parent frame as ``a``; shapes broadcast.

    Returns:
        The pose(s) in frame ``a``, shape of the broadcast; yaw wrapped.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    c, s = _turn(a[..., 2])
    dx, dy = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    x = c * dx + s * dy
    y = -s * dx + c * dy
    return np.stack(np.broadcast_arrays(x, y, wrap_angle(b[..., 2] - a[..., 2])), -1)


def same_pose(a, b, distance: float = 0.02, angle: float = math.radians(0.5)) -> bool:
    """Whether poses ``a`` and ``b`` (x, y, yaw) are within ``distance`` (m) and ``angle``
    (rad) of each other (a scan matcher's two matches that found one pose)."""
    offset = relative_pose(a, b)
    return math.hypot(offset[0], offset[1]) <= distance and abs(offset[2]) <= angle
