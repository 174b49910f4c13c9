"""Compiled kernels (numba) of the sphere collision model: kinematics and classification.

``SphereCollisionModel`` (``planning.collision.spheres``) packs the robot's kinematic tree, its
spheres, their culling groups and the world's boxes, cylinders and spheres into a ``KernelData`` of
flat arrays; ``prefixes`` checks samples along many segments, one configuration at a time in
compiled loops: 1 to 2 us per configuration and ~15 us per call (unpacking the arrays), where
the numpy version of the same passes cost ~25 us per configuration and ~0.5 ms per call
(measured on this project's 2-core VM). Culling goes from coarse to fine: a sphere around
each body against axis-aligned boxes around the objects, then a sphere around each group of
spheres against the objects near the body, then the spheres; self-collision likewise by body
pairs, then group pairs. Each configuration stops at its first certain collision, or at its
first uncertain one when the caller treats both alike (``stop_at_unknown``), and each segment
at its first blocking sample, as VAMP's checks do (Thomason, Kingston, Kavraki, "Motions in
Microseconds via Vectorized Sampling-Based Planning", ICRA 2024).

Kinematics: each step of the tree is X_PC(q) = A + a B + b C (3x4 rows of constant matrices):
a = sin q, b = cos q for a revolute joint; a = q, b = 0 for a prismatic one; a = b = 0 for a
weld (see ``planning.collision.sphere_fk``); X_WC = X_WP X_PC.

The functions here that allocate nothing are compiled without numba's reference counting
(``_nrt=False``, a numba target option): with it, every array taken from ``KernelData`` or the
scratch tuple was counted in and out around the loops, and the counting cost a fifth of a check
(search on MBM: 23 % less time, the same checks and paths; measured in paired runs).
``_classify_one`` is inlined where it is called (numba's ``inline="always"``): a call passed its
forty-odd arrays field by field, 12 % of the search's time (paired runs; the first compile took
103 s against 120 s without it, measured in turn: no longer within the VM's noise). The exact
distance to an object (``_distance2``) and the vectorised sines and cosines are inlined too
(profiled with their symbols, the two took a tenth of the search's compiled time as calls):
per-problem median 0.974x on all of MBM, the same paths. The sines and
cosines come from ``planning.collision.trig``, all of a configuration's in one loop that
vectorises; the groups' centres are computed when a test first needs them (most are not).
These two and the kinematics and centres written out (``_step``, ``_points``): per-problem
median 0.979x on all of MBM, the same paths (``benchmarks/planner_ab.py`` against 26bf203).

Compiled once per machine (``cache=True`` keeps the machine code beside this file, or in
numba's cache folder when that is read-only): the first call in a fresh install takes about
10 s, later processes load it in ~0.5 s. One entry point (``prefixes``; ``transforms`` for
kinematics alone) keeps that short: each compiled entry point costs its own optimisation.
``announce_compile`` says so on stderr, once per process, when that compile is about to happen.

A compiled kernel module, longer than the project's 400 lines: numba keys a cached function on
its own file alone, so every module that compiles this kernel's code into its own lists the
files that code comes from (``refresh_cache``); the data layout (``KernelData``, ``pack``), the
kinematics and the classification that all those callers inline stay in this one file.
"""

from __future__ import annotations

import hashlib
import os
import sys
import threading
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numba import njit
from numba.core.caching import NullCache

from planning.collision import trig
from planning.collision.trig import sincos, sincos_lanes

FREE, COLLIDING, UNKNOWN = 0, 1, 2
# Columns of an object row: kind, W (9), offset (3), sizes (3), lower (3), upper (3).
OBJ_KIND, OBJ_W, OBJ_OFFSET, OBJ_SIZE, OBJ_LOWER, OBJ_UPPER, OBJ_COLUMNS = 0, 1, 10, 13, 16, 19, 22


