"""Collision queries of a planning group's configurations and segments on a scene's checker.

``CheckerAdapter`` sends queries to the scene's ``SceneGraphCollisionChecker`` (so objects added
at run time are seen; ``planning.collision.sphere_checker.SphereCheckerAdapter`` answers the same
queries with sphere models first): ``CheckEdgeCollisionFree`` at the checker's edge step while
searching, and ``CheckConfigsCollisionFree`` (parallel over both cores) at a fine step to
validate. The joints outside the group stay at the scene's positions.

Validating a path at samples leaves the motion between them unchecked: a path can graze an
obstacle between two free samples. ``first_invalid_segment(..., swept=True)`` checks whole
cells instead (``swept_free``): each segment is cut into cells at most the resolution long, and
a cell is free when its centre is free with a margin, on every pair's distance, of how far the
pair's points may approach while the arm moves from the centre to the cell's ends
(``geometry_speed``: per-joint speed bounds of each body's collision geometry). A cell whose
centre is free but not by that margin is cut into smaller cells, whose margins are smaller.
"""

from __future__ import annotations

import weakref
from typing import NamedTuple

import numpy as np
from pydrake.planning import RobotCollisionType

from planning.collision.sphere_robot import shape_hull
from planning.paths import densify

_SHORT_EDGE_STEPS = 12  # edges of at most this many steps are checked by Drake in one call
_CHUNK = 8  # configurations per parallel batch when checking long edges


