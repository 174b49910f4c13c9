"""Ray casting against shapes (drake_sim.systems.sensors.ray_casting), checked against a
reference that marches along each beam with inside-tests and bisects the first crossing."""

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix

import drake_sim.systems.sensors.ray_casting as mut

FAN = mut.Fan(-math.pi, 2 * math.pi / 360, 360)
STEP = 2e-3  # m, the reference's marching step


def _inside_box(p, h):
    return np.all(np.abs(p) <= h, axis=-1)


def _capsule_distance(p, s):
    """Distance from p to the capsule's axis segment, z in [-length/2, length/2]."""
    axis = np.zeros_like(p)
    axis[..., 2] = np.clip(p[..., 2], -s[1] / 2, s[1] / 2)
    return np.linalg.norm(p - axis, axis=-1)


INSIDE = {  # points p (..., 3) in the shape's frame, size as in Primitives
    mut.SPHERE: lambda p, s: np.sum(p * p, axis=-1) <= s[0] ** 2,
    mut.ELLIPSOID: lambda p, s: np.sum((p / s) ** 2, axis=-1) <= 1.0,
    mut.CYLINDER: lambda p, s: (
        (p[..., 0] ** 2 + p[..., 1] ** 2 <= s[0] ** 2) & (np.abs(p[..., 2]) <= s[1] / 2)
    ),
    mut.CAPSULE: lambda p, s: _capsule_distance(p, s) <= s[0],
    mut.HALF_SPACE: lambda p, s: p[..., 2] <= 0.0,
}


def _reference(inside, R_WS, p_WS, fan, max_distance):
    """First crossing along each beam of ``inside`` (points in W -> bool), by marching and
    bisection: independent of the module's closed forms."""
    out = np.full(fan.count, np.inf)
    t = np.arange(1, int(max_distance / STEP) + 1) * STEP
    for i, angle in enumerate(fan.angles()):
        d = R_WS @ np.array([math.cos(angle), math.sin(angle), 0.0])
        flags = inside(p_WS + t[:, None] * d)
        hit = np.flatnonzero(flags)
        if not len(hit):
            continue
        lo, hi = (t[hit[0] - 1] if hit[0] > 0 else 0.0), t[hit[0]]
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if inside(p_WS + mid * d) else (mid, hi)
        out[i] = hi
    return out


def _compare(measured, exact, tol=1e-9):
    both = np.isfinite(measured) & np.isfinite(exact)
    assert both.sum() >= 20
    np.testing.assert_allclose(measured[both], exact[both], rtol=0, atol=tol)
    # Grazing beams whose chord is shorter than the marching step may be missed by the
    # reference only.
    assert np.sum(np.isfinite(measured) != np.isfinite(exact)) <= 2


def _primitive(kind, size, radius, X_WG):
    return mut.Shapes(
        np.zeros((0, 3, 3)),
        mut.Primitives(
            np.array([kind]), X_WG.rotation().matrix()[None], X_WG.translation()[None],
            np.array([size], float), np.array([radius]),
        ),
    )  # fmt: skip


@pytest.mark.parametrize(
    "kind, size, radius",
    [
        (mut.SPHERE, (0.4, 0.4, 0.4), 0.4),
        (mut.ELLIPSOID, (0.6, 0.3, 0.5), 0.6),
        (mut.CYLINDER, (0.3, 0.5, 0.0), math.hypot(0.3, 0.25)),
        (mut.CAPSULE, (0.2, 0.6, 0.0), 0.5),
    ],
)
def test_primitives_seen_from_a_tilted_sensor(kind, size, radius):
    """Each shape, rotated so that the tilted scan plane cuts its side and its caps or ends."""
    X_WG = RigidTransform(RollPitchYaw(1.1, 0.4, 0.3), [1.0, 0.4, 0.2])
    X_WS = RigidTransform(RollPitchYaw(0.15, -0.1, 0.2), [0.0, 0.0, 0.25])
    shapes = _primitive(kind, size, radius, X_WG)
    R, p = X_WS.rotation().matrix(), X_WS.translation()
    measured = mut.cast_fan(shapes, R, p, FAN, 3.0)
    X_GW = X_WG.inverse()
    exact = _reference(
        lambda q: INSIDE[kind](q @ X_GW.rotation().matrix().T + X_GW.translation(), np.array(size)),
        R, p, FAN, 3.0,
    )  # fmt: skip
    _compare(measured, exact)