class KernelData(NamedTuple):
    """The arrays the kernels read (float64 or int64, C-contiguous; m and rad).

    Kinematics: ``parent`` (J,) step of each step's parent (-1: world), ``kind`` (J,) 0 weld,
    1 revolute, 2 prismatic, ``q_index`` (J,) plant position of its joint, ``terms``
    (J, 3, 3, 4) A, B, C above, ``template`` (nq,) the plant positions of the joints other
    than the arm's, ``arm`` (D,) the arm's position indices (D: the arm's joints, any number).
    Spheres: ``sphere_step`` (S,), ``p_BS`` (S, 3). Bodies: ``body_step`` (L,), ``p_BL``
    (L, 3) centre of a sphere around the body's groups, ``body_reach`` (L,) its radius plus
    the body's world padding. Groups: ``group_step`` (G,), ``p_BG`` (G, 3) centres.
    World: ``env_group`` (E,) groups checked against the world, by body, ``env_body`` (E,)
    their body, ``env_reach2`` (E,) squared reach, ``env_member`` (E, 4) spheres (index),
    ``env_out``, ``env_in`` (E, 4) squared outer and inner thresholds (-1: never).
    Self: ``body_pair`` (Q, 2) checked body pairs, ``body_pair_reach2`` (Q,), their group
    pairs in rows ``body_pair_start[q]`` to ``body_pair_start[q + 1]`` of ``pair_group``
    (P, 2), ``pair_reach2`` (P,), ``pair_a``, ``pair_b`` (P, 16) sphere indices, ``pair_out``,
    ``pair_in`` (P, 16); the rows of a body pair run by their first group, and
    ``pair_side_reach2`` (P,) is the squared reach of a row's first group to the other body's
    centre (``p_BL``), beyond which none of that group's rows is within reach.
    Objects: ``objects`` (O, 22), one row per object (columns: ``OBJ_*``): its kind (0 box,
    1 cylinder, 2 sphere), W = R_WO^T (row-major), offset = R_WO^T p_WO, its sizes (box: half
    sizes; cylinder: radius, half length; sphere: radius) and the lower and upper corners of
    an axis-aligned box around it.
    Speeds: ``speed`` (L, D), a bound on how fast any point the checks use on each body (a
    sphere's, a group's or the body's bounding centre) moves per rad of each arm joint, m/rad,
    in any configuration (``checker.speed_walk``; inf: no bound, so no certificates).
    Roots, for the certificates' clearances: ``env_reach``, ``env_out_root``,
    ``body_pair_reach``, ``pair_reach``, ``pair_out_root``, ``pair_side_reach``, the square
    roots of ``env_reach2``, ``env_out``, ``body_pair_reach2``, ``pair_reach2``, ``pair_out``,
    ``pair_side_reach2`` (0 where those are -1).
    Clearance tables (``pair_tables``) of body pairs whose distance depends on one or two arm
    joints: ``table_start`` (Q,) the pair's first cell in ``table`` (T,) (-1: no table),
    ``table_joint`` (Q, 2) its joints (arm columns; -1: none), ``table_n`` (Q, 2) cells along
    each (1: none), ``table_wrap`` (Q, 2) 1 where the cells span one turn and wrap,
    ``table_lo``, ``table_step`` (Q, 2) the first cell's lower edge and the cells' width; a
    cell's value, when above 0, is a clearance (m, in the units of ``speed``'s bounds) the
    pair keeps everywhere in it, so that pair needs no sphere test there (``table_clearance``).
    """

    parent: np.ndarray
    kind: np.ndarray
    q_index: np.ndarray
    terms: np.ndarray
    template: np.ndarray
    arm: np.ndarray
    sphere_step: np.ndarray
    p_BS: np.ndarray
    body_step: np.ndarray
    p_BL: np.ndarray
    body_reach: np.ndarray
    group_step: np.ndarray
    p_BG: np.ndarray
    env_group: np.ndarray
    env_body: np.ndarray
    env_reach2: np.ndarray
    env_member: np.ndarray
    env_out: np.ndarray
    env_in: np.ndarray
    body_pair: np.ndarray
    body_pair_reach2: np.ndarray
    body_pair_start: np.ndarray
    pair_group: np.ndarray
    pair_reach2: np.ndarray
    pair_a: np.ndarray
    pair_b: np.ndarray
    pair_out: np.ndarray
    pair_in: np.ndarray
    objects: np.ndarray
    speed: np.ndarray
    env_reach: np.ndarray
    env_out_root: np.ndarray
    body_pair_reach: np.ndarray
    pair_reach: np.ndarray
    pair_out_root: np.ndarray
    pair_side_reach2: np.ndarray
    pair_side_reach: np.ndarray
    table_start: np.ndarray
    table_joint: np.ndarray
    table_n: np.ndarray
    table_wrap: np.ndarray
    table_lo: np.ndarray
    table_step: np.ndarray
    table: np.ndarray


# ------------------------------------------------------------------ packed arrays ----
# A call from Python types and unboxes each array it is given: KernelData's 35 cost 6 us when
# the caches are warm and 40-110 us right after a scene set-up (measured on this project's
# 2-core VM), two arrays 0.5 and ~20 us. ``pack`` puts them in two buffers, ``unpack`` makes
# the KernelData of views on them again in compiled code (``compiled_rrt.solve``).
_HEADER = 5  # ints a field: offset in its buffer, then up to four sizes (1 for missing axes)


def pack(data: KernelData) -> tuple[np.ndarray, np.ndarray]:
    """(floats, ints): the float64 fields in one buffer, and a header (``_HEADER`` ints a
    field: offset, sizes) followed by the int64 fields in the other; ``unpack`` reverses it."""
    header = np.ones(_HEADER * len(data), dtype=np.int64)
    floats, ints = [], []
    offset = {"f": 0, "i": len(header)}
    for k, a in enumerate(data):
        kind = "f" if a.dtype == np.float64 else "i"
        header[_HEADER * k] = offset[kind]
        header[_HEADER * k + 1 : _HEADER * k + 1 + a.ndim] = a.shape
        (floats if kind == "f" else ints).append(a.ravel())
        offset[kind] += a.size
    return (
        np.concatenate(floats) if floats else np.zeros(0),
        np.concatenate([header, *ints]).astype(np.int64),
    )


