"""The sphere classification of ``sphere_kernel._classify_one``, eight configurations at a time.

``classify_batch`` runs the same tests with the same arithmetic, each value held for up to
``LANES`` configurations side by side (structure of arrays: the lane is the last, contiguous
axis), so that the compiler turns the loops over the lanes into SIMD instructions: forward
kinematics, the bodies', groups' and spheres' centres, and the point-to-object and sphere-pair
distances. Culling is shared by the lanes: an object is near a body when its box comes within
the body's reach of the box around that body's centres in all lanes, and a group, group pair or
sphere is tested when any lane needs it (a group's centres computed then); the verdict of
a lane only counts the tests that lane itself needs, so every lane gets the verdict
``_classify_one`` gives its configuration with ``stop_at_unknown`` false (COLLIDING when a
sphere proves a collision, else UNKNOWN when one cannot decide, else FREE). The lanes of a batch
are consecutive samples along a path, close together, so they mostly need the same tests.

No certificates (clearance radii) here: the batch is for checking every sample of a path (the
fine check, ``compiled_rrt._fine_check``), where skipping samples one certificate at a time is
not worth its cost (measured on the MBM paths: the median radius is 0.001 to 0.006 rad, below
the 0.01 rad between fine samples). ``FIRST_BLOCK`` mode answers whether any lane blocks an
edge; the search's edges do not use it now (their bisection levels in batches measured no
faster than one sample at a time: the edges are short, and a blocked one shows it early).

Group centres on demand and the near objects from the lanes' box, where every group's centres
and every object against every lane were computed before: 0.75x the time per sample of MBM
paths (0.44 -> 0.33 us, 32 lanes, the same verdicts on 137k samples of paths and searches).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from numba import njit

from planning.collision import lane_geometry, sphere_kernel, trig
from planning.collision.lane_geometry import centre_once, min_distance2, points, within
from planning.collision.sphere_kernel import (
    COLLIDING,
    FREE,
    UNKNOWN,
    motion_margins,
    refresh_cache,
    table_clearance,
)
from planning.collision.trig import sincos_lanes

# Configurations per batch, at most. The loops over lanes run to a count known only at run time,
# which LLVM vectorises (with a fixed count of 8 it unrolled them into scalar code instead).
# Measured per configuration on the samples of MBM paths (2-core VM, scalar kernel 1.7-2.5 us):
# 8 lanes 1.2-1.6 us, 16 lanes 0.7-1.0 us, 32 lanes 0.6-0.76 us.
LANES = 32
FULL, FIRST_BLOCK = 0, 1  # classify_batch's modes


@njit(cache=True)
def batch_work(d, lanes=LANES):
    """Scratch arrays of ``classify_batch`` for the model ``d`` (a ``KernelData``), for up to
    ``lanes`` configurations a batch."""
    k = lanes
    return (
        np.empty((len(d.template), k)),  # plant positions, by lane
        np.empty((len(d.parent), 12, k)),  # X_WC of every step, 3x4 row-major
        np.empty((len(d.sphere_step), 3, k)),  # sphere centres, when a lane needs them
        np.zeros(len(d.sphere_step), dtype=np.int64),  # the batch that computed them
        np.empty((len(d.body_step), 3, k)),  # body centres
        np.empty((len(d.group_step), 3, k)),  # group centres
        np.empty((len(d.body_step), len(d.objects) + 1), dtype=np.int64),  # near objects, count
        np.zeros(1, dtype=np.int64),  # batch counter
        np.empty((7, k)),  # per lane: a, b, distances, best, mask, pair mask, side mask
        np.empty((12, k)),  # the step's X_PC
        np.zeros((3, k), dtype=np.bool_),  # per lane: colliding, unknown, not finite
        np.zeros(len(d.group_step), dtype=np.int64),  # the batch that computed each group centre
    )


@njit(cache=True, _nrt=False)
def _stop(flags, excused, mode, lanes):
    """True when the batch can stop: in FULL mode every lane is COLLIDING; in FIRST_BLOCK mode
    some lane is COLLIDING, or UNKNOWN without being ``excused``."""
    colliding, unknown = flags[0], flags[1]
    if mode == FULL:
        for lane in range(lanes):  # noqa: SIM110 (plain loops compile best in numba)
            if not colliding[lane]:
                return False
        return True
    for lane in range(lanes):  # noqa: SIM110
        if colliding[lane] or (unknown[lane] and not excused[lane]):
            return True
    return False


@njit(cache=True, _nrt=False)
def _verdicts(flags, verdict, lanes):
    """verdict = UNKNOWN for non-finite lanes, else COLLIDING, UNKNOWN or FREE by the flags."""
    colliding, unknown, bad = flags[0], flags[1], flags[2]
    for lane in range(lanes):
        if bad[lane]:
            verdict[lane] = UNKNOWN
        elif colliding[lane]:
            verdict[lane] = COLLIDING
        elif unknown[lane]:
            verdict[lane] = UNKNOWN
        else:
            verdict[lane] = FREE


@njit(cache=True, _nrt=False)
def classify_batch(qs, count, d, work, mode, excused, verdict, margin):
    """Classifies the arm configurations ``qs[:count]`` (rows, rad; 1 <= count <= the lanes
    of ``work``), each threshold that proves a lane free widened by ``margin``.

    Args:
        qs: (>= count, D) configurations.
        count: how many rows to classify.
        d: the sphere model's ``KernelData``.
        work: ``batch_work(d, lanes)`` with lanes >= count.
        mode: FULL, every lane's verdict (stopping early only when all lanes collide); or
            FIRST_BLOCK, stop as soon as a lane is COLLIDING, or UNKNOWN with ``excused`` false.
        excused: (>= count,) bool, FIRST_BLOCK's UNKNOWN lanes that do not block.
        verdict: (>= count,) int64 out: FREE, COLLIDING or UNKNOWN for the first ``count`` lanes;
            after an early stop, the verdicts of the tests done so far (a lane shown FREE then
            may not be).
        margin: (L + Q,) m, or empty: none. A lane is FREE only when each body's spheres are
            ``margin[b]`` farther from the objects than they need be, and each checked body
            pair's ``margin[L + p]`` farther apart (``sphere_kernel.motion_margins``: then
            every configuration within that motion of the lane is free too). COLLIDING is not
            widened: it stays a proof about the lane itself.

    Returns:
        True when a lane blocks (FIRST_BLOCK mode; in FULL mode, when every lane collides).
    """
    fulls, T, centres, seen, bodies, groups, near, stamp, lane_rows, m, flags, group_seen = work
    stamp[0] += 1
    now = stamp[0]
    colliding, unknown, bad = flags[0], flags[1], flags[2]
    lanes = count
    # A non-finite configuration is UNKNOWN (never proven free), computed at 0 so that no NaN
    # reaches a comparison.
    for lane in range(lanes):
        colliding[lane] = False
        bad[lane] = False
        for i in range(len(d.template)):
            fulls[i, lane] = d.template[i]
        for j in range(len(d.arm)):
            x = qs[lane, j]
            if not np.isfinite(x):
                bad[lane] = True
                x = 0.0
            fulls[d.arm[j], lane] = x
        unknown[lane] = bad[lane]
    if mode == FIRST_BLOCK and _stop(flags, excused, mode, lanes):
        _verdicts(flags, verdict, lanes)
        return True
    # Forward kinematics (``sphere_kernel._pose_chain``'s arithmetic, by lane).
    a = lane_rows[0]
    b = lane_rows[1]
    for s in range(len(d.parent)):
        kind = d.kind[s]
        qi = d.q_index[s]
        if kind == 1:
            sincos_lanes(fulls[qi], a, b, lanes)
        elif kind == 2:
            for lane in range(lanes):
                a[lane] = fulls[qi, lane]
                b[lane] = 0.0
        else:
            for lane in range(lanes):
                a[lane] = 0.0
                b[lane] = 0.0
        for e in range(12):
            t0 = d.terms[s, 0, e // 4, e % 4]
            t1 = d.terms[s, 1, e // 4, e % 4]
            t2 = d.terms[s, 2, e // 4, e % 4]
            me = m[e]
            for lane in range(lanes):
                me[lane] = t0 + a[lane] * t1 + b[lane] * t2
        p = d.parent[s]
        if p < 0:
            for e in range(12):
                out = T[s, e]
                me = m[e]
                for lane in range(lanes):
                    out[lane] = me[lane]
            continue
        for i in range(3):
            r0 = T[p, 4 * i]
            r1 = T[p, 4 * i + 1]
            r2 = T[p, 4 * i + 2]
            r3 = T[p, 4 * i + 3]
            for j in range(4):
                x0 = m[j]
                x1 = m[4 + j]
                x2 = m[8 + j]
                out = T[s, 4 * i + j]
                if j == 3:
                    for lane in range(lanes):
                        out[lane] = (
                            r0[lane] * x0[lane]
                            + r1[lane] * x1[lane]
                            + r2[lane] * x2[lane]
                            + r3[lane]
                        )
                else:
                    for lane in range(lanes):
                        out[lane] = r0[lane] * x0[lane] + r1[lane] * x1[lane] + r2[lane] * x2[lane]
    for body in range(len(d.body_step)):
        points(T, d.body_step[body], d.p_BL, body, bodies, body, lanes)
    # Objects near each body in some lane: the box around the body's centre in every lane
    # against each object's axis-aligned box, within the body's reach (a superset of the objects
    # near it lane by lane, whose tests below count only for the lanes within reach; 6 tests an
    # object, not 6 a lane).
    objects = d.objects
    n_obj = len(objects)
    widen = len(margin) > 0
    bodies_count = len(d.body_step)
    for body in range(len(d.body_step)):
        reach = d.body_reach[body] + (margin[body] if widen else 0.0)
        x = bodies[body, 0]
        y = bodies[body, 1]
        z = bodies[body, 2]
        lo_x = hi_x = x[0]
        lo_y = hi_y = y[0]
        lo_z = hi_z = z[0]
        for lane in range(1, lanes):
            lo_x = min(lo_x, x[lane])
            hi_x = max(hi_x, x[lane])
            lo_y = min(lo_y, y[lane])
            hi_y = max(hi_y, y[lane])
            lo_z = min(lo_z, z[lane])
            hi_z = max(hi_z, z[lane])
        count_near = 0
        for o in range(n_obj):
            gx = max(objects[o, 16] - hi_x, lo_x - objects[o, 19], 0.0)
            gy = max(objects[o, 17] - hi_y, lo_y - objects[o, 20], 0.0)
            gz = max(objects[o, 18] - hi_z, lo_z - objects[o, 21], 0.0)
            if gx * gx + gy * gy + gz * gz < reach * reach:
                near[body, count_near] = o
                count_near += 1
        near[body, n_obj] = count_near
    dist = lane_rows[2]
    best = lane_rows[3]
    mask = lane_rows[4]
    # The world: groups against the objects near their body, then their spheres.
    for e in range(len(d.env_group)):
        body = d.env_body[e]
        count_near = near[body, n_obj]
        if count_near == 0:
            continue
        g = d.env_group[e]
        centre_once(T, d.group_step, d.p_BG, g, groups, group_seen, now, lanes)
        dist[:lanes] = np.inf
        for i in range(count_near):
            min_distance2(groups[g], objects[near[body, i]], dist, lanes)
        reach2 = d.env_reach2[e]
        extra = margin[body] if widen else 0.0
        if extra > 0.0:
            reach2 = (d.env_reach[e] + extra) ** 2
        any_near = False
        for lane in range(lanes):
            inside = dist[lane] < reach2
            mask[lane] = 1.0 if inside else 0.0
            any_near |= inside
        if not any_near:
            continue
        for k in range(d.env_member.shape[1]):
            if d.env_out[e, k] < 0.0:
                continue
            c = d.env_member[e, k]
            centre_once(T, d.sphere_step, d.p_BS, c, centres, seen, now, lanes)
            best[:lanes] = np.inf
            for i in range(count_near):
                min_distance2(centres[c], objects[near[body, i]], best, lanes)
            inner2 = d.env_in[e, k]
            outer2 = d.env_out[e, k]
            if extra > 0.0:
                outer2 = (d.env_out_root[e, k] + extra) ** 2
            for lane in range(lanes):
                if mask[lane] > 0.0:
                    colliding[lane] |= best[lane] < inner2
                    unknown[lane] |= best[lane] < outer2
        if _stop(flags, excused, mode, lanes):
            _verdicts(flags, verdict, lanes)
            return True
    # Self-collision: body pairs, then group pairs, then sphere pairs.
    pair_mask = lane_rows[5]
    side_mask = lane_rows[6]
    for p in range(len(d.body_pair_reach2)):
        a_body = d.body_pair[p, 0]
        b_body = d.body_pair[p, 1]
        reach2 = d.body_pair_reach2[p]
        extra = margin[bodies_count + p] if widen else 0.0
        if extra > 0.0:
            reach2 = (d.body_pair_reach[p] + extra) ** 2
        any_near = False
        tabled = d.table_start[p] >= 0
        for lane in range(lanes):
            u = bodies[a_body, 0, lane] - bodies[b_body, 0, lane]
            v = bodies[a_body, 1, lane] - bodies[b_body, 1, lane]
            w = bodies[a_body, 2, lane] - bodies[b_body, 2, lane]
            inside = u * u + v * v + w * w < reach2
            if inside and tabled:  # the pair's table proves it apart, widened: no sphere test
                inside = not table_clearance(d, p, qs[lane]) > extra
            mask[lane] = 1.0 if inside else 0.0
            any_near |= inside
        if not any_near:
            continue
        # Each first group against the other body's bounding sphere, then its group pairs.
        last = -1
        side_near = False
        for k in range(d.body_pair_start[p], d.body_pair_start[p + 1]):
            ga = d.pair_group[k, 0]
            if ga != last:
                last = ga
                centre_once(T, d.group_step, d.p_BG, ga, groups, group_seen, now, lanes)
                reach2 = d.pair_side_reach2[k]
                if extra > 0.0:
                    reach2 = (d.pair_side_reach[k] + extra) ** 2
                side_near = within(groups[ga], bodies[b_body], reach2, mask, side_mask, lanes)
            if not side_near:
                continue
            gb = d.pair_group[k, 1]
            centre_once(T, d.group_step, d.p_BG, gb, groups, group_seen, now, lanes)
            reach2 = d.pair_reach2[k]
            if extra > 0.0:
                reach2 = (d.pair_reach[k] + extra) ** 2
            if not within(groups[ga], groups[gb], reach2, side_mask, pair_mask, lanes):
                continue
            for n in range(d.pair_a.shape[1]):
                if d.pair_out[k, n] < 0.0:
                    continue
                i = d.pair_a[k, n]
                j = d.pair_b[k, n]
                centre_once(T, d.sphere_step, d.p_BS, i, centres, seen, now, lanes)
                centre_once(T, d.sphere_step, d.p_BS, j, centres, seen, now, lanes)
                inner2 = d.pair_in[k, n]
                outer2 = d.pair_out[k, n]
                if extra > 0.0:
                    outer2 = (d.pair_out_root[k, n] + extra) ** 2
                for lane in range(lanes):
                    u = centres[i, 0, lane] - centres[j, 0, lane]
                    v = centres[i, 1, lane] - centres[j, 1, lane]
                    w = centres[i, 2, lane] - centres[j, 2, lane]
                    gap2 = u * u + v * v + w * w
                    if pair_mask[lane] > 0.0:
                        colliding[lane] |= gap2 < inner2
                        unknown[lane] |= gap2 < outer2
        if _stop(flags, excused, mode, lanes):
            _verdicts(flags, verdict, lanes)
            return True
    _verdicts(flags, verdict, lanes)
    return mode == FULL and _stop(flags, excused, mode, lanes)


@njit(cache=True)
def classify_many(qs, d, motion):
    """FREE, COLLIDING or UNKNOWN for each row of qs (N, D), rad: ``classify_batch`` in FULL
    mode, ``LANES`` rows per call (the scalar kernel's verdicts, about three times faster per
    configuration); an int8 array (N,). ``motion`` (N, D) rad, or (0, D): none; FREE then
    also says that every configuration within motion[n, j] of row n in each joint j is free
    (``sphere_kernel.motion_margins``; a batch takes the largest margins of its rows)."""
    out = np.empty(len(qs), dtype=np.int8)
    if len(qs) == 0:
        return out
    lanes = min(LANES, len(qs))
    work = batch_work(d, lanes)
    batch = np.empty((lanes, qs.shape[1]))
    verdict = np.empty(lanes, dtype=np.int64)
    excused = np.zeros(lanes, dtype=np.bool_)  # FULL mode reads none
    swept = len(motion) > 0
    margin = np.zeros(len(d.body_step) + len(d.body_pair) if swept else 0)
    row = np.empty(len(margin))
    for start in range(0, len(qs), lanes):
        fill = min(lanes, len(qs) - start)
        batch[:fill] = qs[start : start + fill]
        if swept:
            margin[:] = 0.0
            for lane in range(fill):
                motion_margins(motion[start + lane], d.speed, d.body_pair, row)
                for k in range(len(row)):
                    margin[k] = max(margin[k], row[k])
        classify_batch(batch, fill, d, work, FULL, excused, verdict, margin)
        for lane in range(fill):
            out[start + lane] = verdict[lane]
    return out


# Numba keys a cached function on its own file alone; these compile ``trig``'s and
# ``lane_geometry``'s code into theirs.
refresh_cache(
    sys.modules[__name__],
    [
        Path(__file__),
        Path(sphere_kernel.__file__),
        Path(trig.__file__),
        Path(lane_geometry.__file__),
    ],
    Path(classify_many._cache._cache_path),
)
