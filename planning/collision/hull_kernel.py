"""Exact clearance proofs for what the sphere covers cannot decide (numba): the robot's convex
collision shapes against the world's primitives and against each other.

Drake's checker tests the robot's collision geometry itself: convex meshes (as the convex hull
of their vertices), boxes, and held boxes, cylinders and spheres. ``HullData`` holds each robot
shape as a set of vertices (on the kernel's kinematic steps, as ``KernelData``'s spheres) swept
by a ball of ``geom_radius`` (a sphere: one vertex; a held cylinder: the prism around it, which
contains it). ``hull_free`` proves a configuration free when every pair the checker checks is
farther apart than its padding plus ``MARGIN``: a bounding sphere per shape first, then, for
the pairs that come closer, GJK (Gilbert, Johnson and Keerthi, IEEE J. Robotics and Automation
1988) on the shapes' support functions.

Proofs never rest on GJK having converged: each iteration's direction v gives the lower bound
(min over the Minkowski difference A - B of v.z) / |v| on the distance, computed from the two
support points themselves (a vertex, the ball's offset, an object's support point), and a
pair is proven apart only when that bound exceeds its threshold. When GJK cannot show that
(the shapes touch, or their gap is within the threshold), the configuration stays undecided and
Drake's checker is asked, as before.

``MARGIN`` (0.1 mm) is on the safe side of every threshold: it covers rounding here (~1e-15 m)
and in Drake's own distance queries by orders of magnitude, and it is far below the covers'
slack, so it costs no proofs that matter.

A compiled kernel module, longer than the project's 400 lines since the swept check added its
margins (``geom_body``, ``speed``): its GJK, its data and its entry point stay in one file, which
numba keys its cache on (``refresh_cache``), rather than in more files every entry point lists.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numba import njit

from planning.collision import sphere_kernel, trig
from planning.collision.sphere_kernel import (
    _distance2,
    _pose_chain_lanes,
    _v1,
    _v2,
    refresh_cache,
    unpack,
)

MARGIN = 1e-4  # m, added to every pair's threshold
_ITERATIONS = 48  # GJK iterations before giving up on a pair (polytopes converge in ~10)


class HullData(NamedTuple):
    """The robot's collision shapes for ``hull_free`` (float64 or int64, C-contiguous; m).

    ``geom_step`` (H,) the kinematic step of each shape (``KernelData``'s folded tree),
    ``vert_start`` (H + 1,) its vertices' rows in ``vert`` (V, 3) (on that step's frame),
    ``geom_radius`` (H,) the ball sweeping them (0 for a polytope), ``geom_centre`` (H, 3) and
    ``geom_bound`` (H,) a sphere containing the shape; ``geom_world`` (H,) the least clearance
    to prove against every world object (its padding, at least 0, plus ``MARGIN``; -1: not
    checked against the world); ``pair`` (P, 2) the shape pairs checked against each other and
    ``pair_gap`` (P,) their least clearance, likewise; ``geom_body`` (H,) each shape's body
    (a row of ``speed``) and ``speed`` (B, D) a bound on how fast any point of each body's
    shapes moves per rad of each arm joint, m/rad (``checker.speed_walk`` of the shapes'
    reach), for ``hull_free``'s ``motion``.
    """

    geom_step: np.ndarray
    vert_start: np.ndarray
    vert: np.ndarray
    geom_radius: np.ndarray
    geom_centre: np.ndarray
    geom_bound: np.ndarray
    geom_world: np.ndarray
    pair: np.ndarray
    pair_gap: np.ndarray
    geom_body: np.ndarray
    speed: np.ndarray


@njit(cache=True)
def unpack_hulls(f, i):
    """The ``HullData`` of ``sphere_kernel.pack``'s two buffers (views on them)."""
    return HullData(
        _v1(i, i, 0),
        _v1(i, i, 1),
        _v2(f, i, 2),
        _v1(f, i, 3),
        _v2(f, i, 4),
        _v1(f, i, 5),
        _v1(f, i, 6),
        _v2(i, i, 7),
        _v1(f, i, 8),
        _v1(i, i, 9),
        _v2(f, i, 10),
    )