def test_half_space_from_a_tilted_sensor():
    X_WS = RigidTransform(RollPitchYaw(0.0, 0.2, 0.0), [0.0, 0.0, 0.3])
    R, p = X_WS.rotation().matrix(), X_WS.translation()
    shapes = _primitive(mut.HALF_SPACE, (0, 0, 0), np.inf, RigidTransform())
    measured = mut.cast_fan(shapes, R, p, FAN, 3.0)
    exact = _reference(lambda q: INSIDE[mut.HALF_SPACE](q, None), R, p, FAN, 3.0)
    _compare(measured, exact)
    assert measured[180] == pytest.approx(0.3 / math.sin(0.2))


def test_box_triangles_from_a_tilted_sensor():
    """A box as triangles, cut by a tilted plane through its top: exact, edges and corners
    included (no beam leaks between two triangles of a face)."""
    size = np.array([0.5, 0.8, 0.3])
    X_WG = RigidTransform(RotationMatrix.MakeZRotation(0.6), [-0.9, 0.7, 0.15])
    X_WS = RigidTransform(RollPitchYaw(0.05, 0.08, -0.4), [0.1, -0.1, 0.2])
    tri = mut.box_triangles(size)
    shapes = mut.Shapes(
        tri @ X_WG.rotation().matrix().T + X_WG.translation(), mut.Primitives.empty()
    )
    R, p = X_WS.rotation().matrix(), X_WS.translation()
    measured = mut.cast_fan(shapes, R, p, FAN, 3.0)
    X_GW = X_WG.inverse()
    exact = _reference(
        lambda q: _inside_box(q @ X_GW.rotation().matrix().T + X_GW.translation(), size / 2),
        R, p, FAN, 3.0,
    )  # fmt: skip
    _compare(measured, exact)
    # A beam aimed exactly at a vertical edge of the box still hits.
    corner = X_WG.multiply(size / 2 * np.array([1, -1, 0]))
    flat = mut.Fan(math.atan2(corner[1], corner[0]), 0.0, 1)
    hit = mut.cast_fan(shapes, np.eye(3), np.zeros(3), flat, 5.0)
    assert hit[0] == pytest.approx(math.hypot(corner[0], corner[1]), abs=1e-9)


def test_wrap_behind_the_sensor_and_partial_fans():
    """A wall straight behind a 360-degree fan is seen by its first and last beams (across the
    angle seam); a 270-degree fan sees nothing outside its sector, and its last beam counts."""
    behind = mut.Shapes(
        mut.box_triangles([0.1, 2.0, 1.0]) + [-1.0, 0.0, 0.0], mut.Primitives.empty()
    )
    ranges = mut.cast_fan(behind, np.eye(3), np.zeros(3), FAN, 5.0)
    c = np.cos(FAN.angles())
    aimed = c < -0.75  # these beams meet the wall's face x = -0.95 within |y| < 1
    np.testing.assert_allclose(ranges[aimed], -0.95 / c[aimed], atol=1e-9)
    assert aimed[0] and aimed[-1]
    assert np.all(np.isinf(ranges[c > -0.6]))
    partial = mut.Fan(math.radians(-135.0), math.radians(1.0), 271)  # to +135 degrees
    side = mut.Shapes(mut.box_triangles([2.0, 0.1, 1.0]) + [0.0, 1.0, 0.0], mut.Primitives.empty())
    ranges = mut.cast_fan(side, np.eye(3), np.zeros(3), partial, 5.0)
    s = np.sin(partial.angles())
    assert ranges[180] == pytest.approx(0.95 / math.sin(math.radians(45.0)), abs=1e-9)
    assert np.all(np.isinf(ranges[s <= 0.0])) and np.all(np.isfinite(ranges[s > 0.7]))
    ranges = mut.cast_fan(behind, np.eye(3), np.zeros(3), partial, 5.0)
    # Only +-134 and +-135 degrees reach it (its corner is at 133.5 degrees).
    edge = 0.95 / math.cos(math.radians(45.0))
    assert ranges[0] == pytest.approx(edge, abs=1e-9) and ranges[-1] == pytest.approx(
        edge, abs=1e-9
    )
    assert np.isfinite(ranges[[1, -2]]).all() and np.isinf(ranges[2:-2]).all()