@njit(cache=True, _nrt=False, inline="always")
def _flat(buffer, header, k):
    """Field k of its buffer, flat; and its sizes."""
    h = _HEADER * k
    n0, n1, n2, n3 = header[h + 1], header[h + 2], header[h + 3], header[h + 4]
    return buffer[header[h] : header[h] + n0 * n1 * n2 * n3], n0, n1, n2, n3


@njit(cache=True, inline="always")
def _v1(buffer, header, k):
    return _flat(buffer, header, k)[0]


@njit(cache=True, inline="always")
def _v2(buffer, header, k):
    flat, n0, n1, _, _ = _flat(buffer, header, k)
    return flat.reshape((n0, n1))


@njit(cache=True, inline="always")
def _v4(buffer, header, k):
    flat, n0, n1, n2, n3 = _flat(buffer, header, k)
    return flat.reshape((n0, n1, n2, n3))


@njit(cache=True)
def unpack(f, i):
    """The ``KernelData`` of ``pack``'s buffers (views on them)."""
    return KernelData(
        _v1(i, i, 0),
        _v1(i, i, 1),
        _v1(i, i, 2),
        _v4(f, i, 3),
        _v1(f, i, 4),
        _v1(i, i, 5),
        _v1(i, i, 6),
        _v2(f, i, 7),
        _v1(i, i, 8),
        _v2(f, i, 9),
        _v1(f, i, 10),
        _v1(i, i, 11),
        _v2(f, i, 12),
        _v1(i, i, 13),
        _v1(i, i, 14),
        _v1(f, i, 15),
        _v2(i, i, 16),
        _v2(f, i, 17),
        _v2(f, i, 18),
        _v2(i, i, 19),
        _v1(f, i, 20),
        _v1(i, i, 21),
        _v2(i, i, 22),
        _v1(f, i, 23),
        _v2(i, i, 24),
        _v2(i, i, 25),
        _v2(f, i, 26),
        _v2(f, i, 27),
        _v2(f, i, 28),
        _v2(f, i, 29),
        _v1(f, i, 30),
        _v2(f, i, 31),
        _v1(f, i, 32),
        _v1(f, i, 33),
        _v2(f, i, 34),
        _v1(f, i, 35),
        _v1(f, i, 36),
        _v1(i, i, 37),
        _v2(i, i, 38),
        _v2(i, i, 39),
        _v2(i, i, 40),
        _v2(f, i, 41),
        _v2(f, i, 42),
        _v1(f, i, 43),
    )


@njit(cache=True, _nrt=False, inline="always")
def _pose_chain(full, parent, kind, q_index, terms, T):
    """X_WC of every step, (J, 3, 4), into T."""
    for s in range(len(parent)):
        a = 0.0
        b = 0.0
        if kind[s] == 1:
            a, b = sincos(full[q_index[s]])
        elif kind[s] == 2:
            a = full[q_index[s]]
        _step(s, a, b, parent, terms, T)


@njit(cache=True, _nrt=False, inline="always")
def _pose_chain_lanes(full, sines, cosines, parent, kind, q_index, terms, T):
    """``_pose_chain`` with the sines and cosines of all of ``full`` taken first, in one loop
    that vectorises (``trig.sincos_lanes``; ``sines``, ``cosines`` are scratch like ``full``):
    the same values."""
    sincos_lanes(full, sines, cosines, len(full))
    for s in range(len(parent)):
        a = 0.0
        b = 0.0
        if kind[s] == 1:
            a = sines[q_index[s]]
            b = cosines[q_index[s]]
        elif kind[s] == 2:
            a = full[q_index[s]]
        _step(s, a, b, parent, terms, T)


@njit(cache=True, _nrt=False, inline="always")
def _row(m, i, a, b):
    """Row i of a step's X_PC = A + a B + b C (``m`` = ``terms[s]``), four scalars; inlined
    with i a constant, so ``_step`` runs the twelve sums written out."""
    return (
        m[0, i, 0] + a * m[1, i, 0] + b * m[2, i, 0],
        m[0, i, 1] + a * m[1, i, 1] + b * m[2, i, 1],
        m[0, i, 2] + a * m[1, i, 2] + b * m[2, i, 2],
        m[0, i, 3] + a * m[1, i, 3] + b * m[2, i, 3],
    )


