"""Geometry of the batched sphere kernel (``sphere_batch``), lane by lane: points on the
kinematic steps, gates between point pairs and distances to the world's objects, each value
held for up to ``sphere_batch.LANES`` configurations side by side (the lane is the last,
contiguous axis) in loops that the compiler turns into SIMD instructions.

The arithmetic is the scalar kernel's (``sphere_kernel._point``, ``_distance2``), so a lane's
values are the ones ``sphere_kernel`` computes for its configuration. The functions are
inlined into ``classify_batch`` (or compiled into it), never called from Python.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, _nrt=False)
def points(T, s, p_B, k, out, row, lanes):
    """out[row] = X_W,s p_B[k] for every lane (same arithmetic as ``sphere_kernel._point``)."""
    x = p_B[k, 0]
    y = p_B[k, 1]
    z = p_B[k, 2]
    for i in range(3):
        r0 = T[s, 4 * i]
        r1 = T[s, 4 * i + 1]
        r2 = T[s, 4 * i + 2]
        r3 = T[s, 4 * i + 3]
        o = out[row, i]
        for lane in range(lanes):
            o[lane] = r0[lane] * x + r1[lane] * y + r2[lane] * z + r3[lane]


@njit(cache=True, _nrt=False, inline="always")
def centre_once(T, steps, p_B, k, out, seen, now, lanes):
    """out[k] = X_W,steps[k] p_B[k] for every lane, unless this batch (``now``) has computed it
    already (``seen[k]``): group and sphere centres on demand, as ``sphere_kernel`` computes
    them (most are never needed)."""
    if seen[k] != now:
        points(T, steps[k], p_B, k, out, k, lanes)
        seen[k] = now


@njit(cache=True, _nrt=False, inline="always")
def within(p, r, reach2, gate, out, lanes):
    """out[lane] = 1 where gate[lane] > 0 and the points p[:, lane] and r[:, lane] ((3, lanes)
    each) are less than sqrt(reach2) apart, else 0; True when some lane is."""
    found = False
    for lane in range(lanes):
        u = p[0, lane] - r[0, lane]
        v = p[1, lane] - r[1, lane]
        w = p[2, lane] - r[2, lane]
        inside = gate[lane] > 0.0 and u * u + v * v + w * w < reach2
        out[lane] = 1.0 if inside else 0.0
        found |= inside
    return found


@njit(cache=True, _nrt=False, inline="always")
def _in_object(W, offset, x, y, z):
    """(u, v, w): the point (x, y, z) in an object's frame, from its row's W (9 values,
    row-major) and offset (3): ``sphere_kernel._distance2``'s arithmetic."""
    w0, w1, w2, w3, w4, w5, w6, w7, w8 = W
    o0, o1, o2 = offset
    return (
        w0 * x + w1 * y + w2 * z - o0,
        w3 * x + w4 * y + w5 * z - o1,
        w6 * x + w7 * y + w8 * z - o2,
    )


@njit(cache=True, _nrt=False)
def min_distance2(p, obj, best, lanes):
    """best = min(best, squared distance from each lane's point p (3, lanes) to the object of
    row ``obj``): ``sphere_kernel._distance2``'s arithmetic (adding a zero term is exact)."""
    px = p[0]
    py = p[1]
    pz = p[2]
    # The row's frame, read once (outside the loops over the lanes, which then vectorise).
    W = (obj[1], obj[2], obj[3], obj[4], obj[5], obj[6], obj[7], obj[8], obj[9])
    offset = (obj[10], obj[11], obj[12])
    s0, s1, s2 = obj[13], obj[14], obj[15]
    if obj[0] == 0.0:  # box
        for lane in range(lanes):
            u, v, w = _in_object(W, offset, px[lane], py[lane], pz[lane])
            u = max(abs(u) - s0, 0.0)
            v = max(abs(v) - s1, 0.0)
            w = max(abs(w) - s2, 0.0)
            total = 0.0 + u * u
            total += v * v
            total += w * w
            best[lane] = min(best[lane], total)
    elif obj[0] == 1.0:  # cylinder along its z axis
        for lane in range(lanes):
            u, v, w = _in_object(W, offset, px[lane], py[lane], pz[lane])
            radial = max(np.sqrt(u * u + v * v) - s0, 0.0)
            axial = max(abs(w) - s1, 0.0)
            total = 0.0 + radial * radial
            total += axial * axial
            best[lane] = min(best[lane], total)
    else:  # sphere
        for lane in range(lanes):
            u, v, w = _in_object(W, offset, px[lane], py[lane], pz[lane])
            gap = max(np.sqrt(u * u + v * v + w * w) - s0, 0.0)
            best[lane] = min(best[lane], gap * gap)
