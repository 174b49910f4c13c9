"""Pairs of the robot's own bodies that no configuration within the joint limits brings within
their padding: proven once per robot and left out of every later check.

A pair of links one or two joints apart can sit close at every pose without ever touching: the
UR5's forearm and wrist 2 stay about 14 mm apart whatever the wrist does, inside the sphere
cover's 15 mm slack, so the spheres leave every configuration undecided and each one went to the
exact shapes (~12 ms of a UR5 request's search). MoveIt's Setup Assistant disables such pairs
by sampling ("never in collision" in 10,000 random poses); here the pair is left out only when
it is *proven* apart over the whole box of the joints it depends on:

- The joints a pair's distance depends on are those that move exactly one of its two bodies
  (``HullData.speed`` is nonzero for the joints on a body's way to the base): a joint moving
  both moves them rigidly together, one moving neither changes nothing. Pairs depending on more
  than ``MAX_JOINTS`` of them, or on a joint outside the group (a finger, at the scene's
  position), are left to the checks.
- That box (a revolute joint's limits, at most one turn: its poses repeat) is cut into cells;
  ``hull_kernel.prove_free_packed`` at a cell's centre, with the cell's half widths as ``motion``,
  proves the pair's exact shapes farther apart than their padding plus ``hull_kernel.MARGIN``
  everywhere in the cell (its margins are the speed bounds of the points that move). Cells not
  proven are halved along their widest joint (by speed) until proven, or the pair is kept: a
  cell centre not proven even at rest, a cell narrower than ``MIN_HALF``, or more than
  ``BUDGET`` cells.

The proof uses the exact checks' own data and thresholds, so what it leaves out Drake's checker
would never have found in collision either.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
from pathlib import Path

import numpy as np

from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic
from drake_sim.base.resources import cache_dir
from planning.collision.hull_kernel import HullData, prove_free_packed
from planning.collision.pair_tables import (
    ClearanceGrid,
    PairTable,
    cached_grid,
    table_key,
    table_of,
)
from planning.collision.sphere_kernel import pack

MAX_JOINTS = 2  # a pair's joints: cells grow as the cells per joint to this power
MIN_HALF = 1e-3  # rad (m for a prismatic joint): a cell this narrow not proven keeps the pair
BUDGET = 200_000  # cells per pair at most
_START = 8  # cells per joint to begin with


class OwnPairs:
    """What a sphere model proves about the robot's own body pairs, once per model: the pairs
    never close (``never``, among the bodies only the group's joints move: ``own``, plant
    indices) and the pairs' clearance tables (``tables``, ``pair_tables``), over the box of the
    group's joints (``domain``).

    Args:
        plant: the MultibodyPlant.
        arm: the group's position indices.
        bodies: the robot's bodies with collision geometry (plant indices), the held objects'
            attachment body excluded (its shapes change).
    """

    def __init__(self, plant, arm, bodies):
        arm = [int(i) for i in arm]
        inboard = {int(plant.get_joint(j).child_body().index()): plant.get_joint(j)
                   for j in plant.GetJointIndices()}  # fmt: skip
        single = {j.position_start(): j for j in inboard.values() if j.num_positions() == 1}

        def group_only(body: int) -> bool:  # every joint up to the base welded or the group's
            while body in inboard:
                joint = inboard[body]
                if joint.type_name() != "weld" and joint.position_start() not in arm:
                    return False
                body = int(joint.parent_body().index())
            return True

        self.bodies = {int(b) for b in bodies}
        self.own = {b for b in self.bodies if group_only(b)}
        self.revolute = np.array([single[i].type_name() == "revolute" for i in arm])
        self.lower = plant.GetPositionLowerLimits()[arm]
        self.upper = plant.GetPositionUpperLimits()[arm]
        self._never: set[frozenset] | None = None
        self._grids: dict[str, ClearanceGrid | None] = {}  # by ``pair_tables.table_key``

    def never(self, d, h: HullData, present) -> set[frozenset]:
        """The own pairs (plant indices) proven apart at every configuration (``never_close``
        on the model's data ``d``, ``h``, whose body rows are ``present``)."""
        if self._never is None:
            rows = {k for k, b in enumerate(present) if b in self.own}
            pairs = cached_never_close(d, h, self.lower, self.upper, self.revolute, rows)
            self._never = {frozenset((present[a], present[b])) for a, b in pairs}
        return self._never

    def tables(self, d, h: HullData, present) -> list[PairTable | None]:
        """A clearance table (or None) for each of ``d.body_pair``'s rows: pairs of the robot's
        bodies, a joint outside the group on the way (a finger, the head) at the scene's
        position (``pair_tables.table_key`` then differs with that position)."""
        low, high, wrap = domain(self.lower, self.upper, self.revolute)
        shape_rows: dict[frozenset, list[int]] = {}
        for r, (g, e) in enumerate(h.pair):
            key = frozenset((int(h.geom_body[g]), int(h.geom_body[e])))
            shape_rows.setdefault(key, []).append(r)
        out = []
        for a, b in d.body_pair:
            rows = shape_rows.get(frozenset((int(a), int(b))))
            robot = present[a] in self.bodies and present[b] in self.bodies
            args = (d, h, rows, a, b, low, high, wrap, d.speed)
            key = table_key(*args) if robot and rows else None
            if key is not None and key not in self._grids:
                self._grids[key] = cached_grid(key, *args)
            grid = None if key is None else self._grids[key]
            out.append(None if grid is None else table_of(grid, a, b, d.speed))
        return out


def cached_never_close(d, h: HullData, lower, upper, revolute, bodies) -> set[tuple[int, int]]:
    """``never_close``, read from the cache when the same data were proven before (a proof
    takes ~0.1-1 s per robot); keyed by every input's content and this module's code."""
    digest = hashlib.sha256(Path(__file__).read_bytes())
    for name, array in [*d._asdict().items(), *h._asdict().items()]:
        if name != "objects":
            digest.update(name.encode() + np.ascontiguousarray(array).tobytes())
    for array in (lower, upper, revolute, sorted(bodies)):
        digest.update(np.ascontiguousarray(array, dtype=float).tobytes())
    path = cache_dir() / "self_pairs" / f"{digest.hexdigest()[:16]}.json"
    try:
        return {tuple(pair) for pair in json.loads(path.read_text())}
    except (OSError, ValueError, TypeError):
        pass
    out = never_close(d, h, lower, upper, revolute, bodies)
    with contextlib.suppress(ConfigError):  # a cache that cannot be written: proven again
        write_atomic(path, json.dumps(sorted(out)), "self-pair proof cache")
    return out


def never_close(d, h: HullData, lower, upper, revolute, bodies) -> set[tuple[int, int]]:
    """Pairs of ``h``'s bodies (rows of ``h.speed``) proven apart at every configuration within
    the limits, as (row, row) with the smaller row first.

    Args:
        d: the sphere model's ``KernelData`` (its kinematics; its objects are not read).
        h: its ``HullData`` (the shape pairs checked, their thresholds, the speed bounds).
        lower, upper: the group's joint limits (D,), rad or m.
        revolute: (D,) True for a revolute or continuous joint.
        bodies: the rows (bodies) whose pairs may be left out: the robot's own links, whose
            pose no joint outside the group changes relative to the other's.
    """
    low, high, _ = domain(lower, upper, revolute)
    d = d._replace(objects=np.zeros((0, d.objects.shape[1])))
    moves = h.speed > 0.0
    by_pair: dict[tuple[int, int], list[int]] = {}
    for p, (g, e) in enumerate(h.pair):
        a, b = sorted((int(h.geom_body[g]), int(h.geom_body[e])))
        if a in bodies and b in bodies:
            by_pair.setdefault((a, b), []).append(p)
    middle = np.where(np.isfinite(low) & np.isfinite(high), 0.5 * (low + high), 0.0)
    out = set()
    for (a, b), rows in sorted(by_pair.items()):
        joints = np.flatnonzero(moves[a] != moves[b])
        if len(joints) > MAX_JOINTS:
            continue
        if not np.all(np.isfinite(low[joints]) & np.isfinite(high[joints])):
            continue
        pair_h = h._replace(
            geom_world=np.full(len(h.geom_step), -1.0),
            pair=np.ascontiguousarray(h.pair[rows]),
            pair_gap=np.ascontiguousarray(h.pair_gap[rows]),
        )
        weight = h.speed[a, joints] + h.speed[b, joints]  # m per rad of each joint, at most
        if _proven(d, pair_h, middle, joints, low[joints], high[joints], weight):
            out.add((a, b))
    return out


def domain(lower, upper, revolute):
    """(low, high, wrap): the box each joint's poses span, a revolute joint's limits cut to one
    turn (a joint without limits: one turn about 0), a prismatic joint's limits; ``wrap`` True
    where that box is one whole turn (its poses repeat beyond it)."""
    low, high = np.array(lower, dtype=float), np.array(upper, dtype=float)
    revolute = np.asarray(revolute, dtype=bool)
    free = revolute & ~(np.isfinite(low) & np.isfinite(high))
    low[free], high[free] = -np.pi, np.pi
    wrap = revolute & (high - low >= 2.0 * np.pi)
    high[wrap] = low[wrap] + 2.0 * np.pi
    return low, high, wrap


def _proven(d, h, middle, joints, low, high, weight) -> bool:
    """True when every cell of the box [low, high] over ``joints`` (the others at ``middle``)
    is proven free by ``prove_free_packed`` with its half widths as motion (module docstring)."""
    k = len(joints)
    packed = (*pack(d), *pack(h))
    edges = [np.linspace(lo, hi, _START + 1) for lo, hi in zip(low, high, strict=True)]
    grids = np.meshgrid(*[0.5 * (e[:-1] + e[1:]) for e in edges], indexing="ij")
    centres = np.stack([g.ravel() for g in grids], axis=1) if k else np.zeros((1, 0))
    halves = np.tile(0.5 * (high - low) / _START, (len(centres), 1))
    used = 0
    while len(centres):
        used += len(centres)
        if used > BUDGET:
            return False
        q = np.tile(middle, (len(centres), 1))
        q[:, joints] = centres
        motion = np.zeros_like(q)
        motion[:, joints] = halves
        failed = ~prove_free_packed(q, *packed, motion)
        if not failed.any():
            return True
        q, centres, halves = q[failed], centres[failed], halves[failed]
        if not prove_free_packed(q, *packed, np.zeros((0, q.shape[1]))).all():
            return False  # a centre within the threshold even at rest
        widest = np.argmax(halves * weight, axis=1)
        rows = np.arange(len(halves))
        if (halves[rows, widest] < MIN_HALF).any():
            return False
        halves[rows, widest] *= 0.5
        shift = np.zeros_like(centres)
        shift[rows, widest] = halves[rows, widest]
        centres = np.concatenate([centres - shift, centres + shift])
        halves = np.concatenate([halves, halves])
    return True