@njit(cache=True, _nrt=False)
def _hull_support(h, g, T, nx, ny, nz):
    """The point of robot shape g (world frame, posed by the transforms T) farthest along the
    direction (nx, ny, nz)."""
    X = T[h.geom_step[g]]
    # The direction in the step's frame: R^T n.
    a = X[0, 0] * nx + X[1, 0] * ny + X[2, 0] * nz
    b = X[0, 1] * nx + X[1, 1] * ny + X[2, 1] * nz
    c = X[0, 2] * nx + X[1, 2] * ny + X[2, 2] * nz
    vert = h.vert
    best = -np.inf
    k_best = h.vert_start[g]
    for k in range(h.vert_start[g], h.vert_start[g + 1]):
        value = vert[k, 0] * a + vert[k, 1] * b + vert[k, 2] * c
        if value > best:
            best = value
            k_best = k
    x = vert[k_best, 0]
    y = vert[k_best, 1]
    z = vert[k_best, 2]
    px = X[0, 0] * x + X[0, 1] * y + X[0, 2] * z + X[0, 3]
    py = X[1, 0] * x + X[1, 1] * y + X[1, 2] * z + X[1, 3]
    pz = X[2, 0] * x + X[2, 1] * y + X[2, 2] * z + X[2, 3]
    r = h.geom_radius[g]
    if r > 0.0:
        norm = np.sqrt(nx * nx + ny * ny + nz * nz)
        if norm > 0.0:
            px += r * nx / norm
            py += r * ny / norm
            pz += r * nz / norm
    return px, py, pz


@njit(cache=True, _nrt=False)
def _centre(h, g, T):
    """The centre of robot shape g's bounding sphere, posed by the transforms T (world)."""
    X = T[h.geom_step[g]]
    c = h.geom_centre[g]
    x = X[0, 0] * c[0] + X[0, 1] * c[1] + X[0, 2] * c[2] + X[0, 3]
    y = X[1, 0] * c[0] + X[1, 1] * c[1] + X[1, 2] * c[2] + X[1, 3]
    z = X[2, 0] * c[0] + X[2, 1] * c[1] + X[2, 2] * c[2] + X[2, 3]
    return x, y, z


@njit(cache=True, _nrt=False)
def _object_support(obj, nx, ny, nz):
    """The point of a world object (a ``KernelData.objects`` row) farthest along (nx, ny, nz)."""
    # The direction in the object's frame: W n (W = R_WO^T).
    u = obj[1] * nx + obj[2] * ny + obj[3] * nz
    v = obj[4] * nx + obj[5] * ny + obj[6] * nz
    w = obj[7] * nx + obj[8] * ny + obj[9] * nz
    if obj[0] == 0.0:  # box
        x = obj[13] if u >= 0.0 else -obj[13]
        y = obj[14] if v >= 0.0 else -obj[14]
        z = obj[15] if w >= 0.0 else -obj[15]
    elif obj[0] == 1.0:  # cylinder along its z axis
        radial = np.sqrt(u * u + v * v)
        x = obj[13] * u / radial if radial > 0.0 else obj[13]
        y = obj[13] * v / radial if radial > 0.0 else 0.0
        z = obj[14] if w >= 0.0 else -obj[14]
    else:  # sphere
        norm = np.sqrt(u * u + v * v + w * w)
        x = obj[13] * u / norm if norm > 0.0 else obj[13]
        y = obj[13] * v / norm if norm > 0.0 else 0.0
        z = obj[13] * w / norm if norm > 0.0 else 0.0
    # Back to the world: p_W = W^T (p_O + offset).
    x += obj[10]
    y += obj[11]
    z += obj[12]
    px = obj[1] * x + obj[4] * y + obj[7] * z
    py = obj[2] * x + obj[5] * y + obj[8] * z
    pz = obj[3] * x + obj[6] * y + obj[9] * z
    return px, py, pz


