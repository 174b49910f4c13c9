"""The joint path search in one compiled call: straight line, RRT-Connect, shortcutting and the
fine check, on the sphere models alone (numba; ``planning.collision.sphere_kernel``).

``plan`` is what ``JointPathSearch.find`` tries first when the scene has sphere models. It
runs the same steps as the Python pipeline, with every edge checked on the spheres (``_free``)
and UNKNOWN samples counted as colliding (but near the start and goal, see ``anchor_radius``,
and those undecided for the robot's own links alone that its exact shapes prove free, see
``_proven``), so what it returns is free for Drake's checker too once the fine check has asked
it about those:

1. the straight line, at the search resolution;
2. RRT-Connect (Kuffner and LaValle, ICRA 2000), one extension at a time, edges checked at the
   search resolution, the smaller tree extended first (``balance``, as VAMP's RRT-Connect does:
   on all of MBM 55 % fewer checks and the compiled search's p95 23.5 -> 10.8 ms, against the
   trees taking turns), and with dynamic-domain sampling (Yershova, Jaillet, Simeon and
   LaValle, ICRA 2005; ``RrtConnectOptions.dynamic_domain``). Restarts with fresh trees were
   measured no better on the hard MBM problems (at 4k and 10k checks, 14 and 9 of the 50
   slowest gave up, against 3 without);
3. shortcutting: greedy vertex skipping, then random shortcuts between points along the path
   (Geraerts and Overmars, IJRR 2007), then greedy again;
and ``fine_check`` then checks every sample of the result at the fine resolution, 32 at a time
in one vectorised call (``planning.collision.sphere_batch``: 2.9x cheaper than one at a time
with certificates, whose radii on MBM paths are mostly below the 0.01 rad between samples),
setting UNKNOWN samples aside for Drake's checker. With ``swept`` (``validation.swept``, the
default) each sample is the centre of a cell of the path, checked with margins for how far the
robot may move within the cell (``sphere_kernel.motion_margins``), so that the whole path is
free, not only its samples: an independent audit (``drake_sim.tools.path_audit``) found 8 of
the 696 MBM Panda paths touching an obstacle between the samples of the point check (up to
0.6 mm deep), and none with the cells. The cells the spheres leave UNKNOWN go to the exact
shapes with the same margins, then are cut into smaller cells (``_cells_free``), and only those
still unproven go to Drake (``checker.swept_free``). On MBM's box scenes this check takes
0.72 ms a path against 0.20 for the samples alone: the sphere cover grazes obstacles along the
search's edges, so about one cell in ten needs the exact shapes.

``plan`` gives up after ``max_checks`` classified configurations (a count, not a time, so a
seed gives the same path on any machine); then, or when the fine check finds a collision, the
Python pipeline takes over, with Drake for what the spheres cannot decide. Random numbers come
from an xorshift64* generator seeded with SplitMix64, so they are the same on every machine.

A compiled kernel module, longer than the project's 400 lines: the whole search is compiled into
one entry point (``solve``; ``plan`` and ``fine_check`` for the Python pipeline), and numba keys
its cache on this file and the files it lists (``refresh_cache`` at the end), so the search's
steps stay together here rather than in more files for every entry point to list.
"""

from __future__ import annotations

import functools
import sys
from pathlib import Path

import numpy as np
from numba import njit

from planning.collision import hull_kernel, lane_geometry, sphere_batch, sphere_kernel, trig
from planning.collision.hull_kernel import hull_free, hull_scratch, unpack_hulls
from planning.collision.sphere_batch import FULL, classify_batch
from planning.collision.sphere_kernel import (
    COLLIDING,
    FREE,
    SELF_UNKNOWN,
    UNKNOWN,
    _classify_one,
    _near_any,
    _work,
    edge_speeds,
    motion_margins,
    pack,
    refresh_cache,
    unpack,
)

FOUND, GAVE_UP, ENDS_UNPROVEN = 0, 1, 2
# A proof by the exact shapes counts as this many configurations against a search's budget: on
# the UR5 it took ~14 us, a sphere check ~1.5 us, and the caller turns the time left into a
# count at 2 us a configuration (``joint_path._CHECK_S``), so a budget still bounds the time.
HULL_CHECKS = 8
_MARCH_BELOW = 0.05  # rad: edges sampled finer than this are checked in order, with certificates
# Blocking samples remembered, and how near (rad) an edge must pass one to check there first:
# on MBM, 4 % fewer checks in the search (the shortcuts' 9 %), the same paths.
_WITNESSES = 4
_WITNESS_RADIUS = 0.3
_MASK = (1 << 64) - 1


def seed_state(seed: int) -> np.ndarray:
    """The generator's state for an integer seed (SplitMix64 of it, never zero), (1,) uint64:
    a new array, which the search advances."""
    return np.array([_splitmix(int(seed))], dtype=np.uint64)


@functools.lru_cache(maxsize=64)
def _splitmix(seed: int) -> int:
    """SplitMix64 of the seed, never zero (kept: each request starts from its planner's seed)."""
    z = (seed + 0x9E3779B97F4A7C15) & _MASK
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _MASK
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK
    z ^= z >> 31
    return z or 1


