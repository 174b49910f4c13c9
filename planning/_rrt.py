"""Joint-space path planning on Drake's collision checker: RRT-Connect, shortcutting, checks.

All paths here are arrays of shape (N, 7): arm joint waypoints (rad) whose straight-line
interpolation is the path; the fingers stay at the scene's positions. ``CheckerAdapter`` sends
collision queries to the scene's ``SceneGraphCollisionChecker`` (so objects added at run time
are seen; ``planning._sphere_checker.SphereCheckerAdapter`` answers the same queries with
sphere models first):
``CheckEdgeCollisionFree`` at the checker's edge step while searching, and
``CheckConfigsCollisionFree`` (parallel over both cores) at a fine step to validate.

References:
    J. Kuffner, S. LaValle, "RRT-Connect: An efficient approach to single-query path
    planning", ICRA 2000.
    R. Geraerts, M. Overmars, "Creating high-quality paths for motion planning", IJRR 2007
    (random shortcutting).
"""

from __future__ import annotations

import time

import numpy as np

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
    """7-joint collision queries on a ``PlanningScene``'s checker (fingers from the scene).

    Args:
        scene: the planning scene.
        resolution: when given, edges are checked by sampling at this joint-space step (rad,
            in parallel) instead of at the checker's own edge step.
    """

    def __init__(self, scene, resolution: float | None = None):
        self._resolution = resolution
        self._proven: set[bytes] = set()  # edges found free at ``resolution``
        self._checker = scene.checker
        self._template = scene.full_q(np.zeros(7))
        self._arm = scene.model.arm_indices
        idx = self._arm
        self.lower = scene.plant.GetPositionLowerLimits()[idx].copy()
        self.upper = scene.plant.GetPositionUpperLimits()[idx].copy()

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
            self._proven.add(_edge_key(q_a, q_b))
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
        return _edge_key(q_a, q_b) in self._proven

    def mark_proven(self, q_a, q_b) -> None:
        self._proven.add(_edge_key(q_a, q_b))

    def configs_free(self, qs) -> np.ndarray:
        """Checks many configurations (rows of qs) in parallel; returns a bool array."""
        full = np.tile(self._template, (len(qs), 1))
        full[:, self._arm] = qs
        return np.asarray(self._checker.CheckConfigsCollisionFree(list(full)), dtype=bool)


def densify(path: np.ndarray, resolution: float) -> tuple[np.ndarray, np.ndarray]:
    """Interpolates a path so that consecutive configurations are at most ``resolution`` apart.

    Args:
        path: (N, 7) waypoints, rad.
        resolution: largest joint-space L2 distance between consecutive samples, rad.

    Returns:
        (samples, segment): the samples (M, 7), first and last waypoints included, and the index
        of the path segment each sample lies on.
    """
    samples, segment = [path[:1]], [0]
    for i in range(len(path) - 1):
        n = max(1, int(np.ceil(np.linalg.norm(path[i + 1] - path[i]) / resolution)))
        s = np.arange(1, n + 1)[:, None] / n
        samples.append(path[i] + s * (path[i + 1] - path[i]))
        segment.extend([i] * n)
    return np.vstack(samples), np.asarray(segment)


def _edge_key(q_a, q_b) -> bytes:
    return np.concatenate([q_a, q_b]).tobytes()


def first_invalid_segment(adapter: CheckerAdapter, path: np.ndarray, resolution: float):
    """Returns the index of the first segment with a collision at ``resolution``, or None.

    Segments the adapter has already found free at that resolution are not checked again;
    the others are checked in one parallel batch (and remembered when free).
    """
    reuse = adapter.resolution == resolution
    todo = [
        i for i in range(len(path) - 1) if not (reuse and adapter.is_proven(path[i], path[i + 1]))
    ]
    if not todo:
        return None
    pieces = [densify(path[i : i + 2], resolution)[0] for i in todo]
    free = adapter.configs_free(np.vstack(pieces))
    bad, offset = None, 0
    for i, piece in zip(todo, pieces, strict=True):
        ok = free[offset : offset + len(piece)].all()
        offset += len(piece)
        if not ok and bad is None:
            bad = i
        elif ok and reuse:
            adapter.mark_proven(path[i], path[i + 1])
    return bad