@njit(cache=True, _nrt=False)
def _difference_support(h, g, other, obj, T, nx, ny, nz):
    """The point of A - B farthest along -n: A's support along -n minus B's along n, where A
    is robot shape g and B robot shape ``other`` (>= 0) or the world object ``obj``."""
    ax, ay, az = _hull_support(h, g, T, -nx, -ny, -nz)
    if other >= 0:
        bx, by, bz = _hull_support(h, other, T, nx, ny, nz)
    else:
        bx, by, bz = _object_support(obj, nx, ny, nz)
    return ax - bx, ay - by, az - bz


@njit(cache=True, _nrt=False)
def _closest(P, k, v):
    """The point of the simplex P[:k] (rows, up to 4) nearest to the origin, into v (3,);
    keeps in P the vertices of the face it lies in and returns their count (0 when the
    simplex holds the origin, or none is left). Each subset's affine nearest point is tried
    and kept when it lies inside its face (positive weights); the nearest of those is the
    simplex's (a point of one face lies in the simplex, and the simplex's nearest point is the
    inside nearest point of the face it lies in)."""
    best = np.inf
    best_mask = 0
    bx = by = bz = 0.0
    for mask in range(1, 1 << k):
        i0 = i1 = i2 = i3 = 0
        m = 0
        for i in range(k):
            if mask & (1 << i):
                if m == 0:
                    i0 = i
                elif m == 1:
                    i1 = i
                elif m == 2:
                    i2 = i
                else:
                    i3 = i
                m += 1
        o = P[i0]
        if m == 1:
            x, y, z = o[0], o[1], o[2]
        elif m == 2:
            e = P[i1]
            ex, ey, ez = e[0] - o[0], e[1] - o[1], e[2] - o[2]
            denom = ex * ex + ey * ey + ez * ez
            if denom <= 1e-30:
                continue
            mu = -(o[0] * ex + o[1] * ey + o[2] * ez) / denom
            if mu <= 0.0 or mu >= 1.0:
                continue
            x, y, z = o[0] + mu * ex, o[1] + mu * ey, o[2] + mu * ez
        elif m == 3:
            e, f = P[i1], P[i2]
            ex, ey, ez = e[0] - o[0], e[1] - o[1], e[2] - o[2]
            fx, fy, fz = f[0] - o[0], f[1] - o[1], f[2] - o[2]
            g11 = ex * ex + ey * ey + ez * ez
            g12 = ex * fx + ey * fy + ez * fz
            g22 = fx * fx + fy * fy + fz * fz
            r1 = -(o[0] * ex + o[1] * ey + o[2] * ez)
            r2 = -(o[0] * fx + o[1] * fy + o[2] * fz)
            det = g11 * g22 - g12 * g12
            if det <= 1e-24 * g11 * g22 or det <= 0.0:
                continue
            mu1 = (r1 * g22 - r2 * g12) / det
            mu2 = (g11 * r2 - g12 * r1) / det
            if mu1 <= 0.0 or mu2 <= 0.0 or mu1 + mu2 >= 1.0:
                continue
            x = o[0] + mu1 * ex + mu2 * fx
            y = o[1] + mu1 * ey + mu2 * fy
            z = o[2] + mu1 * ez + mu2 * fz
        else:
            e, f, s = P[i1], P[i2], P[i3]
            ex, ey, ez = e[0] - o[0], e[1] - o[1], e[2] - o[2]
            fx, fy, fz = f[0] - o[0], f[1] - o[1], f[2] - o[2]
            sx, sy, sz = s[0] - o[0], s[1] - o[1], s[2] - o[2]
            # o + mu1 e + mu2 f + mu3 s = 0 when the tetrahedron is not flat.
            det = ex * (fy * sz - fz * sy) - fx * (ey * sz - ez * sy) + sx * (ey * fz - ez * fy)
            scale = (
                np.sqrt(ex * ex + ey * ey + ez * ez)
                * np.sqrt(fx * fx + fy * fy + fz * fz)
                * np.sqrt(sx * sx + sy * sy + sz * sz)
            )
            if abs(det) <= 1e-12 * scale:
                continue
            ox, oy, oz = -o[0], -o[1], -o[2]
            mu1 = (
                ox * (fy * sz - fz * sy) - fx * (oy * sz - oz * sy) + sx * (oy * fz - oz * fy)
            ) / det
            mu2 = (
                ex * (oy * sz - oz * sy) - ox * (ey * sz - ez * sy) + sx * (ey * oz - ez * oy)
            ) / det
            mu3 = (
                ex * (fy * oz - fz * oy) - fx * (ey * oz - ez * oy) + ox * (ey * fz - ez * fy)
            ) / det
            if mu1 <= 0.0 or mu2 <= 0.0 or mu3 <= 0.0 or mu1 + mu2 + mu3 >= 1.0:
                continue
            x = y = z = 0.0  # the origin is inside
        d2 = x * x + y * y + z * z
        if d2 < best:
            best = d2
            best_mask = mask
            bx, by, bz = x, y, z
    v[0], v[1], v[2] = bx, by, bz
    m = 0
    for i in range(k):
        if best_mask & (1 << i):
            if m != i:
                P[m, 0], P[m, 1], P[m, 2] = P[i, 0], P[i, 1], P[i, 2]
            m += 1
    return m if best > 0.0 else 0