def _bisection_order(n: int) -> np.ndarray:
    """Returns the n + 1 fractions k / n, k = 0..n, ordered coarse to fine (end points first)."""
    order, seen = [n, 0], {0, n}
    width = n
    while len(order) < n + 1:
        width = max(1, width // 2)
        for k in range(width, n, width):
            if k not in seen:
                seen.add(k)
                order.append(k)
    return np.asarray(order, dtype=float) / max(n, 1)


class CheckerAdapter:
    """Collision queries of the group's joints on a ``PlanningScene``'s checker (the other
    joints from the scene).

    Args:
        scene: the planning scene.
        resolution: when given, edges are checked by sampling at this joint-space step (rad,
            in parallel) instead of at the checker's own edge step.
    """

    def __init__(self, scene, resolution: float | None = None):
        self._resolution = resolution
        self._proven: set[bytes] = set()  # edges found free at ``resolution``
        self._checker = scene.checker
        self._scene = scene
        self._template = scene.full_q(np.zeros(scene.num_joints))
        self._arm = scene.model.arm_indices
        self.lower, self.upper = scene.lower, scene.upper

    def full(self, q) -> np.ndarray:
        full = self._template.copy()
        full[self._arm] = q
        return full

    def config_free(self, q) -> bool:
        return self._checker.CheckConfigCollisionFree(self.full(q))

    def edge_free(self, q_a, q_b) -> bool:
        """True when the segment is collision-free at the edge step (the checker's, or
        ``resolution``). Short edges go to Drake's ``CheckEdgeCollisionFree`` (end first, then
        in order); long ones are sampled coarse to fine (bisection order) and checked in
        parallel chunks, so a colliding long edge (a typical shortcut attempt) fails after a
        few checks instead of after the free part before the obstacle."""
        step = self._resolution or self._checker.edge_step_size()
        n = int(np.ceil(np.linalg.norm(q_b - q_a) / step))
        if n <= _SHORT_EDGE_STEPS and self._resolution is None:
            return self._checker.CheckEdgeCollisionFree(self.full(q_a), self.full(q_b))
        if self._resolution is not None:
            if self.is_proven(q_a, q_b):
                return True
            # A cheap coarse pass first: most failing candidates fail there.
            if not self._checker.CheckEdgeCollisionFree(self.full(q_a), self.full(q_b)):
                return False
        t = _bisection_order(n)
        samples = q_a + t[:, None] * (q_b - q_a)
        chunk = _CHUNK
        for start in range(0, len(samples), chunk):
            if not self.configs_free(samples[start : start + chunk]).all():
                return False
            chunk *= 2  # the edge looks free: larger batches, fewer calls
        if self._resolution is not None:
            self._proven.add(edge_key(q_a, q_b))
        return True

    def free_prefix(self, q_a, q_b) -> float:
        """Returns the fraction t in [0, 1] of the segment from q_a (known free) towards q_b
        that is collision-free at the edge step: samples at most a step apart from q_a up to
        q_a + t (q_b - q_a) are free, the next one is not (1 when all are free)."""
        step = self._resolution or self._checker.edge_step_size()
        n = max(1, int(np.ceil(np.linalg.norm(q_b - q_a) / step)))
        t = np.arange(1, n + 1) / n
        samples = q_a + t[:, None] * (q_b - q_a)
        chunk = 4
        for start in range(0, n, chunk):
            free = self.configs_free(samples[start : start + chunk])
            if not free.all():
                first = start + int(np.argmin(free))
                return float(t[first - 1]) if first > 0 else 0.0
            chunk *= 2
        return 1.0

    def free_prefixes(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """``free_prefix`` of many segments (rows of q_a and q_b), (K,)."""
        return np.array([self.free_prefix(a, b) for a, b in zip(q_a, q_b, strict=True)])

    @property
    def resolution(self) -> float | None:
        return self._resolution

    def is_proven(self, q_a, q_b) -> bool:
        """True when this adapter has already found the edge free at its resolution."""
        return edge_key(q_a, q_b) in self._proven

    def mark_proven(self, q_a, q_b) -> None:
        self._proven.add(edge_key(q_a, q_b))

    def cell_ratios(self, qs, motion) -> np.ndarray:
        """For each row of qs, how far it is from everything as a share of what the row of
        ``motion`` (rad per joint) may take away (``drake_ratio``; 0: colliding; above 1: every
        configuration within that motion is free)."""
        qs = np.atleast_2d(np.asarray(qs, dtype=float))
        motion = np.broadcast_to(motion, qs.shape)
        speed = geometry_speed(self._scene)
        rows = zip(qs, motion, strict=True)
        return np.array([drake_ratio(self._checker, self.full(q), m, speed) for q, m in rows])

    def configs_free(self, qs, motion=None) -> np.ndarray:
        """Checks many configurations (rows of qs) in parallel; returns a bool array. With
        ``motion`` (rows, rad per joint), a row is free only when every configuration within
        that motion of it is free too (``drake_clear``, one at a time)."""
        qs = np.atleast_2d(np.asarray(qs, dtype=float))
        if motion is not None:  # Drake's distances, one configuration at a time
            return self.cell_ratios(qs, motion) > 1.0
        full = np.tile(self._template, (len(qs), 1))
        full[:, self._arm] = qs
        return np.asarray(self._checker.CheckConfigsCollisionFree(list(full)), dtype=bool)


def edge_key(q_a, q_b) -> bytes:
    """The key under which an edge proven free is remembered."""
    return np.concatenate([q_a, q_b]).tobytes()


def first_invalid_segment(
    adapter: CheckerAdapter, path: np.ndarray, resolution: float, swept: bool = False
):
    """Returns the index of the first segment with a collision at ``resolution``, or None.

    Segments the adapter has already found free at that resolution are not checked again;
    the others are checked in one parallel batch (and remembered when free). With ``swept``,
    the segments are checked along their whole length (``cells``, ``swept_free``), and only
    segments found free that way are reused.
    """
    reuse = adapter.resolution == resolution
    key = _swept_key if swept else edge_key
    todo = [
        i
        for i in range(len(path) - 1)
        if not (reuse and key(path[i], path[i + 1]) in adapter._proven)
    ]
    if not todo:
        return None
    if swept:
        pieces, deltas = zip(*(cells(path[i], path[i + 1], resolution) for i in todo), strict=True)
        free = swept_free(adapter, np.vstack(pieces), np.vstack(deltas))
    else:
        pieces = [densify(path[i : i + 2], resolution)[0] for i in todo]
        free = adapter.configs_free(np.vstack(pieces))
    bad, offset = None, 0
    for i, piece in zip(todo, pieces, strict=True):
        ok = free[offset : offset + len(piece)].all()
        offset += len(piece)
        if not ok and bad is None:
            bad = i
        elif ok and reuse:
            adapter._proven.add(key(path[i], path[i + 1]))
    return bad


def _swept_key(q_a, q_b) -> bytes:
    """The key of an edge proven free along its whole length (``first_invalid_segment``)."""
    return b"swept" + edge_key(q_a, q_b)


_MAX_SPLIT = 16  # cells a failing cell is cut into at most
_DEPTH = 2  # times a cell may be cut (a 0.01 rad cell down to 0.04 mrad at most)


def cells(q_a, q_b, resolution: float) -> tuple[np.ndarray, np.ndarray]:
    """The segment q_a -> q_b cut into n = ceil(length / resolution) cells of equal length:
    their centres (n, D) and half-extents (n, D), signed, rad (a cell runs from centre - half to
    centre + half)."""
    q_a, q_b = np.asarray(q_a, dtype=float), np.asarray(q_b, dtype=float)
    n = max(1, int(np.ceil(np.linalg.norm(q_b - q_a) / resolution)))
    t = (np.arange(n) + 0.5) / n
    return q_a + t[:, None] * (q_b - q_a), np.tile((q_b - q_a) / (2 * n), (n, 1))


def swept_free(adapter, centres: np.ndarray, halves: np.ndarray, first=None, depth: int = 0):
    """For the cells (``cells``: centres, half-extents (K, D)) in order up to the first that is
    not proven free: True for each whose every configuration is collision-free, False for that
    one and all after it (not looked at: callers want the first failing segment). A cell is
    free when its centre is free with margins for the cell's motion (``adapter.cell_ratios``
    above 1, or ``first``'s at this level), else, when its centre is free, when its smaller
    cells are, as many as the centre's ratio says (cells that much smaller pass if their
    centres are as far from everything), down to ``_DEPTH`` cuts (then it counts as colliding:
    a conservative answer)."""
    centres = np.atleast_2d(np.asarray(centres, dtype=float))
    halves = np.atleast_2d(np.asarray(halves, dtype=float))
    ratio = (first or adapter.cell_ratios)(centres, np.abs(halves))
    free = ratio > 1.0
    for k in np.flatnonzero(~free):
        free[k] = _cut_free(adapter, centres[k], halves[k], ratio[k], depth)
        if not free[k]:
            free[k + 1 :] = False
            break
    return free


def _cut_free(adapter, centre, half, ratio: float, depth: int) -> bool:
    """True when the cell centre +- half, whose centre's ratio (``cell_ratios``) is ``ratio``
    (at most 1), is free by its smaller cells (``swept_free``); those nearest to something (the
    least ratio) first: a cell that touches fails soon, without proving the others."""
    if not (ratio > 0.0 and depth < _DEPTH):
        return False
    m = int(np.clip(np.ceil(1.5 / ratio), 2, _MAX_SPLIT))
    offsets = (2.0 * np.arange(m) + 1.0) / m - 1.0  # sub-centres, in (-1, 1)
    sub, small = centre + offsets[:, None] * half, half / m
    ratios = adapter.cell_ratios(sub, np.tile(np.abs(small), (m, 1)))
    for k in np.argsort(ratios):
        if ratios[k] > 1.0:
            return True  # the rest are larger
        if not _cut_free(adapter, sub[k], small, ratios[k], depth + 1):
            return False
    return True


class GeometrySpeed(NamedTuple):
    """Speed bounds of the robot's collision geometry (``geometry_speed``).

    Attributes:
        rows: the row of ``speed`` of each body with collision geometry, by body index.
        speed: (B, D) how fast any point of each body's geometry moves per unit of each arm
            joint, in any configuration, m/rad (m/m for a prismatic joint).
    """

    rows: dict
    speed: np.ndarray


# scene -> (its robot's shapes' reach by body, {held objects' key: GeometrySpeed})
_speeds: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def geometry_speed(scene) -> GeometrySpeed:
    """The scene's ``GeometrySpeed`` (``speed_walk`` of its shapes' reach), made once per set of
    held objects."""
    held = list(scene.attached_objects.values())
    key = tuple((o.shape, tuple(o.size), o.X_PO.GetAsMatrix34().tobytes()) for o in held)
    if scene not in _speeds:
        _speeds[scene] = (_robot_reach(scene), {})
    robot, made = _speeds[scene]
    if key in made:
        return made[key]
    plant = scene.plant
    arm = {int(k): j for j, k in enumerate(scene.model.arm_indices)}
    reach = dict(robot)
    if held:
        model = scene.model  # held objects hang on its attachment body
        body = int(plant.GetBodyByName(model.attachment_body, model.instance).index())
        hulls = [shape_hull(o.drake_shape(), o.X_PO) for o in held]
        reach[body] = max(reach.get(body, 0.0), _farthest(hulls))
    rows = {body: k for k, body in enumerate(reach)}
    made[key] = GeometrySpeed(rows, speed_walk(plant, arm, reach))
    return made[key]


def speed_walk(plant, arm, reach: dict) -> np.ndarray:
    """A bound on how fast any point within ``reach[body]`` (m) of each body's origin moves per
    unit of each arm joint (``arm``: plant position -> column), in any configuration, (B, D),
    rows in ``reach``'s order, m/rad (m/m for a prismatic joint).

    A revolute joint moves a point at most its distance from the joint's axis per rad, no more
    than its distance from the joint frame's origin: walking from the body up the tree, that is
    at most the point's distance from the body's origin plus the length of every joint frame's
    offset on the way (rigid, so the same in any configuration; a weld adds its own offset, a
    prismatic joint its largest travel, a joint of more freedoms makes it unbounded)."""
    inboard = {}
    for index in plant.GetJointIndices():
        joint = plant.get_joint(index)
        inboard[int(joint.child_body().index())] = joint
    speed = np.zeros((len(reach), len(set(arm.values()))))
    for k, body in enumerate(reach):
        far, b = reach[body], body
        while b in inboard:
            joint = inboard[b]
            far += np.linalg.norm(joint.frame_on_child().GetFixedPoseInBodyFrame().translation())
            kind, n = joint.type_name(), joint.num_positions()
            column = arm.get(int(joint.position_start())) if n == 1 else None
            if kind == "revolute" and column is not None:
                speed[k, column] = far
            elif kind == "prismatic":
                if column is not None:
                    speed[k, column] = 1.0
                lower, upper = joint.position_lower_limits()[0], joint.position_upper_limits()[0]
                far += max(abs(lower), abs(upper))  # inf without limits: then no bound
            elif kind == "weld":
                far += np.linalg.norm(joint.X_FM().translation())
            elif kind != "revolute":
                far = np.inf  # a joint of more freedoms: no bound here
            far += np.linalg.norm(joint.frame_on_parent().GetFixedPoseInBodyFrame().translation())
            b = int(joint.parent_body().index())
    return speed


def _farthest(hulls) -> float:
    """How far from the frame's origin any point of ``shape_hull``s lies, m."""
    return max((float(np.linalg.norm(v, axis=1).max()) + r for v, r in hulls), default=0.0)


def _robot_reach(scene) -> dict:
    """How far from its origin any point of each robot body's collision shapes lies, m, by
    body index: the bodies with shapes only."""
    plant = scene.plant
    inspector = scene.checker.MakeStandaloneModelContext().GetQueryObject().inspector()
    reach = {}
    for index in plant.GetBodyIndices(scene.model.instance):
        geometries = plant.GetCollisionGeometriesForBody(plant.get_body(index))
        if geometries:
            shapes = [(inspector.GetShape(g), inspector.GetPoseInFrame(g)) for g in geometries]
            reach[int(index)] = _farthest([shape_hull(*shape) for shape in shapes])
    return reach


def drake_clear(checker, full: np.ndarray, motion: np.ndarray, speed: GeometrySpeed) -> bool:
    """True when Drake's checker finds every pair it checks at the plant positions ``full``
    farther apart (beyond its padding) than the arm's ``motion`` (D,) may bring it closer:
    each robot body's geometry moves at most ``speed`` times the motion, and a joint that
    moves both bodies of a robot pair does not change their distance (``drake_ratio`` > 1)."""
    return drake_ratio(checker, full, motion, speed) > 1.0


def drake_ratio(checker, full: np.ndarray, motion: np.ndarray, speed: GeometrySpeed) -> float:
    """The least, over the pairs Drake's checker checks, of their distance at the plant
    positions ``full`` (beyond the padding) over how much the arm's ``motion`` (D,) may take
    away from it (``drake_clear``); at most 2 (pairs farther are not looked at), 0 when a pair
    touches."""
    move = speed.speed * motion[None, :]
    env = move.sum(axis=1)
    worst = 2.0 * float(env.max(initial=0.0))
    if not np.isfinite(worst):
        return 0.0
    clearance = checker.CalcRobotClearance(full, 2.0 * worst + 1e-6)
    self_pair = RobotCollisionType.kSelfCollision
    ratio = 2.0
    for robot, other, kind, distance in zip(
        clearance.robot_indices(),
        clearance.other_indices(),
        clearance.collision_types(),
        clearance.distances(),
        strict=True,
    ):
        a, b = speed.rows.get(int(robot)), speed.rows.get(int(other))
        if a is None:
            need = worst
        elif kind != self_pair:
            need = env[a]
        elif b is None:
            need = worst
        else:
            both = (speed.speed[a] > 0.0) & (speed.speed[b] > 0.0)
            need = float((move[a] + move[b])[~both].sum())
        if distance <= 0.0:
            return 0.0
        if need > 0.0:
            ratio = min(ratio, distance / need)
    return ratio
