"""Clearance tables of the robot's own body pairs whose distance depends on one or two joints.

Some links sit close at most poses without touching: the UR5's forearm and wrist 2 about
14 mm apart, inside the sphere cover's 15 mm slack, so their spheres leave nearly every
configuration undecided and each one went to the exact shapes (a UR5 MBM request took 10-35 ms
of search and fine check, against 1-4 ms with the pair left out). Unlike the pairs
``self_pairs`` leaves out, these do meet at some poses (wrist 1 turned far enough), so they
cannot be dropped; but their distance depends on at most two joints (those that move exactly
one of the two bodies: a joint moving both turns them together), so it can be tabulated once.

The box of those joints (a revolute joint's limits, at most one turn, then the cells wrap; a
prismatic joint's limits) is cut into cells; each cell holds a lower bound of the pair's
clearance anywhere in it: the exact shapes' distance at its centre (a GJK lower bound, as
``hull_kernel``'s proofs) less the pair's threshold (padding plus ``hull_kernel.MARGIN``) and
less how much the distance can shrink within the cell (the speed bounds times the half widths).
The cells are as many as keep that shrink under ``LOSS`` (at most ``MAX_CELLS``). The kernels
(``sphere_kernel.table_clearance``) skip the pair's sphere tests where its cell's value is above
0 and take that value as its clearance for the certificates: in the units of the spheres' speed
bounds, that is the value divided by how much faster the exact shapes' points may move
(``scale``), so every radius and margin the spheres' speeds give stays safe for the shapes.

A compiled module (numba): its distance loop runs a million GJK calls for a table.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import sys
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numba import njit

from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic
from drake_sim.base.resources import cache_dir
from planning.collision import hull_kernel, sphere_kernel, trig
from planning.collision.hull_kernel import _centre, _closest, _difference_support, unpack_hulls
from planning.collision.sphere_kernel import _pose_chain_lanes, pack, refresh_cache, unpack

LOSS = 0.002  # m: how much a cell's bound may lose to the motion within it, at most
MAX_CELLS = 1 << 19  # cells of one table, at most
_ITERATIONS = 64


class PairTable(NamedTuple):
    """One body pair's table: ``joints`` (arm columns, 1 or 2), ``n`` cells along each,
    ``wrap`` (True: the cells span one turn), ``lo`` and ``step`` (the cells' lower edge and
    width, rad or m), ``values`` (prod(n),) clearances in the spheres' speed units, m."""

    joints: np.ndarray
    n: np.ndarray
    wrap: np.ndarray
    lo: np.ndarray
    step: np.ndarray
    values: np.ndarray


class ClearanceGrid(NamedTuple):
    """What a pair's table is made from, the same for every sphere cover of the robot (so it
    is computed and cached once): ``joints``, ``n``, ``wrap``, ``lo``, ``step`` as
    ``PairTable``'s, ``slope`` (how fast the exact shapes may close per unit of each joint, m)
    and ``clear`` (prod(n),) each cell's clearance bound in metres (its centre's, less the
    shrink within the cell)."""

    joints: np.ndarray
    n: np.ndarray
    wrap: np.ndarray
    lo: np.ndarray
    step: np.ndarray
    slope: np.ndarray
    clear: np.ndarray