@njit(cache=True, _nrt=False)
def _apart(h, g, other, obj, T, gap, P, v):
    """True when robot shape g and robot shape ``other`` (>= 0) or the world object ``obj``
    are provably more than ``gap`` apart (GJK, see the module docstring); P (4, 3) and v (3,)
    are scratch."""
    # A first direction: from the other's bounding centre to g's.
    vx, vy, vz = _centre(h, g, T)
    if other >= 0:
        ox, oy, oz = _centre(h, other, T)
        vx -= ox
        vy -= oy
        vz -= oz
    else:  # the object's centre: p_W = W^T offset
        vx -= obj[1] * obj[10] + obj[4] * obj[11] + obj[7] * obj[12]
        vy -= obj[2] * obj[10] + obj[5] * obj[11] + obj[8] * obj[12]
        vz -= obj[3] * obj[10] + obj[6] * obj[11] + obj[9] * obj[12]
    if vx == 0.0 and vy == 0.0 and vz == 0.0:
        vx = 1.0
    k = 0
    gap2 = gap * gap
    for _ in range(_ITERATIONS):
        vv = vx * vx + vy * vy + vz * vz
        wx, wy, wz = _difference_support(h, g, other, obj, T, vx, vy, vz)
        # Every point z of A - B has v.z >= v.w: the distance is at least v.w / |v|.
        vw = vx * wx + vy * wy + vz * wz
        if vw > 0.0 and vw * vw > gap2 * vv:
            return True
        if k > 0 and vv - vw <= 1e-12 * vv:
            return False  # converged: the distance is about |v|, not above the gap
        P[k, 0], P[k, 1], P[k, 2] = wx, wy, wz
        k = _closest(P, k + 1, v)
        if k == 0 or k == 4:
            return False  # the origin is in A - B (or its simplex): touching
        vx, vy, vz = v[0], v[1], v[2]
        if vx * vx + vy * vy + vz * vz <= gap2:
            return False  # a point of A - B within the gap: the distance is not above it
    return False


@njit(cache=True, _nrt=False)
def _motion_gap(h, a, b, motion):
    """How far, m, shape a's points (b < 0) or the distances between shapes a's and b's may
    change while the arm moves by at most ``motion[j]`` rad in each joint j (empty: none);
    see ``sphere_kernel.motion_margins``."""
    total = 0.0
    body_a = h.geom_body[a]
    for j in range(len(motion)):
        if motion[j] <= 0.0:
            continue
        if b < 0:
            total += h.speed[body_a, j] * motion[j]
            continue
        body_b = h.geom_body[b]
        if not (h.speed[body_a, j] > 0.0 and h.speed[body_b, j] > 0.0):
            total += (h.speed[body_a, j] + h.speed[body_b, j]) * motion[j]
    return total