@njit(cache=True, _nrt=False, inline="always")
def _step(s, a, b, parent, terms, T):
    """T[s] = X_WC of step s = T[parent] (A + a B + b C), written out entry by entry (the
    step's X_PC in twelve scalars, then X_WP X_PC): the loop over a tuple picked by index
    that it replaced took ~12 % longer (the kinematics alone, timed over MBM samples)."""
    m = terms[s]
    m00, m01, m02, m03 = _row(m, 0, a, b)
    m10, m11, m12, m13 = _row(m, 1, a, b)
    m20, m21, m22, m23 = _row(m, 2, a, b)
    p = parent[s]
    out = T[s]
    if p < 0:
        out[0, 0], out[0, 1], out[0, 2], out[0, 3] = m00, m01, m02, m03
        out[1, 0], out[1, 1], out[1, 2], out[1, 3] = m10, m11, m12, m13
        out[2, 0], out[2, 1], out[2, 2], out[2, 3] = m20, m21, m22, m23
        return
    up = T[p]
    for i in range(3):
        r0 = up[i, 0]
        r1 = up[i, 1]
        r2 = up[i, 2]
        r3 = up[i, 3]
        out[i, 0] = r0 * m00 + r1 * m10 + r2 * m20
        out[i, 1] = r0 * m01 + r1 * m11 + r2 * m21
        out[i, 2] = r0 * m02 + r1 * m12 + r2 * m22
        out[i, 3] = r0 * m03 + r1 * m13 + r2 * m23 + r3


@njit(cache=True, _nrt=False)
def _point(T, s, p_B, k, out, row):
    """out[row] = X_W,s p_B[k]: the point k of p_B (K, 3), fixed on step s."""
    x = p_B[k, 0]
    y = p_B[k, 1]
    z = p_B[k, 2]
    for i in range(3):
        out[row, i] = T[s, i, 0] * x + T[s, i, 1] * y + T[s, i, 2] * z + T[s, i, 3]


@njit(cache=True, _nrt=False, inline="always")
def _point_once(T, steps, p_B, k, out, seen, now):
    """``_point`` of point k on step steps[k], unless this check (``now``) has computed it
    already (``seen[k]``): the groups' and spheres' centres on demand (most are never needed).
    Inlined: the same code as written out where it is called."""
    if seen[k] != now:
        _point(T, steps[k], p_B, k, out, k)
        seen[k] = now


@njit(cache=True, _nrt=False, inline="always")
def _points(T, steps, p_B, out):
    """out[k] = X_W,steps[k] p_B[k] for every k (``_point``'s arithmetic, in one loop: a call
    per point took ~25 % longer, timed as ``_step``)."""
    for k in range(len(steps)):
        X = T[steps[k]]
        x = p_B[k, 0]
        y = p_B[k, 1]
        z = p_B[k, 2]
        out[k, 0] = X[0, 0] * x + X[0, 1] * y + X[0, 2] * z + X[0, 3]
        out[k, 1] = X[1, 0] * x + X[1, 1] * y + X[1, 2] * z + X[1, 3]
        out[k, 2] = X[2, 0] * x + X[2, 1] * y + X[2, 2] * z + X[2, 3]


@njit(cache=True, _nrt=False, inline="always")
def _box_gap2(boxes, o, x, y, z):
    """Squared distance from the point (x, y, z) to the axis-aligned box of object o, m^2 (0
    inside): ``boxes`` is (6, O), the lower corners' coordinates, then the upper ones'."""
    gx = max(boxes[0, o] - x, x - boxes[3, o], 0.0)
    gy = max(boxes[1, o] - y, y - boxes[4, o], 0.0)
    gz = max(boxes[2, o] - z, z - boxes[5, o], 0.0)
    return gx * gx + gy * gy + gz * gz


@njit(cache=True, _nrt=False, inline="always")
def _distance2(x, y, z, obj):
    """Squared distance from the point (x, y, z) to the object of row ``obj``, m^2 (0 inside)."""
    u = obj[1] * x + obj[2] * y + obj[3] * z - obj[10]
    v = obj[4] * x + obj[5] * y + obj[6] * z - obj[11]
    w = obj[7] * x + obj[8] * y + obj[9] * z - obj[12]
    total = 0.0
    if obj[0] == 0.0:  # box
        u = abs(u) - obj[13]
        v = abs(v) - obj[14]
        w = abs(w) - obj[15]
        if u > 0.0:
            total += u * u
        if v > 0.0:
            total += v * v
        if w > 0.0:
            total += w * w
    elif obj[0] == 1.0:  # cylinder along its z axis
        radial = np.sqrt(u * u + v * v) - obj[13]
        axial = abs(w) - obj[14]
        if radial > 0.0:
            total += radial * radial
        if axial > 0.0:
            total += axial * axial
    else:  # sphere
        gap = np.sqrt(u * u + v * v + w * w) - obj[13]
        if gap > 0.0:
            total = gap * gap
    return total


@njit(cache=True, _nrt=False)
def _gap2(a, i, b, j):
    """Squared distance between the points a[i] and b[j], m^2."""
    u = a[i, 0] - b[j, 0]
    v = a[i, 1] - b[j, 1]
    w = a[i, 2] - b[j, 2]
    return u * u + v * v + w * w


@njit(cache=True, _nrt=False)
def _band(d2, inner2, outer2):
    """COLLIDING when the squared distance d2 is below the inner band (the spheres that lie
    inside the geometry overlap), UNKNOWN below the outer band, else FREE."""
    if d2 < inner2:
        return COLLIDING
    if d2 < outer2:
        return UNKNOWN
    return FREE


SELF_UNKNOWN = -1.0  # ``_classify_one``'s radius for an UNKNOWN of the robot's own pairs alone