def clearance_grid(d, h, rows, a, b, low, high, wrap, sphere_speed) -> ClearanceGrid | None:
    """The cells of body pair (a, b)'s table and their clearances (rows of ``h.speed``), or
    None when it cannot have a table (more than two joints, no finite box, no speed bound);
    ``table_of`` makes a cover's table of it.

    Args:
        d: the sphere model's ``KernelData`` (its kinematics).
        h: its ``HullData`` (``speed``: the shapes' own bounds, the same for every cover);
            ``rows`` the rows of ``h.pair`` that are this pair's shapes.
        low, high: (D,) the box each joint spans (``self_pairs.domain``); ``wrap`` (D,) True
            where that is one turn of a revolute joint.
        sphere_speed: ``KernelData.speed`` (L, D), the spheres' speed bounds.
    """
    found = _joints(h, a, b, low, high, sphere_speed)
    if found is None:
        return None
    joints, slope, _ = found
    span = high[joints] - low[joints]
    n = np.maximum(1, np.ceil(span * slope * len(joints) / (2.0 * LOSS))).astype(np.int64)
    while np.prod(n) > MAX_CELLS:
        n = np.maximum(1, n // 2)
    step = span / n
    centres = np.meshgrid(*[low[j] + (np.arange(k) + 0.5) * w for j, k, w in
                            zip(joints, n, step, strict=True)], indexing="ij")  # fmt: skip
    qs = np.tile(np.where(np.isfinite(low + high), 0.5 * (low + high), 0.0), (int(np.prod(n)), 1))
    for k, j in enumerate(joints):
        qs[:, j] = centres[k].ravel()
    clear = clearances(qs, *pack(d), *pack(h), np.asarray(rows, dtype=np.int64))
    clear = clear - float(np.sum(slope * step / 2.0))
    return ClearanceGrid(joints, n, wrap[joints], low[joints], step, slope, clear)


def table_of(grid: ClearanceGrid, a, b, sphere_speed) -> PairTable | None:
    """The table of body pair (a, b) for a sphere cover with speed bounds ``sphere_speed``:
    the grid's clearances in the cover's speed units (divided by how much faster the exact
    shapes may close); None when no cell is above 0."""
    sphere_slope = sphere_speed[a, grid.joints] + sphere_speed[b, grid.joints]
    scale = max(1.0, float(np.max(grid.slope / sphere_slope)))
    if not np.any(grid.clear > 0.0):
        return None
    return PairTable(grid.joints, grid.n, grid.wrap, grid.lo, grid.step, grid.clear / scale)


def _joints(h, a, b, low, high, sphere_speed) -> tuple | None:
    """(joints, slope, sphere_slope): the joints (arm columns) body pair (a, b)'s distance
    depends on, those moving one of them and not the other, and how fast the pair's exact
    shapes and its spheres may close per unit of each (m/rad); None when a table cannot be
    had: more than two joints, a box that is not finite, no speed bound."""
    joints = np.flatnonzero((h.speed[a] > 0.0) != (h.speed[b] > 0.0))
    if not 1 <= len(joints) <= 2 or not np.all(np.isfinite(low[joints] + high[joints])):
        return None
    slope = h.speed[a, joints] + h.speed[b, joints]
    sphere_slope = sphere_speed[a, joints] + sphere_speed[b, joints]
    if not (np.all(np.isfinite(slope)) and np.all(sphere_slope > 0.0)):
        return None
    return joints, slope, sphere_slope


def table_key(d, h, rows, a, b, low, high, wrap, sphere_speed) -> str | None:
    """What ``clearance_grid`` reads for body pair (a, b), as a digest (its cache key), or None
    when the pair cannot have a table (more than two joints, no finite box, no speed bound):
    the pair's shapes, thresholds, speeds and box, the kinematic steps from its shapes to the
    base (not the rest: a finger's position elsewhere leaves the key as it is) and this code.
    Not the spheres' speeds: every cover of the robot shares the grid (``table_of``)."""
    if _joints(h, a, b, low, high, sphere_speed) is None:
        return None
    shapes = sorted({int(g) for g in h.pair[rows].ravel()})
    steps = set()
    for step in h.geom_step[shapes]:
        while step >= 0 and step not in steps:
            steps.add(int(step))
            step = d.parent[step]
    steps = sorted(steps)
    digest = hashlib.sha256(Path(__file__).read_bytes())
    parts = [steps, d.parent[steps], d.kind[steps], d.q_index[steps], d.terms[steps], d.arm]
    parts += [h.pair[rows], h.pair_gap[rows], low, high, wrap, h.speed[[a, b]]]
    parts += [h.geom_step[shapes], h.geom_radius[shapes]]
    parts += [h.vert[h.vert_start[g] : h.vert_start[g + 1]] for g in shapes]
    for part in parts:
        digest.update(np.ascontiguousarray(part, dtype=float).tobytes())
    return digest.hexdigest()[:16]


def cached_grid(key: str, d, h, rows, a, b, low, high, wrap, sphere_speed):
    """``clearance_grid`` (a ``ClearanceGrid`` or None), read from the cache under ``key``
    (``table_key``) when the pair was tabulated before (a grid takes ~1-10 s), else made and
    written there."""
    path = cache_dir() / "pair_tables" / f"{key}.npz"
    try:
        with np.load(path) as saved:
            if not saved["some"]:
                return None
            return ClearanceGrid(*(saved[name] for name in ClearanceGrid._fields))
    except (OSError, ValueError, KeyError):
        pass
    grid = clearance_grid(d, h, rows, a, b, low, high, wrap, sphere_speed)
    buffer = io.BytesIO()
    np.savez(buffer, some=grid is not None, **(grid._asdict() if grid else {}))
    with contextlib.suppress(ConfigError):  # a cache that cannot be written: tabulated again
        write_atomic(path, buffer.getvalue(), "clearance table cache")
    return grid


def kernel_fields(tables: list[PairTable | None]) -> dict:
    """``KernelData``'s ``table_*`` fields and ``table`` for the body pairs' tables (one per
    ``body_pair`` row, None: no table)."""
    q = len(tables)
    out = dict(
        table_start=np.full(q, -1, dtype=np.int64),
        table_joint=np.full((q, 2), -1, dtype=np.int64),
        table_n=np.ones((q, 2), dtype=np.int64),
        table_wrap=np.zeros((q, 2), dtype=np.int64),
        table_lo=np.zeros((q, 2)),
        table_step=np.ones((q, 2)),
    )
    values, start = [], 0
    for p, table in enumerate(tables):
        if table is None:
            continue
        k = len(table.joints)
        out["table_start"][p] = start
        out["table_joint"][p, :k] = table.joints
        out["table_n"][p, :k] = table.n
        out["table_wrap"][p, :k] = table.wrap
        out["table_lo"][p, :k] = table.lo
        out["table_step"][p, :k] = table.step
        values.append(table.values)
        start += len(table.values)
    out["table"] = np.concatenate(values) if values else np.zeros(0)
    return out


@njit(cache=True)
def clearances(qs, floats, ints, hull_floats, hull_ints, rows):
    """For each arm configuration of qs (N, D), the least over the shape pairs ``h.pair[rows]``
    of a lower bound on their distance less their threshold ``h.pair_gap`` (m; <= 0 when they
    may be within it); d and h are the ``KernelData`` and ``HullData`` packed
    (``sphere_kernel.pack``), as ``hull_kernel.prove_free_packed`` takes them: one compile
    serves every robot."""
    d = unpack(floats, ints)
    h = unpack_hulls(hull_floats, hull_ints)
    full = d.template.copy()
    sines = np.empty(len(d.template))
    cosines = np.empty(len(d.template))
    T = np.empty((len(d.parent), 3, 4))
    P = np.empty((4, 3))
    v = np.empty(3)
    none = np.zeros(sphere_kernel.OBJ_COLUMNS)
    start = np.zeros((len(rows), 3))  # each pair's last separating direction (0: none)
    out = np.empty(len(qs))
    for n in range(len(qs)):
        for k in range(len(d.arm)):
            full[d.arm[k]] = qs[n, k]
        _pose_chain_lanes(full, sines, cosines, d.parent, d.kind, d.q_index, d.terms, T)
        least = np.inf
        for i, r in enumerate(rows):
            g, e = h.pair[r, 0], h.pair[r, 1]
            bound = _distance_bound(h, g, e, none, T, P, v, start[i])
            least = min(least, bound - h.pair_gap[r])
        out[n] = least
    return out


@njit(cache=True, _nrt=False)
def _distance_bound(h, g, e, none, T, P, v, start):
    """A lower bound on the distance between robot shapes g and e (0 when they may touch):
    the best of GJK's bounds v.w / |v| (``hull_kernel._apart``), run until it converges.

    GJK starts from ``start`` (3,), the direction that separated the pair at the neighbouring
    cell (any direction gives a valid bound; a near one converges in a step or two), or from
    the centres' difference where it is 0; the direction it ends with is left there."""
    vx, vy, vz = start[0], start[1], start[2]
    if vx == 0.0 and vy == 0.0 and vz == 0.0:
        ax, ay, az = _centre(h, g, T)
        bx, by, bz = _centre(h, e, T)
        vx, vy, vz = ax - bx, ay - by, az - bz
    if vx == 0.0 and vy == 0.0 and vz == 0.0:
        vx = 1.0
    start[0], start[1], start[2] = 0.0, 0.0, 0.0
    best = 0.0
    k = 0
    for _ in range(_ITERATIONS):
        vv = vx * vx + vy * vy + vz * vz
        wx, wy, wz = _difference_support(h, g, e, none, T, vx, vy, vz)
        vw = vx * wx + vy * wy + vz * wz
        if vw > 0.0:
            best = max(best, vw / np.sqrt(vv))
        if k > 0 and vv - vw <= 1e-12 * vv:
            start[0], start[1], start[2] = vx, vy, vz
            return best  # converged
        P[k, 0], P[k, 1], P[k, 2] = wx, wy, wz
        k = _closest(P, k + 1, v)
        if k == 0 or k == 4:
            return 0.0  # the origin is in A - B: touching
        vx, vy, vz = v[0], v[1], v[2]
        if vx * vx + vy * vy + vz * vz <= 1e-24:
            return 0.0
    return best


# Numba keys a cached function on its own file alone; these compile the kernels' code in.
refresh_cache(
    sys.modules[__name__],
    [Path(__file__), Path(hull_kernel.__file__), Path(sphere_kernel.__file__), Path(trig.__file__)],
    Path(clearances._cache._cache_path),
)