def path_length(path: np.ndarray) -> float:
    """Joint-space L2 length of a piecewise-linear path, rad."""
    return float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum()) if len(path) > 1 else 0.0


class _Tree:
    def __init__(self, root: np.ndarray, capacity: int = 1024):
        self.q = np.empty((capacity, root.size))
        self.parent = np.empty(capacity, dtype=int)
        self.q[0], self.parent[0], self.size = root, -1, 1

    def add(self, q: np.ndarray, parent: int) -> int:
        if self.size == len(self.q):
            self.q = np.vstack([self.q, np.empty_like(self.q)])
            self.parent = np.concatenate([self.parent, np.empty_like(self.parent)])
        self.q[self.size], self.parent[self.size] = q, parent
        self.size += 1
        return self.size - 1

    def nearest(self, q: np.ndarray) -> int:
        d = self.q[: self.size] - q
        return int(np.argmin(np.einsum("ij,ij->i", d, d)))

    def branch(self, index: int) -> list[np.ndarray]:
        """Configurations from the root to ``index``."""
        out = []
        while index >= 0:
            out.append(self.q[index])
            index = self.parent[index]
        return out[::-1]


def rrt_connect(
    adapter: CheckerAdapter,
    q_start: np.ndarray,
    q_goal: np.ndarray,
    *,
    step: float,
    goal_bias: float,
    deadline: float,
    rng: np.random.Generator,
    max_iterations: int = 100_000,
) -> np.ndarray | None:
    """Plans a collision-free path with RRT-Connect; both ends must be collision-free.

    Args:
        adapter: collision queries.
        q_start, q_goal: the 7 arm joints at either end, rad.
        step: largest extension of a tree per step, rad (joint-space L2).
        goal_bias: probability of sampling the other tree's root instead of a random q.
        deadline: ``time.perf_counter()`` value at which to give up.
        rng: the random generator.
        max_iterations: samples before giving up.

    Returns:
        (N, 7) waypoints from q_start to q_goal, or None when none was found in time.
    """
    trees = [_Tree(np.asarray(q_start, float)), _Tree(np.asarray(q_goal, float))]
    for iteration in range(max_iterations):
        if time.perf_counter() > deadline:
            return None
        a, b = trees[iteration % 2], trees[(iteration + 1) % 2]
        target = b.q[0] if rng.random() < goal_bias else rng.uniform(adapter.lower, adapter.upper)
        new = _extend(adapter, a, target, step)
        if new is None:
            continue
        reached = _connect(adapter, b, a.q[new], step)
        if reached is None:
            continue
        return joined_path(a, new, b, reached, reverse=iteration % 2 == 1)
    return None


def _steer(q_near: np.ndarray, target: np.ndarray, step: float) -> tuple[np.ndarray, float]:
    """Returns the configuration at most ``step`` from ``q_near`` towards ``target``, and the
    distance to ``target``."""
    delta = target - q_near
    dist = float(np.linalg.norm(delta))
    return (target if dist <= step else q_near + delta * (step / dist)), dist


def _extend(adapter, tree: _Tree, target: np.ndarray, step: float) -> int | None:
    near = tree.nearest(target)
    q_new, dist = _steer(tree.q[near], target, step)
    if dist < 1e-9 or not adapter.edge_free(tree.q[near], q_new):
        return None
    return tree.add(q_new, near)


def _connect(adapter, tree: _Tree, target: np.ndarray, step: float) -> int | None:
    """Extends ``tree`` towards target until it gets there (returns the node) or is blocked.

    The whole line to the target is checked in one ``free_prefix`` query; nodes are then
    added every ``step`` along its free part (all of it checked at the edge step)."""
    index = tree.nearest(target)
    q_near = tree.q[index]
    dist = float(np.linalg.norm(target - q_near))
    if dist < 1e-9:
        return index
    reach = adapter.free_prefix(q_near, target) * dist
    for k in range(1, int(np.floor(reach / step + 1e-9)) + 1):
        if k * step >= dist - 1e-9:
            break
        index = tree.add(q_near + (target - q_near) * (k * step / dist), index)
    if reach >= dist - 1e-9:
        return tree.add(target.copy(), index)
    return None