@njit(cache=True, _nrt=False, inline="always")
def table_clearance(d, p, q):
    """The clearance body pair p keeps at the arm configuration q (D,) by its table (m, in the
    units of ``speed``'s bounds; see ``KernelData``), 0 when it has no table or q lies outside
    it (or is not finite): then its spheres decide."""
    start = d.table_start[p]
    if start < 0:
        return 0.0
    index = 0
    for k in range(2):
        j = d.table_joint[p, k]
        if j < 0:
            break
        n = d.table_n[p, k]
        x = (q[j] - d.table_lo[p, k]) / d.table_step[p, k]
        if d.table_wrap[p, k] != 0:
            x -= n * np.floor(x / n)
        if not (x >= 0.0 and x < n):
            return 0.0
        index = index * n + int(x)
    return d.table[start + index]


@njit(cache=True, _nrt=False, inline="always")
def _classify_one(q, d, stop_at_unknown, work, lam):
    """(verdict, radius) for the arm configuration q (D,): FREE, COLLIDING or UNKNOWN, and for
    a FREE one how far (rad, joint-space L2) q may move along a direction whose bodies' speed
    bounds are ``lam`` (L + Q,), m per rad (``edge_speeds``), with every sphere staying FREE
    (inf when nothing moves; 0 for a verdict other than FREE). With ``stop_at_unknown``,
    returns at the first uncertain sphere (UNKNOWN, though a later sphere might prove a
    collision), the radius then ``SELF_UNKNOWN`` when that sphere is one of a pair of the
    robot's own and every sphere was proven FREE of the objects. ``work`` holds scratch arrays
    (``_work``).

    The radius is each test's clearance (the distance beyond its threshold: body, group or
    sphere against the objects, and body, group or sphere pairs) over the speed bound of what
    it compares; the distance to a convex object changes no faster than the point moves. The
    centres on demand (``_point_once``) are inlined where they are needed, the same code as
    written out: as calls, they measured twice as slow."""
    for k in range(len(q)):
        if not np.isfinite(q[k]):
            return UNKNOWN, 0.0  # never proven free: comparisons with NaN are all false
    full, T, centres, seen, bodies, groups, near, stamp, before, far, boxes, gaps = work[:12]
    sines, cosines, group_seen = work[12:]
    stamp[0] += 1
    now = stamp[0]
    for k in range(len(d.arm)):
        full[d.arm[k]] = q[k]
    _pose_chain_lanes(full, sines, cosines, d.parent, d.kind, d.q_index, d.terms, T)
    _points(T, d.body_step, d.p_BL, bodies)
    radius = np.inf
    # Objects near each body (axis-aligned boxes around them against the body's sphere); the
    # others were at least far[b] (the least box distance minus the body's reach) away when the
    # list was made, with the body's centre at before[b]. The list holds while the centre stays
    # within far[b] of there: along an edge, most samples keep it.
    objects = d.objects
    n_obj = len(objects)
    for b in range(len(d.body_step)):
        u = bodies[b, 0] - before[b, 0]
        v = bodies[b, 1] - before[b, 1]
        w = bodies[b, 2] - before[b, 2]
        moved2 = u * u + v * v + w * w
        if not (far[b] > 0.0 and moved2 < far[b] * far[b]):
            x = bodies[b, 0]
            y = bodies[b, 1]
            z = bodies[b, 2]
            for o in range(n_obj):  # the boxes' corners by coordinate: a loop that vectorises
                gaps[o] = _box_gap2(boxes, o, x, y, z)
            count = 0
            far2 = np.inf
            reach2 = d.body_reach[b] * d.body_reach[b]
            for o in range(n_obj):
                if gaps[o] < reach2:
                    near[b, count] = o
                    count += 1
                else:
                    far2 = min(far2, gaps[o])
            near[b, n_obj] = count
            far[b] = np.sqrt(far2) - d.body_reach[b]  # inf when every object is near
            before[b, 0] = bodies[b, 0]
            before[b, 1] = bodies[b, 1]
            before[b, 2] = bodies[b, 2]
            moved2 = 0.0
        if lam[b] > 0.0 and far[b] < np.inf:
            radius = min(radius, (far[b] - np.sqrt(moved2)) / lam[b])
    state = FREE
    # From the hand back (the rows go from the base out): collisions show sooner, 3 % less time
    # per MBM request (interleaved A/B over 175 problems).
    for e in range(len(d.env_group) - 1, -1, -1):
        b = d.env_body[e]
        count = near[b, n_obj]
        if count == 0:
            continue
        g = d.env_group[e]
        _point_once(T, d.group_step, d.p_BG, g, groups, group_seen, now)
        # The least squared distance to the near objects, or a lower bound of it that proves
        # the group out of reach: an object's axis-aligned box first (no rotation), its exact
        # distance only when the box comes within reach (per-problem median 0.983x on MBM,
        # the same paths; ``benchmarks/planner_ab.py``). A bound gives a smaller radius, still
        # a safe one; the box holds the object up to rounding, which the thresholds' margin
        # (``sphere_arrays.MARGIN``) covers.
        x = groups[g, 0]
        y = groups[g, 1]
        z = groups[g, 2]
        reach2 = d.env_reach2[e]
        close2 = np.inf
        for i in range(count):
            o = near[b, i]
            box2 = _box_gap2(boxes, o, x, y, z)
            close2 = min(close2, box2 if box2 >= reach2 else _distance2(x, y, z, objects[o]))
        if close2 >= reach2:
            if lam[b] > 0.0:
                radius = min(radius, (np.sqrt(close2) - d.env_reach[e]) / lam[b])
            continue
        for m in range(d.env_member.shape[1]):
            if d.env_out[e, m] < 0.0:
                continue
            c = d.env_member[e, m]
            _point_once(T, d.sphere_step, d.p_BS, c, centres, seen, now)
            best = np.inf
            for i in range(count):
                o = near[b, i]
                best = min(
                    best, _distance2(centres[c, 0], centres[c, 1], centres[c, 2], objects[o])
                )
            verdict = _band(best, d.env_in[e, m], d.env_out[e, m])
            if verdict != FREE:
                if verdict == COLLIDING or stop_at_unknown:
                    return verdict, 0.0
                state = UNKNOWN
            elif lam[b] > 0.0:
                radius = min(radius, (np.sqrt(best) - d.env_out_root[e, m]) / lam[b])
    for p in range(len(d.body_pair_reach2)):
        a_body = d.body_pair[p, 0]
        b_body = d.body_pair[p, 1]
        speed = lam[len(d.body_step) + p]
        clear = table_clearance(d, p, q)
        if clear > 0.0:  # the pair's table proves it apart here: no sphere test
            if speed > 0.0:
                radius = min(radius, clear / speed)
            continue
        gap2 = _gap2(bodies, a_body, bodies, b_body)
        if gap2 >= d.body_pair_reach2[p]:
            if speed > 0.0:
                radius = min(radius, (np.sqrt(gap2) - d.body_pair_reach[p]) / speed)
            continue
        # Each first group against the other body's bounding sphere, then its group pairs.
        last = -1
        side_far = False
        for k in range(d.body_pair_start[p], d.body_pair_start[p + 1]):
            g = d.pair_group[k, 0]
            if g != last:
                last = g
                _point_once(T, d.group_step, d.p_BG, g, groups, group_seen, now)
                gap2 = _gap2(groups, g, bodies, b_body)
                side_far = gap2 >= d.pair_side_reach2[k]
                if side_far and speed > 0.0:
                    radius = min(radius, (np.sqrt(gap2) - d.pair_side_reach[k]) / speed)
            if side_far:
                continue
            h = d.pair_group[k, 1]
            _point_once(T, d.group_step, d.p_BG, h, groups, group_seen, now)
            gap2 = _gap2(groups, g, groups, h)
            if gap2 >= d.pair_reach2[k]:
                if speed > 0.0:
                    radius = min(radius, (np.sqrt(gap2) - d.pair_reach[k]) / speed)
                continue
            for m in range(d.pair_a.shape[1]):
                if d.pair_out[k, m] < 0.0:
                    continue
                i = d.pair_a[k, m]
                j = d.pair_b[k, m]
                _point_once(T, d.sphere_step, d.p_BS, i, centres, seen, now)
                _point_once(T, d.sphere_step, d.p_BS, j, centres, seen, now)
                u = centres[i, 0] - centres[j, 0]
                v = centres[i, 1] - centres[j, 1]
                w = centres[i, 2] - centres[j, 2]
                gap2 = u * u + v * v + w * w
                verdict = _band(gap2, d.pair_in[k, m], d.pair_out[k, m])
                if verdict != FREE:
                    if verdict == COLLIDING:
                        return verdict, 0.0
                    if stop_at_unknown:  # every sphere was FREE of the objects
                        return verdict, SELF_UNKNOWN
                    state = UNKNOWN
                elif speed > 0.0:
                    radius = min(radius, (np.sqrt(gap2) - d.pair_out_root[k, m]) / speed)
    if state != FREE:
        return state, 0.0
    return state, max(radius, 0.0)