@njit(cache=True, _nrt=False)
def _shapes_free(h, objects, T, P, v, none, motion):
    """True when every checked pair of the posed shapes (transforms T) is provably apart, by
    its clearance plus how much the arm's ``motion`` may close it (``_motion_gap``);
    ``none`` is an object row that no robot pair reads."""
    for g in range(len(h.geom_step)):
        gap = h.geom_world[g]
        if gap < 0.0:
            continue
        gap += _motion_gap(h, g, -1, motion)
        x, y, z = _centre(h, g, T)
        reach = h.geom_bound[g] + gap
        for o in range(len(objects)):
            if _distance2(x, y, z, objects[o]) > reach * reach:
                continue
            if not _apart(h, g, -1, objects[o], T, gap, P, v):
                return False
    for p in range(len(h.pair)):
        g = h.pair[p, 0]
        e = h.pair[p, 1]
        gap = h.pair_gap[p] + _motion_gap(h, g, e, motion)
        ax, ay, az = _centre(h, g, T)
        bx, by, bz = _centre(h, e, T)
        dx, dy, dz = ax - bx, ay - by, az - bz
        reach = h.geom_bound[g] + h.geom_bound[e] + gap
        if dx * dx + dy * dy + dz * dz > reach * reach:
            continue
        if not _apart(h, g, e, none, T, gap, P, v):
            return False
    return True


@njit(cache=True)
def hull_scratch(d):
    """Scratch of ``hull_free``: the plant positions, sines, cosines, transforms, a simplex,
    a point and an object row of zeros."""
    return (
        d.template.copy(),
        np.empty(len(d.template)),
        np.empty(len(d.template)),
        np.empty((len(d.parent), 3, 4)),
        np.empty((4, 3)),
        np.empty(3),
        np.zeros(d.objects.shape[1]),
    )


@njit(cache=True, _nrt=False)
def hull_free(q, d, h, scratch, motion):
    """True when the arm configuration q (D,) is provably collision-free for Drake's checker:
    every pair it checks more than its padding plus ``MARGIN`` apart, and more by what
    ``motion`` (D,) may close it (empty: nothing): then every configuration within motion[j]
    rad of q in each joint j is free too. ``d`` is the sphere model's ``KernelData``
    (kinematics, world objects), ``h`` its ``HullData``, ``scratch`` ``hull_scratch(d)``."""
    full, sines, cosines, T, P, v, none = scratch
    for k in range(len(q)):
        if not np.isfinite(q[k]):
            return False
        full[d.arm[k]] = q[k]
    _pose_chain_lanes(full, sines, cosines, d.parent, d.kind, d.q_index, d.terms, T)
    return _shapes_free(h, d.objects, T, P, v, none, motion)


@njit(cache=True)
def prove_free(qs, d, h, motion):
    """``hull_free`` of each row of qs (N, D) with the row of ``motion`` (N, D; (0, D): none):
    a bool array."""
    scratch = hull_scratch(d)
    out = np.zeros(len(qs), dtype=np.bool_)
    none = np.zeros(0)
    for n in range(len(qs)):
        out[n] = hull_free(qs[n], d, h, scratch, motion[n] if len(motion) else none)
    return out


@njit(cache=True)
def prove_free_packed(qs, floats, ints, hull_floats, hull_ints, motion):
    """``prove_free`` with the ``KernelData`` and the ``HullData`` packed
    (``sphere_kernel.pack``): five arrays to pass from Python instead of 47."""
    return prove_free(qs, unpack(floats, ints), unpack_hulls(hull_floats, hull_ints), motion)


# Numba keys a cached function on its own file alone; these compile the kernel's code (its
# kinematics, distances and ``unpack``) into theirs.
refresh_cache(
    sys.modules[__name__],
    [Path(__file__), Path(sphere_kernel.__file__), Path(trig.__file__)],
    Path(prove_free_packed._cache._cache_path),
)