@njit(cache=True, _nrt=False)
def _uniform(state):
    """A uniform double in [0, 1) from xorshift64*; advances ``state``."""
    x = state[0]
    x ^= x >> np.uint64(12)
    x ^= x << np.uint64(25)
    x ^= x >> np.uint64(27)
    state[0] = x
    return float((x * np.uint64(2685821657736338717)) >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@njit(cache=True, _nrt=False)
def _nearest(cols, size, q, work):
    """(index, distance) of the node nearest to q among the first ``size`` of a tree stored
    by coordinates, ``cols`` (D, capacity): a linear scan, one coordinate at a time over all
    nodes so that the compiler vectorises it (about 1.5 ns per node against 4.4 ns node by
    node, measured; the same sums in the same order, so the same answer). ``work`` holds at
    least ``size`` values."""
    row = cols[0]
    q0 = q[0]
    for i in range(size):
        u = row[i] - q0
        work[i] = u * u
    for j in range(1, cols.shape[0]):
        qj = q[j]
        row = cols[j]
        for i in range(size):
            u = row[i] - qj
            work[i] += u * u
    best = 0
    best_d2 = np.inf
    for i in range(size):
        if work[i] < best_d2:
            best_d2 = work[i]
            best = i
    return best, np.sqrt(best_d2)


@njit(cache=True)
def _grow(nodes, cols, parent, radii, size, q, p):
    """Adds node q with parent p to a tree (its rows ``nodes``, the same by coordinates
    ``cols``, each node's parent and dynamic-domain radius, inf until an extension from it
    fails); returns the arrays (doubled when full) and the new size."""
    if size == len(nodes):
        bigger = np.empty((2 * len(nodes), nodes.shape[1]))
        bigger[:size] = nodes
        wider = np.empty((cols.shape[0], 2 * cols.shape[1]))
        wider[:, :size] = cols[:, :size]
        more = np.empty(2 * len(parent), dtype=np.int64)
        more[:size] = parent
        farther = np.empty(2 * len(radii))
        farther[:size] = radii
        nodes, cols, parent, radii = bigger, wider, more, farther
    nodes[size] = q
    cols[:, size] = q
    parent[size] = p
    radii[size] = np.inf
    return nodes, cols, parent, radii, size + 1


@njit(cache=True)
def _branch(nodes, parent, index):
    """Nodes from ``index`` up to the root, (k, D)."""
    count = 0
    i = index
    while i >= 0:
        count += 1
        i = parent[i]
    out = np.empty((count, nodes.shape[1]))
    i = index
    for k in range(count):
        out[k] = nodes[i]
        i = parent[i]
    return out


@njit(cache=True, _nrt=False)
def _remember(q, witnesses, ring):
    """Keeps q, a sample that blocked an edge, among the last ``_WITNESSES`` such samples
    (``ring``: how many are kept, and the row to write next)."""
    row = ring[1]
    for j in range(len(q)):
        witnesses[row, j] = q[j]
    ring[1] = (row + 1) % len(witnesses)
    ring[0] = min(ring[0] + 1, len(witnesses))


@njit(cache=True, _nrt=False)
def _nearest_sample(q_a, q_b, length2, n, witnesses, ring):
    """The inner sample i (1 <= i < n) of the segment q_a -> q_b nearest to a remembered
    blocking sample, when one lies within ``_WITNESS_RADIUS`` rad of it; else -1."""
    best, chosen = _WITNESS_RADIUS * _WITNESS_RADIUS, -1
    for w in range(ring[0]):
        along = 0.0
        for j in range(len(q_a)):
            along += (witnesses[w, j] - q_a[j]) * (q_b[j] - q_a[j])
        i = min(max(int(round(along / length2 * n)), 1), n - 1)
        t = i / n
        gap = 0.0
        for j in range(len(q_a)):
            gap += (q_a[j] + t * (q_b[j] - q_a[j]) - witnesses[w, j]) ** 2
        if gap < best:
            best, chosen = gap, i
    return chosen


@njit(cache=True, _nrt=False)
def _proven(q, radius, d, scratch):
    """True when the robot's exact shapes prove q free (``hull_kernel.hull_free``), for a
    sample the spheres leave UNKNOWN for a pair of the robot's own links alone (``radius`` is
    ``_classify_one``'s, ``SELF_UNKNOWN``); False when the search has no hulls
    (``make_scratch``).

    Links that pass within the cover's slack of each other at every pose (the UR5's forearm
    and wrist 2, and its base and upper arm, about 14 mm apart) leave every sample UNKNOWN,
    and the search on the spheres alone never finds a path: on 32 UR5 MBM problems the median
    went from 218 to 28 ms, p95 from 1081 to 109 ms; the Panda's paths stay as they were.
    What the spheres leave UNKNOWN against the objects still blocks: the cover's slack keeps
    the search's edges off them, where proofs let it graze obstacles between its samples and
    fail the fine check (proving those too took the Panda's MBM median from 1.4 to 6.4 ms,
    7 of 696 requests left to the Python pipeline). The proof is of the sample alone, not of
    its neighbourhood: with the motion to the next sample as margins (``hull_free``'s motion),
    the UR5's self pairs, moved by the shoulder or wrist joints by 0.05 rad, were rarely
    proven (median 453 ms); the fine check proves the cells around them."""
    h, hull_work, prove = scratch[8], scratch[9], scratch[10]
    if not prove or radius != SELF_UNKNOWN:
        return False
    scratch[3][0] += HULL_CHECKS  # the budget counts work (``plan``'s max_checks)
    return hull_free(q, d, h, hull_work, hull_work[6])  # hull_work[6]: no motion


@njit(cache=True, _nrt=False)
def _edge_prefix(q_a, q_b, step, d, scratch):
    """Checks the samples t = i/n, i = 1..n, n = max(1, ceil(|q_b - q_a| / step)), of the
    segment q_a -> q_b in order and returns (first, n): the index of the first blocking sample
    (sample t = (first + 1) / n; n when none blocks). UNKNOWN blocks too, unless the exact
    shapes prove it free (``_proven``) or it lies within the scratch's ``anchor_radius`` (rad)
    of one of its ``anchors`` (K, D): configurations Drake has found free (a search's start
    and goal), whose neighbours the spheres often cannot decide; a caller that lets those
    through must ask Drake about them later. The end sample, which may become a waypoint,
    passes that way only when it is an anchor itself.

    A FREE sample certifies every sample within its radius (``_classify_one``), which are
    then skipped: in free space one check stands for many (a proven one certifies none).
    ``scratch``: ``make_scratch``'s; its counter counts the configurations classified."""
    work, lam, q, counter, anchors, anchor_radius = scratch[:6]
    length = edge_speeds(q_a, q_b, d, lam)
    if not np.isfinite(length):
        return 0, 1
    n = max(1, int(np.ceil(length / step)))
    h = length / n
    i = 1
    while i <= n:
        t = i / n
        for j in range(len(q_a)):
            q[j] = q_a[j] + t * (q_b[j] - q_a[j])
        state, radius = _classify_one(q, d, True, work, lam)
        counter[0] += 1
        if state != FREE:
            # The end only when it is an anchor itself: it may become a waypoint.
            reach = anchor_radius if i < n else 0.0
            if state == UNKNOWN and (
                _near_any(q, anchors, reach) or _proven(q, radius, d, scratch)
            ):
                i += 1
                continue
            return i - 1, n
        # Samples k h away with k h <= radius are certified (rounding kept on the safe side).
        if h <= 0.0 or radius >= (n - i) * h:
            break
        i += int(radius * (1.0 - 1e-9) / h) + 1
    return n, n


@njit(cache=True, _nrt=False)
def _free(q_a, q_b, step, d, scratch, end_known=False):
    """True when every sample t = i/n, i = 1..n of the segment (n = ceil(length / step)) is
    free, UNKNOWN ones near an anchor or proven included (``_edge_prefix``). The end goes
    first (unless ``end_known``: a waypoint, checked already), then the inner sample nearest to
    one of the last samples that blocked an edge (within ``_WITNESS_RADIUS``: the shortcuts' and the
    greedy passes' candidate edges mostly run past the obstacle that blocked the one before),
    then the others in bisection order (midpoint, quarter points, ...): a colliding edge of a
    search usually shows it within a few checks, wherever the obstacle lies (one at a time:
    checking the levels of the bisection in batches (``sphere_batch``) measured no faster, the
    search's edges being short). The order changes how many checks a blocked edge costs, never
    the answer. With certificates worth having (``step`` below ``_MARCH_BELOW``), samples
    after the end are checked in order instead, each FREE one certifying those within its
    radius."""
    work, lam, q, counter, anchors, anchor_radius, witnesses, ring = scratch[:8]
    if not end_known:
        first, n = _edge_prefix(q_b, q_b, step, d, scratch)
        if first < n:
            _remember(q_b, witnesses, ring)
            return False
    if step < _MARCH_BELOW:
        first, n = _edge_prefix(q_a, q_b, step, d, scratch)
        return first == n
    length2 = 0.0
    for j in range(len(q_a)):
        length2 += (q_b[j] - q_a[j]) ** 2
    if not np.isfinite(length2):
        return False
    n = max(1, int(np.ceil(np.sqrt(length2) / step)))
    witness = _nearest_sample(q_a, q_b, length2, n, witnesses, ring) if n > 1 else -1
    stride = 1
    while stride < n:
        stride *= 2
    alone = witness > 0  # the witness's sample first, alone; then the bisection without it
    while stride > 1:
        half = stride // 2
        start, stop, by = (witness, witness + 1, 1) if alone else (half, n, stride)
        for i in range(start, stop, by):
            if i == witness and not alone:
                continue
            t = i / n
            for j in range(len(q_a)):
                q[j] = q_a[j] + t * (q_b[j] - q_a[j])
            state, radius = _classify_one(q, d, True, work, lam)
            counter[0] += 1
            near = state == UNKNOWN and _near_any(q, anchors, anchor_radius)
            passes = state == FREE or near or (state == UNKNOWN and _proven(q, radius, d, scratch))
            if not passes:
                _remember(q, witnesses, ring)
                return False
        if alone:
            alone = False
        else:
            stride = half
    return True


@njit(cache=True)
def _rrt_connect(q_start, q_goal, lower, upper, d, settings, scratch):
    """RRT-Connect (``settings``: ``plan``'s); returns (found, path). With ``balance`` the
    smaller tree is extended
    (the start tree on a tie), else the trees take turns. ``domain`` (rad; inf: off) is
    dynamic-domain sampling: a node whose extension failed gets that radius (later failures
    shrink it by 1e-4, down to ``domain_min``; successes grow it as much) and a target farther
    than its nearest node's radius is drawn again without a check. Such rejections count
    against ``max_checks`` too, by the nearest-node scan they cost (an eighth of a check, and
    another eighth per 128 nodes scanned), so that the budget still bounds the time."""
    edge_step, step, goal_bias, max_checks, _, rng, _, balance, domain, domain_min, _ = settings
    dim = len(q_start)
    counter = scratch[3]
    nodes = [np.empty((256, dim)), np.empty((256, dim))]
    cols = [np.empty((dim, 256)), np.empty((dim, 256))]
    parents = [np.empty(256, dtype=np.int64), np.empty(256, dtype=np.int64)]
    radii = [np.empty(256), np.empty(256)]
    sizes = [0, 0]
    nodes[0], cols[0], parents[0], radii[0], sizes[0] = _grow(
        nodes[0], cols[0], parents[0], radii[0], 0, q_start, -1
    )
    nodes[1], cols[1], parents[1], radii[1], sizes[1] = _grow(
        nodes[1], cols[1], parents[1], radii[1], 0, q_goal, -1
    )
    distances = np.empty(256)
    target = np.empty(dim)
    q_new = np.empty(dim)
    a = 1
    rejected = 0  # eighths of a check
    while counter[0] + rejected // 8 < max_checks:
        a = (0 if sizes[0] <= sizes[1] else 1) if balance else 1 - a
        b = 1 - a
        if _uniform(rng) < goal_bias:
            target[:] = nodes[b][0]
        else:
            for j in range(dim):
                target[j] = lower[j] + _uniform(rng) * (upper[j] - lower[j])
        if len(distances) < max(sizes[0], sizes[1]):  # scratch of the nearest-node scans
            distances = np.empty(2 * max(sizes[0], sizes[1]))
        near, dist = _nearest(cols[a], sizes[a], target, distances)
        radius = radii[a][near]
        if dist > radius:
            rejected += 1 + sizes[a] // 128
            continue
        if dist > 1e-9:
            scale = min(1.0, step / dist)
            for j in range(dim):
                q_new[j] = nodes[a][near, j] + scale * (target[j] - nodes[a][near, j])
            if not _free(nodes[a][near], q_new, edge_step, d, scratch):
                if domain < np.inf:
                    shrunk = max(radius * 0.9999, domain_min)
                    radii[a][near] = domain if radius == np.inf else shrunk
            else:
                if radius < np.inf:
                    radii[a][near] = radius * 1.0001
                nodes[a], cols[a], parents[a], radii[a], sizes[a] = _grow(
                    nodes[a], cols[a], parents[a], radii[a], sizes[a], q_new, near
                )
                new = sizes[a] - 1
                # Connect tree b towards the new node along the straight line.
                other, gap = _nearest(cols[b], sizes[b], q_new, distances)
                reached = -1
                if gap <= 1e-9:
                    reached = other
                else:
                    work, lam, q = scratch[:3]
                    first, n = _edge_prefix(nodes[b][other], q_new, edge_step, d, scratch)
                    free_length = gap * first / n
                    index = other
                    origin = nodes[b][other].copy()
                    k = 1
                    whole = first == n
                    while k * step <= free_length + 1e-9 and k * step < gap - 1e-9:
                        for j in range(dim):
                            q[j] = origin[j] + (q_new[j] - origin[j]) * (k * step / gap)
                        # A node is a waypoint to be: FREE (or proven), not merely near an anchor.
                        counter[0] += 1
                        state, radius = _classify_one(q, d, True, work, lam)
                        if state != FREE and not (
                            state == UNKNOWN and _proven(q, radius, d, scratch)
                        ):
                            whole = False
                            break
                        nodes[b], cols[b], parents[b], radii[b], sizes[b] = _grow(
                            nodes[b], cols[b], parents[b], radii[b], sizes[b], q, index
                        )
                        index = sizes[b] - 1
                        k += 1
                    if whole:
                        nodes[b], cols[b], parents[b], radii[b], sizes[b] = _grow(
                            nodes[b], cols[b], parents[b], radii[b], sizes[b], q_new, index
                        )
                        reached = sizes[b] - 1
                if reached >= 0:
                    head = _branch(nodes[a], parents[a], new)[::-1]  # a's root .. new
                    tail = _branch(nodes[b], parents[b], reached)  # reached .. b's root
                    path = np.empty((len(head) + len(tail) - 1, dim))
                    path[: len(head)] = head
                    path[len(head) :] = tail[1:]
                    if a == 1:
                        path = path[::-1].copy()
                    return True, path
    return False, np.empty((0, dim))


@njit(cache=True)
def _greedy(path, edge_step, d, scratch):
    """Joins each waypoint to the farthest later one it sees in a straight line (the
    waypoints are free: their own checks are not repeated)."""
    keep = np.zeros(len(path), dtype=np.bool_)
    keep[0] = True
    i = 0
    while i < len(path) - 1:
        j = i + 1
        for k in range(len(path) - 1, i + 1, -1):
            if _free(path[i], path[k], edge_step, d, scratch, True):
                j = k
                break
        keep[j] = True
        i = j
    return path[keep].copy()


@njit(cache=True)
def _arc(path):
    """The cumulative joint-space length at each waypoint, (N,), rad."""
    cum = np.zeros(len(path))
    for i in range(1, len(path)):
        total = 0.0
        for j in range(path.shape[1]):
            total += (path[i, j] - path[i - 1, j]) ** 2
        cum[i] = cum[i - 1] + np.sqrt(total)
    return cum


@njit(cache=True)
def _at(path, cum, s):
    """(segment, point) at arc length s."""
    i = 0
    while i < len(path) - 2 and cum[i + 1] <= s:
        i += 1
    length = cum[i + 1] - cum[i]
    t = (s - cum[i]) / length if length > 0.0 else 0.0
    return i, path[i] + t * (path[i + 1] - path[i])


@njit(cache=True)
def _shortcut(path, iterations, edge_step, d, rng, scratch):
    """Greedy vertex skipping, ``iterations`` random shortcuts between two points drawn by arc
    length (kept when free and shorter), then greedy skipping again. The second pass costs 55
    of the median MBM request's 240 shortcut checks, for paths 0.5 % shorter, but it also drops
    the waypoints the random shortcuts leave (median 5 against 8 on MBM), and without it the
    timed plans took 12 % longer (median 2.36 against 2.10 s): kept."""
    path = _greedy(path, edge_step, d, scratch)
    for _ in range(iterations):
        if len(path) < 3:
            break
        cum = _arc(path)
        s_a = _uniform(rng) * cum[-1]
        s_b = _uniform(rng) * cum[-1]
        if s_a > s_b:
            s_a, s_b = s_b, s_a
        i, q_a = _at(path, cum, s_a)
        k, q_b = _at(path, cum, s_b)
        if i >= k:
            continue
        gap = 0.0
        for j in range(path.shape[1]):
            gap += (q_b[j] - q_a[j]) ** 2
        if np.sqrt(gap) >= s_b - s_a - 0.01:
            continue
        # q_a and q_b lie on checked segments, between their samples, and become waypoints: they
        # are checked too, but after the samples between them, where most shortcuts that fail
        # fail (two checks fewer for those; the same checks for the others).
        if not _free(q_a, q_b, edge_step, d, scratch, True):
            continue
        if not _free(q_a, q_a, edge_step, d, scratch) or not _free(q_b, q_b, edge_step, d, scratch):
            continue
        out = np.empty((i + 1 + 2 + len(path) - k - 1, path.shape[1]))
        out[: i + 1] = path[: i + 1]
        out[i + 1] = q_a
        out[i + 2] = q_b
        out[i + 3 :] = path[k + 1 :]
        path = _drop_duplicates(out)
    return _greedy(path, edge_step, d, scratch)


@njit(cache=True)
def _drop_duplicates(path):
    """The path without waypoints equal to the one before."""
    keep = np.ones(len(path), dtype=np.bool_)
    for i in range(1, len(path)):
        same = True
        for j in range(path.shape[1]):
            if abs(path[i, j] - path[i - 1, j]) > 1e-12:
                same = False
                break
        keep[i] = not same
    return path[keep].copy()


@njit(cache=True)
def _fine_check(path, step, d, counter, swept):
    """Checks every sample of every segment of the path at ``step`` (n = ceil(length / step)
    samples a segment), ``LANES`` samples per batch (``sphere_batch``), in order; UNKNOWN
    samples are set aside; ``counter[0]`` counts the samples classified. Returns (the first
    segment with a COLLIDING sample, or -1; the UNKNOWN samples before it (K, D); their
    segments (K,)).

    Without ``swept``, the samples are t = i/n, i = 1..n, and only they are checked. With it,
    the segment is cut into n cells of equal length and each cell's centre, t = (i - 1/2)/n,
    is checked with margins (``sphere_kernel.motion_margins`` of ``cell_motion``): the most
    any point of the robot may move within half a cell. A FREE centre then proves its whole
    cell free, and the cells cover the segment, ends included: the path is free along its whole
    length, not only at its samples (the batch takes the largest margins of its segments)."""
    lanes = sphere_batch.LANES
    dim = path.shape[1]
    batch_work = sphere_batch.batch_work(d, lanes)
    batch = np.empty((lanes, dim))
    verdict = np.empty(lanes, dtype=np.int64)
    excused = np.zeros(lanes, dtype=np.bool_)  # FULL mode reads none
    owner = np.empty(lanes, dtype=np.int64)
    widths = len(d.body_step) + len(d.body_pair)
    margin = np.zeros(widths if swept else 0)  # the batch's margins (none: empty)
    cell = np.empty(widths)  # the segment's
    motion = np.empty(dim)
    merged = -1  # the last segment whose margins the batch's hold
    unknown = np.empty((16, dim))
    segment = np.empty(16, dtype=np.int64)
    count = 0
    fill = 0
    last = len(path) - 2
    for s in range(len(path) - 1):
        q_a = path[s]
        q_b = path[s + 1]
        length = 0.0
        for j in range(dim):
            length += (q_b[j] - q_a[j]) ** 2
        # One sample (the end, not finite so not free) for a segment of unknown length.
        finite = np.isfinite(length)
        n = max(1, int(np.ceil(np.sqrt(length) / step))) if finite else 1
        centred = swept and finite
        if swept:
            cell_motion(q_a, q_b, n, motion)
            motion_margins(motion, d.speed, d.body_pair, cell)
        for i in range(1, n + 1):
            t = (i - 0.5) / n if centred else i / n
            for j in range(dim):
                batch[fill, j] = q_a[j] + t * (q_b[j] - q_a[j])
            owner[fill] = s
            fill += 1
            if swept and merged != s:
                merged = s
                for k in range(widths):
                    margin[k] = max(margin[k], cell[k])
            if fill < lanes and not (s == last and i == n):
                continue
            counter[0] += fill
            classify_batch(batch, fill, d, batch_work, FULL, excused, verdict, margin)
            margin[:] = 0.0
            merged = -1
            for lane in range(fill):
                if verdict[lane] == COLLIDING:
                    return owner[lane], unknown[:count].copy(), segment[:count].copy()
                if verdict[lane] == UNKNOWN:
                    if count == len(unknown):
                        unknown = np.concatenate((unknown, np.empty_like(unknown)))
                        segment = np.concatenate((segment, np.empty_like(segment)))
                    unknown[count] = batch[lane]
                    segment[count] = owner[lane]
                    count += 1
            fill = 0
    return -1, unknown[:count].copy(), segment[:count].copy()


@njit(cache=True, _nrt=False)
def cell_motion(q_a, q_b, n, motion):
    """Fills ``motion`` (D,) with half a cell of the segment q_a -> q_b cut into n cells, per
    joint, rad: how far the arm moves from a cell's centre to its ends (0 where not finite)."""
    for j in range(len(q_a)):
        half = abs(q_b[j] - q_a[j]) / (2.0 * n)
        motion[j] = half if np.isfinite(half) else 0.0


@njit(cache=True)
def cell_halves(path, segment, step):
    """The half-extents (signed, rad) of the cells of the segments ``segment`` (K,) of ``path``
    cut at ``step`` (``_fine_check``, the same arithmetic), (K, D); 0 where not finite."""
    out = np.zeros((len(segment), path.shape[1]))
    for r in range(len(segment)):
        q_a = path[segment[r]]
        q_b = path[segment[r] + 1]
        length = 0.0
        for j in range(len(q_a)):
            length += (q_b[j] - q_a[j]) ** 2
        n = max(1, int(np.ceil(np.sqrt(length) / step))) if np.isfinite(length) else 1
        for j in range(len(q_a)):
            half = (q_b[j] - q_a[j]) / (2.0 * n)
            out[r, j] = half if np.isfinite(half) else 0.0
    return out


@njit(cache=True)
def make_scratch(d, dim, anchors, anchor_radius, h, prove):
    """The scratch arrays of a search's edge checks: the scalar kernel's (``_work``), the speed
    bounds (L + Q,), a configuration (dim,), the count of configurations classified (1,), the
    ``anchors`` (K, dim) and ``anchor_radius`` (rad) of ``_edge_prefix``, the last samples
    that blocked an edge (``_WITNESSES``, dim) with their count and next row (2,) (``_free``),
    and the robot's exact shapes ``h`` (``HullData``) with their scratch, asked about the
    samples the spheres cannot decide when ``prove`` (``_proven``)."""
    return (
        _work(d),
        np.zeros(len(d.body_step) + len(d.body_pair)),
        np.empty(dim),
        np.zeros(1, dtype=np.int64),
        anchors,
        anchor_radius,
        np.zeros((_WITNESSES, dim)),
        np.zeros(2, dtype=np.int64),
        h,
        hull_scratch(d),
        prove,
    )


@njit(cache=True)
def plan(q_start, q_goal, lower, upper, d, settings, hull_floats, hull_ints):
    """Searches a path between two configurations the caller has checked (neither is
    classified again), edges checked at ``edge_step``; ``fine_check`` checks it finely.

    Args:
        q_start, q_goal: (D,) rad.
        lower, upper: the arm's joint limits (D,), rad.
        d: the sphere model's ``KernelData``.
        settings: the search's settings, one tuple passed on as it is (a plain tuple: numba
            types it as fast as separate arguments, a NamedTuple took 2 us more a call):

            - edge_step: the search's edge resolution, rad;
            - step: RRT-Connect's largest extension, rad;
            - goal_bias: probability of sampling the other tree's root;
            - max_checks: classified configurations before giving up;
            - iterations: random shortcut attempts;
            - rng: the generator's state (``seed_state``), advanced;
            - anchor_radius: rad; samples the spheres cannot decide within this distance of
              the start or the goal count as free (``_edge_prefix``): the fine check asks Drake;
            - balance, domain, domain_min: RRT-Connect's tree balancing and dynamic domain
              (``_rrt_connect``; ``RrtConnectOptions``);
            - prove: samples the spheres cannot decide go to the robot's exact shapes
              (``_proven``), when there are any.
        hull_floats, hull_ints: the packed ``HullData`` (``NO_HULLS``: none).

    Returns:
        (status, path, how, checks): FOUND with the path, or GAVE_UP (no path);
        ``how`` 0 the straight line, 1 RRT-Connect and shortcutting; ``checks`` the
        configurations classified.
    """
    h, has_hulls = _hull_data(hull_floats, hull_ints)
    return _plan(q_start, q_goal, lower, upper, d, settings, h, has_hulls)


@njit(cache=True)
def _plan(q_start, q_goal, lower, upper, d, settings, h, has_hulls):
    """``plan``, the exact shapes ``h`` proving what the spheres cannot decide when
    ``has_hulls`` and the settings' ``prove``."""
    edge_step, _, _, _, iterations, rng, anchor_radius, _, _, _, prove = settings
    dim = len(q_start)
    anchors = np.empty((2, dim))
    anchors[0] = q_start
    anchors[1] = q_goal
    scratch = make_scratch(d, dim, anchors, anchor_radius, h, prove and has_hulls)
    counter = scratch[3]
    empty = np.empty((0, dim))
    path = np.empty((2, dim))
    path[0] = q_start
    path[1] = q_goal
    if _free(q_start, q_goal, edge_step, d, scratch):
        return FOUND, path, 0, counter[0]
    found, path = _rrt_connect(q_start, q_goal, lower, upper, d, settings, scratch)
    if not found:
        return GAVE_UP, empty, 1, counter[0]
    return FOUND, _shortcut(path, iterations, edge_step, d, rng, scratch), 1, counter[0]


@njit(cache=True)
def solve(
    q_start,
    q_goal,
    lower,
    upper,
    floats,
    ints,
    hull_floats,
    hull_ints,
    settings,
    check_ends,
    fine_step,
    swept,
):
    """A whole request in one call: with ``check_ends``, the start and the goal are classified
    first; then ``plan`` (same arguments, but the kernel data packed in two buffers:
    ``sphere_kernel.pack``), and the path's ``_fine_check`` at ``fine_step`` (rad; none when
    0; ``swept``: every point of the path, not only its samples, see ``_fine_check``). What
    the spheres cannot decide there (an end, a sample of the fine check) goes to the
    robot's exact shapes (``hull_kernel``; ``hull_floats`` and ``hull_ints`` are the packed
    ``HullData``, or empty: none), and only what those cannot prove free goes back to the
    caller (to Drake). One call instead of four (start, goal, search, fine check), and four
    arrays instead of 35 and more: each call from Python types and unboxes its arrays,
    KernelData's costing 6 us when the caches are warm and 40-110 us right after a scene set-up
    has evicted them (measured on this project's 2-core VM).

    Returns:
        (status, path, how, checks, unproven, bad, unknown, segment): ``plan``'s four (with
        ``checks`` counting the ends' and the fine check's too), or ENDS_UNPROVEN with no path
        when the spheres cannot prove an end free (``unproven``: bit 0 the start, bit 1 the
        goal; the caller asks Drake, then calls again without ``check_ends``); then the fine
        check's first colliding segment (-1: none), the UNKNOWN samples before it and their
        segments (``_fine_check``; -1 and none when not FOUND or ``fine_step`` is 0).
    """
    d = unpack(floats, ints)
    dim = len(q_start)
    unknown = np.empty((0, dim))
    segment = np.empty(0, dtype=np.int64)
    unproven = 0
    checks = 0
    h, has_hulls = _hull_data(hull_floats, hull_ints)
    if check_ends:
        # No anchors (UNKNOWN blocks); the exact shapes prove what the spheres cannot decide,
        # against the objects too (an end is a point: no edge to graze along).
        scratch = make_scratch(d, dim, unknown, 0.0, h, False)
        hull_work = scratch[9]
        for k in range(2):
            end = q_start if k == 0 else q_goal
            first, n = _edge_prefix(end, end, 1.0, d, scratch)
            if first < n and not (has_hulls and hull_free(end, d, h, hull_work, hull_work[6])):
                unproven |= 1 << k
        checks = scratch[3][0]
        if unproven:
            return ENDS_UNPROVEN, np.empty((0, dim)), 0, checks, unproven, -1, unknown, segment
    status, path, how, searched = _plan(q_start, q_goal, lower, upper, d, settings, h, has_hulls)
    checks += searched
    bad = -1
    if status == FOUND and fine_step > 0.0:
        bad, unknown, segment, samples = fine_check(
            path, fine_step, d, hull_floats, hull_ints, swept
        )
        checks += samples
    return status, path, how, checks, unproven, bad, unknown, segment


@njit(cache=True)
def _unproven(unknown, segment, d, hull_floats, hull_ints, path, step, swept):
    """The rows of ``unknown`` (and their ``segment``) that the robot's exact shapes (packed
    ``HullData``; empty: none) cannot prove free; with ``swept``, the cells of ``path`` cut at
    ``step`` centred there (``_fine_check``) that neither they nor smaller cells
    (``_cells_free``) prove free."""
    if len(unknown) == 0 or (len(hull_ints) == 0 and not swept):
        return unknown, segment
    h, has_hulls = _hull_data(hull_floats, hull_ints)
    if swept:
        halves = cell_halves(path, segment, step)
        keep = ~_cells_free(unknown, halves, d, h, has_hulls)
    else:
        scratch = hull_scratch(d)
        keep = np.zeros(len(unknown), dtype=np.bool_)
        for r in range(len(unknown)):
            keep[r] = not hull_free(unknown[r], d, h, scratch, np.zeros(0))
    return unknown[keep].copy(), segment[keep].copy()


_CELL_DEPTH = 4  # times ``_cells_free`` cuts a cell in four (a 0.01 rad cell: down to 0.04 mrad)


@njit(cache=True)
def _hull_data(hull_floats, hull_ints):
    """(``HullData``, whether it has shapes) of the packed buffers (``NO_HULLS``: none, and
    ``_no_hulls``' empty data in its place)."""
    has_hulls = len(hull_ints) > 0
    return (unpack_hulls(hull_floats, hull_ints) if has_hulls else _no_hulls()), has_hulls


@njit(cache=True)
def _no_hulls():
    """A ``HullData`` with no shapes (``hull_free`` proves nothing with it: never asked)."""
    return unpack_hulls(np.zeros(0), np.zeros(11 * 5, dtype=np.int64))


@njit(cache=True)
def _classify_cells(centres, halves, with_margins, d, work, out):
    """``classify_batch`` of the rows of ``centres``, ``LANES`` at a time, into ``out``: with
    the margins of the motions ``halves`` (each batch the largest of its rows') or without."""
    lanes = sphere_batch.LANES
    dim = centres.shape[1]
    batch = np.empty((lanes, dim))
    verdict = np.empty(lanes, dtype=np.int64)
    excused = np.zeros(lanes, dtype=np.bool_)
    widths = len(d.body_step) + len(d.body_pair)
    margin = np.zeros(widths if with_margins else 0)
    row = np.empty(widths)
    motion = np.empty(dim)
    for start in range(0, len(centres), lanes):
        fill = min(lanes, len(centres) - start)
        margin[:] = 0.0
        for lane in range(fill):
            batch[lane] = centres[start + lane]
            if with_margins:
                for j in range(dim):
                    motion[j] = abs(halves[start + lane, j])
                motion_margins(motion, d.speed, d.body_pair, row)
                for k in range(widths):
                    margin[k] = max(margin[k], row[k])
        classify_batch(batch, fill, d, work, FULL, excused, verdict, margin)
        out[start : start + fill] = verdict[:fill]


@njit(cache=True)
def _cells_free(centres, halves, d, h, has_hulls):
    """For each cell centre +- half (rows), the spheres having left its centre UNKNOWN with the
    cell's margins: True when it is proven free. The exact shapes are asked first, with the
    margins (``hull_free``: the search's paths graze the spheres, whose cover is up to its slack
    fatter than the shapes, so they prove most such cells, 62 % on MBM's box scenes); a cell
    they cannot prove is cut into four smaller cells, with smaller margins, which the spheres
    classify together (``LANES`` at a time; most then pass), the UNKNOWN ones going the same
    way, up to ``_CELL_DEPTH`` cuts. A cell is False when a centre in it collides or a piece
    stays unproven: the caller asks Drake about it (``checker.swept_free``)."""
    dim = centres.shape[1]
    work = sphere_batch.batch_work(d, sphere_batch.LANES)
    scratch = hull_scratch(d)
    motion = np.empty(dim)
    free = np.ones(len(centres), dtype=np.bool_)
    cells, sizes, owner = centres.copy(), halves.copy(), np.arange(len(centres))
    for cut in range(_CELL_DEPTH + 1):  # cells: UNKNOWN with their margins, owner unsettled
        split = np.zeros(len(cells), dtype=np.bool_)
        count = 0
        for k in range(len(cells)):
            if not free[owner[k]]:
                continue
            for j in range(dim):
                motion[j] = abs(sizes[k, j])
            if has_hulls and hull_free(cells[k], d, h, scratch, motion):
                continue
            if cut == _CELL_DEPTH:
                free[owner[k]] = False
            else:
                split[k] = True
                count += 1
        if count == 0:
            break
        more = np.empty((4 * count, dim))
        more_sizes = np.empty((4 * count, dim))
        more_owner = np.empty(4 * count, dtype=np.int64)
        r = 0
        for k in range(len(cells)):
            if not split[k]:
                continue
            for i in range(4):
                offset = (2.0 * i + 1.0) / 4.0 - 1.0
                for j in range(dim):
                    more[r, j] = cells[k, j] + offset * sizes[k, j]
                    more_sizes[r, j] = sizes[k, j] / 4.0
                more_owner[r] = owner[k]
                r += 1
        verdict = np.empty(len(more), dtype=np.int64)
        _classify_cells(more, more_sizes, True, d, work, verdict)
        go_on = np.zeros(len(more), dtype=np.bool_)
        for k in range(len(more)):
            if verdict[k] == COLLIDING:
                free[more_owner[k]] = False
        for k in range(len(more)):  # FREE cells are proven; UNKNOWN ones of unsettled owners go on
            go_on[k] = verdict[k] == UNKNOWN and free[more_owner[k]]
        cells, sizes, owner = more[go_on], more_sizes[go_on], more_owner[go_on]
        if len(cells) == 0:
            break
    return free


@njit(cache=True)
def fine_check(path, step, d, hull_floats, hull_ints, swept):
    """``_fine_check`` of a path (N, D) at ``step``, rad (``swept``: its cells, see there):
    (first COLLIDING segment or -1, the UNKNOWN samples the robot's exact shapes cannot prove
    free (packed ``HullData``; empty: none), their segments, configurations classified)."""
    counter = np.zeros(1, dtype=np.int64)
    bad, unknown, segment = _fine_check(path, step, d, counter, swept)
    unknown, segment = _unproven(unknown, segment, d, hull_floats, hull_ints, path, step, swept)
    return bad, unknown, segment, counter[0]


NO_HULLS = (np.zeros(0), np.zeros(0, dtype=np.int64))
"""The packed ``HullData`` arguments for none (the spheres' verdicts alone)."""


def warm_up(data, lower, upper, hulls=NO_HULLS) -> None:
    """Compiles (first run on a machine, with a note on stderr) or loads ``solve``, ``plan``
    and ``fine_check`` now rather than in a request: a one-sample problem (``hulls``: the
    packed ``HullData``, or ``NO_HULLS``)."""
    sphere_kernel.announce_compile(solve, plan, fine_check)
    for _, step in warm_up_steps(data, lower, upper, hulls):
        step()


def warm_up_steps(data, lower, upper, hulls=NO_HULLS) -> list:
    """``warm_up`` as named steps ``(name, callable)``, one per compiled entry point, for a
    build that reports its progress (``planning.planner_kernels``)."""
    q = np.ascontiguousarray((lower + upper) / 2.0)
    settings = (0.1, 1.0, 0.05, 1, 0, seed_state(0), 0.0, True, np.inf, 1.0, True)
    return [
        (
            "the compiled search",
            lambda: solve(q, q, lower, upper, *pack(data), *hulls, settings, True, 0.01, True),
        ),
        (
            "the Python pipeline's search",
            lambda: plan(q, q, lower, upper, data, settings, *hulls),
        ),
        (
            "the fine check",
            lambda: (
                fine_check(np.vstack([q, q]), 0.01, data, *hulls, True),
                cell_halves(np.vstack([q, q]), np.zeros(1, dtype=np.int64), 0.01),
            ),
        ),
    ]


# Numba keys a cached function on its own file alone; these compile the kernels' code into theirs.
refresh_cache(
    sys.modules[__name__],
    [
        Path(__file__),
        Path(sphere_kernel.__file__),
        Path(sphere_batch.__file__),
        Path(lane_geometry.__file__),
        Path(trig.__file__),
        Path(hull_kernel.__file__),
    ],
    Path(plan._cache._cache_path),
)