@njit(cache=True)
def _work(d):
    """Scratch arrays of ``_classify_one``."""
    n_obj = len(d.objects)
    return (
        d.template.copy(),
        np.empty((len(d.parent), 3, 4)),
        np.empty((len(d.sphere_step), 3)),
        np.zeros(len(d.sphere_step), dtype=np.int64),
        np.empty((len(d.body_step), 3)),
        np.empty((len(d.group_step), 3)),
        np.empty((len(d.body_step), n_obj + 1), dtype=np.int64),
        np.zeros(1, dtype=np.int64),
        np.zeros((len(d.body_step), 3)),  # the bodies' centres when their lists were made
        np.full(len(d.body_step), -1.0),  # their margins to the far objects then (< 0: none)
        d.objects[:, OBJ_LOWER : OBJ_UPPER + 3].T.copy(),  # the objects' boxes' corners, (6, O)
        np.empty(n_obj),  # squared distances from a body's centre to them
        np.empty(len(d.template)),  # sines of the plant positions
        np.empty(len(d.template)),  # cosines
        np.zeros(len(d.group_step), dtype=np.int64),  # the check that computed each group centre
    )


@njit(cache=True)
def transforms(fulls, parent, kind, q_index, terms):
    """X_WC of every step for each row of plant positions ``fulls`` (N, nq): (N, J, 3, 4)."""
    out = np.empty((len(fulls), len(parent), 3, 4))
    for n in range(len(fulls)):
        _pose_chain(fulls[n], parent, kind, q_index, terms, out[n])
    return out