def joined_path(a: _Tree, i: int, b: _Tree, j: int, *, reverse: bool) -> np.ndarray:
    """The path from a's root to its node i, which meets node j of b, then on to b's root
    (the meeting point once); reversed when tree a grew from the goal."""
    path = np.asarray(a.branch(i) + b.branch(j)[::-1])
    return _drop_duplicates(path[::-1] if reverse else path)


def _drop_duplicates(path: np.ndarray, tolerance: float = 1e-12) -> np.ndarray:
    """Drops waypoints within ``tolerance`` rad of their predecessor."""
    keep = np.concatenate([[True], np.linalg.norm(np.diff(path, axis=0), axis=1) > tolerance])
    return path[keep]


def shortcut(
    adapter: CheckerAdapter,
    path: np.ndarray,
    *,
    iterations: int,
    deadline: float,
    rng: np.random.Generator,
    batch: int = 8,
) -> np.ndarray:
    """Shortens a collision-free path: greedy vertex skipping, then random shortcuts.

    The greedy pass joins each waypoint to the farthest later waypoint it sees in a straight
    line (all candidates of a waypoint in one query); the random pass draws ``batch`` pairs of
    points along the path (by arc length) at a time, checks their straight segments in one
    query, and replaces the parts between them by the collision-free segments, largest
    shortening first, as long as the replaced parts do not overlap.

    Returns:
        the shorter path (the input when nothing helped), same ends.
    """
    path = _greedy(adapter, path, deadline)
    for _ in range(int(np.ceil(iterations / batch))):
        if len(path) < 3 or time.perf_counter() > deadline:
            break
        cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
        s = np.sort(rng.uniform(0.0, cum[-1], (batch, 2)), axis=1)
        seg = np.clip(np.searchsorted(cum, s, "right") - 1, 0, len(path) - 2)
        keep = seg[:, 0] < seg[:, 1]
        if not keep.any():
            continue
        s, seg = s[keep], seg[keep]
        q = [_points(path, cum, seg[:, k], s[:, k]) for k in (0, 1)]
        gain = (s[:, 1] - s[:, 0]) - np.linalg.norm(q[1] - q[0], axis=1)
        free = (adapter.free_prefixes(q[0], q[1]) >= 1.0) & adapter.configs_free(q[0])
        chosen: list[int] = []
        for k in np.argsort(-gain):
            apart = all(s[k, 1] <= s[c, 0] or s[k, 0] >= s[c, 1] for c in chosen)
            if free[k] and gain[k] > 1e-9 and apart:
                chosen.append(int(k))
        if chosen:
            path = _splice(path, cum, [(s[k], q[0][k], q[1][k]) for k in chosen])
    return _greedy(adapter, path, deadline)


def _points(path, cum, i, s) -> np.ndarray:
    """Points at arc lengths s on segments i (arrays), (K, 7)."""
    length = cum[i + 1] - cum[i]
    t = np.where(length > 0, (s - cum[i]) / np.where(length > 0, length, 1.0), 0.0)
    return path[i] + t[:, None] * (path[i + 1] - path[i])


def _splice(path, cum, cuts) -> np.ndarray:
    """Replaces the parts of the path between arc lengths (s_a, s_b) by straight segments
    q_a -> q_b, for non-overlapping cuts [((s_a, s_b), q_a, q_b), ...]."""
    out, done = [], -1.0
    for (s_a, s_b), q_a, q_b in sorted(cuts, key=lambda c: c[0][0]):
        out.extend(path[(cum > done) & (cum < s_a)])
        out.extend([q_a, q_b])
        done = s_b
    out.extend(path[cum > done])
    out = [path[0], *out] if done < 0 or not np.allclose(out[0], path[0]) else out
    return _drop_duplicates(np.asarray(out))


def _greedy(adapter, path: np.ndarray, deadline: float) -> np.ndarray:
    out, i = [path[0]], 0
    while i < len(path) - 1:
        j = i + 1
        if j < len(path) - 1 and time.perf_counter() <= deadline:
            later = np.arange(i + 2, len(path))
            starts = np.repeat(path[i][None, :], len(later), axis=0)
            free = np.flatnonzero(adapter.free_prefixes(starts, path[later]) >= 1.0)
            if len(free):
                j = int(later[free[-1]])
        out.append(path[j])
        i = j
    return np.asarray(out)