@njit(cache=True)
def prefixes(q_a, q_b, step, stop_at_unknown, d):
    """Samples segments q_a[k] -> q_b[k] (rows, rad) every ``step`` at most and classifies each
    segment's samples t = 1/n, 2/n, ..., 1 in order up to its first blocking one (COLLIDING,
    or UNKNOWN too with ``stop_at_unknown``).

    Returns:
        (first, n, unknown_edge, unknown_local): per segment, the index of its first blocking
        sample (n when none) and its number of samples n; and the (segment, sample index)
        of every UNKNOWN sample before the segment's first blocking one.
    """
    work = _work(d)
    still = np.zeros(len(d.body_step) + len(d.body_pair))  # no certificates needed here
    count = len(q_a)
    first = np.empty(count, dtype=np.int64)
    n = np.empty(count, dtype=np.int64)
    for k in range(count):
        length = 0.0
        for j in range(q_a.shape[1]):
            length += (q_b[k, j] - q_a[k, j]) ** 2
        # One sample (the end) for a segment of unknown length, e.g. with a NaN end.
        n[k] = max(1, int(np.ceil(np.sqrt(length) / step))) if np.isfinite(length) else 1
    unknown_edge = np.empty(n.sum(), dtype=np.int64)
    unknown_local = np.empty(n.sum(), dtype=np.int64)
    q = np.empty(q_a.shape[1])
    n_unknown = _prefix_samples(
        q_a, q_b, n, stop_at_unknown, d, work, still, q, first, unknown_edge, unknown_local
    )
    return first, n, unknown_edge[:n_unknown], unknown_local[:n_unknown]


@njit(cache=True, _nrt=False)
def _prefix_samples(
    q_a, q_b, n, stop_at_unknown, d, work, still, q, first, unknown_edge, unknown_local
):
    """``prefixes``' loop over the samples, filling ``first``, ``unknown_edge`` and
    ``unknown_local`` and returning how many UNKNOWN samples it found. A function of its own,
    compiled without reference counting: inside ``prefixes``, which allocates and so counts
    references, every array of ``d`` and ``work`` was counted in and out around each inlined
    ``_classify_one``, which made a check 2.6 times as long (0.86 against 2.2 us a
    configuration on MBM scenes, this project's 2-core VM)."""
    n_unknown = 0
    for k in range(len(q_a)):
        first[k] = n[k]
        for i in range(n[k]):
            t = (i + 1) / n[k]
            for j in range(q_a.shape[1]):
                q[j] = q_a[k, j] + t * (q_b[k, j] - q_a[k, j])
            s = _classify_one(q, d, stop_at_unknown, work, still)[0]
            if s == COLLIDING or (stop_at_unknown and s == UNKNOWN):
                first[k] = i
                break
            if s == UNKNOWN:
                unknown_edge[n_unknown] = k
                unknown_local[n_unknown] = i
                n_unknown += 1
    return n_unknown


@njit(cache=True, _nrt=False)
def edge_speeds(q_a, q_b, d, lam):
    """Fills ``lam`` (L + Q,) with the speed bounds along the segment q_a -> q_b, m per rad of
    joint-space L2 distance: each body's (the sum over the joints of its speed times the
    direction's share), then each checked body pair's, the rate at which the distance between
    their points may shrink. A joint moving both bodies of a pair turns them together and
    keeps their distances: only the other joints count, each with both bodies' speeds.
    Returns the segment's length, rad."""
    length = 0.0
    for j in range(len(q_a)):
        length += (q_b[j] - q_a[j]) ** 2
    length = np.sqrt(length)
    bodies = len(d.body_step)
    for b in range(bodies):
        total = 0.0
        if length > 0.0:
            for j in range(len(q_a)):
                u = abs(q_b[j] - q_a[j]) / length
                if u > 0.0:
                    total += d.speed[b, j] * u
        lam[b] = total
    for p in range(len(d.body_pair)):
        a = d.body_pair[p, 0]
        b = d.body_pair[p, 1]
        total = 0.0
        if length > 0.0:
            for j in range(len(q_a)):
                if d.speed[a, j] > 0.0 and d.speed[b, j] > 0.0:
                    continue  # turns both bodies together
                u = abs(q_b[j] - q_a[j]) / length
                if u > 0.0:
                    total += (d.speed[a, j] + d.speed[b, j]) * u
        lam[bodies + p] = total
    return length


@njit(cache=True, _nrt=False)
def motion_margins(motion, speed, body_pair, out):
    """Fills ``out`` (L + Q,) with how far, m, each body's points may move (rows of ``speed``,
    ``KernelData.speed`` or ``HullData.speed``), then how much the distances between each
    pair's (``body_pair`` (Q, 2)) may shrink, while the arm moves by at most ``motion[j]``
    rad in each joint j (``edge_speeds``' bounds times a displacement; a joint that moves both
    bodies of a pair does not count for it). Validating a configuration with these added to
    its clearances validates every configuration within ``motion`` of it
    (``compiled_rrt._fine_check``). A joint of infinite speed (no bound) that moves gives inf."""
    bodies = len(speed)
    for b in range(bodies):
        total = 0.0
        for j in range(len(motion)):
            if motion[j] > 0.0:
                total += speed[b, j] * motion[j]
        out[b] = total
    for p in range(len(body_pair)):
        a = body_pair[p, 0]
        b = body_pair[p, 1]
        total = 0.0
        for j in range(len(motion)):
            if motion[j] > 0.0 and not (speed[a, j] > 0.0 and speed[b, j] > 0.0):
                total += (speed[a, j] + speed[b, j]) * motion[j]
        out[bodies + p] = total


@njit(cache=True, _nrt=False)
def _near_any(q, anchors, radius):
    """True when q is within ``radius`` (joint-space L2) of a row of ``anchors``."""
    for k in range(len(anchors)):
        total = 0.0
        for j in range(len(q)):
            total += (q[j] - anchors[k, j]) ** 2
        if total <= radius * radius:
            return True
    return False


# ------------------------------------------------------------------- compile note ----
COMPILE_NOTE = (
    "note: compiling the collision kernel and planner once for this machine (2 to 4 minutes)..."
)
_announce_lock = threading.Lock()
_announce_done = False  # announce_compile has looked, in this process


def cache_is_cold(dispatcher=None) -> bool:
    """True when the next call of ``dispatcher`` (``prefixes`` when None) compiles it: it is not
    compiled in this process yet and numba's on-disk cache has no entry for this machine and
    this source (no index file, a stale one, no key with this CPU and bytecode, or its data file
    gone). False when that cannot be told (caching off, numba's internals changed)."""
    dispatcher = prefixes if dispatcher is None else dispatcher
    try:
        if dispatcher.signatures:
            return False
        cache = dispatcher._cache
        files = cache._cache_file
        # Keys are (signature, machine, bytecode hashes); the signature is only known at the call.
        wanted = cache._index_key(None, dispatcher.targetctx.codegen())[1:]
        entries = files._load_index().items()  # {} when missing or stale
        return not any(
            key[1:] == wanted and os.path.isfile(files._data_path(name)) for key, name in entries
        )
    except Exception:
        return False


def announce_compile(*others, note: str = COMPILE_NOTE, kernel: bool = True) -> bool:
    """Prints ``note`` on stderr when ``prefixes`` (unless ``kernel`` is False) or one of the
    ``others`` dispatchers is about to be compiled (``cache_is_cold``), at most once per
    process; only the first call looks at the cache, later calls return at once. Call it just
    before the first call.

    Returns:
        True when it printed the note.
    """
    global _announce_done
    if _announce_done:
        return False
    with _announce_lock:
        if _announce_done:
            return False
        _announce_done = True
        if not ((kernel and cache_is_cold()) or any(cache_is_cold(o) for o in others)):
            return False
    print(note, file=sys.stderr, flush=True)
    return True


def refresh_cache(module, sources, cache_dir) -> None:
    """Drops the cached machine code of ``module``'s compiled functions when one of the
    ``sources`` (paths: the module's own file and those whose compiled code it inlines, this
    kernel's above all) changed.

    Numba keys a cached function on its own file's time stamp only, while a function that
    calls this kernel's compiles the kernel's code into its own: after a change of the kernel
    alone (a ``git pull``), its stale code would run against the new data layout and crash. A
    hash of the sources is kept beside the cache; when it differs, the caches of the functions
    defined in ``module`` are emptied (numba then compiles them again, once). When that cannot
    be done (a read-only cache), they are not cached at all.
    """
    digest = hashlib.sha256(b"".join(Path(p).read_bytes() for p in sources)).hexdigest()
    dispatchers = [
        v
        for v in vars(module).values()
        if hasattr(v, "py_func") and v._cache and v.py_func.__module__ == module.__name__
    ]
    try:
        marker = Path(cache_dir) / f"{Path(module.__file__).stem}.kernel.sha256"
        if marker.is_file() and marker.read_text() == digest:
            return
        for dispatcher in dispatchers:
            dispatcher._cache.flush()
        marker.write_text(digest)
    except OSError:
        for dispatcher in dispatchers:
            dispatcher._cache = NullCache()


# The kernels inline ``trig.sincos``: their caches go stale when it changes.
refresh_cache(
    sys.modules[__name__], [Path(__file__), Path(trig.__file__)], Path(prefixes._cache._cache_path)
)
