"""RRT-Connect in joint space, growing its trees by batches of extensions (one query each).

Each round samples ``batch`` targets (the other tree's root with probability ``goal_bias``),
extends tree A from each target's nearest node by at most ``step`` (all these edges in one
``free_prefixes`` query), then tries to connect tree B to every new node along the straight line
(again one query for all lines); nodes are added every ``step`` along the free part of each line.
With ``batch`` 1 this is the classic algorithm. With a vectorised collision checker (sphere
models, ``planning.collision.sphere_checker``) a query of many short edges costs little more than
one, so a batch makes several RRT-Connect iterations for the price of one.

Paths are arrays of shape (N, 7): arm joint waypoints (rad) whose straight-line interpolation is
the path.

References:
    J. Kuffner, S. LaValle, "RRT-Connect: An efficient approach to single-query path
    planning", ICRA 2000.
    T. Thomason, Z. Kingston, L. Kavraki, "Motions in Microseconds via Vectorized
    Sampling-Based Planning", ICRA 2024 (many checks per call).
"""

from __future__ import annotations

import time

import numpy as np

from planning.paths import drop_duplicates


class Tree:
    """A search tree: configurations (rows of ``q``) and each node's parent index."""

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
    adapter,
    q_start: np.ndarray,
    q_goal: np.ndarray,
    *,
    step: float,
    goal_bias: float,
    deadline: float,
    rng: np.random.Generator,
    batch: int = 1,
    max_rounds: int = 100_000,
    balance: bool = False,
) -> np.ndarray | None:
    """Plans a collision-free path with RRT-Connect; both ends must be collision-free.

    Args:
        adapter: collision queries with ``free_prefixes`` (``checker.CheckerAdapter``).
        q_start, q_goal: the 7 arm joints at either end, rad.
        step: largest extension of a tree per step, rad (joint-space L2).
        goal_bias: probability of a target being the other tree's root.
        deadline: ``time.perf_counter()`` value at which to give up.
        rng: the random generator.
        batch: extensions per round (1: the classic algorithm, one extension at a time).
        max_rounds: rounds before giving up.
        balance: extend the smaller tree each round (the start tree on a tie), rather than
            each in turn.

    Returns:
        (N, 7) waypoints from q_start to q_goal, or None when none was found in time.
    """
    trees = [Tree(np.asarray(q_start, float)), Tree(np.asarray(q_goal, float))]
    for round_ in range(max_rounds):
        if time.perf_counter() > deadline:
            return None
        k = int(trees[0].size > trees[1].size) if balance else round_ % 2
        a, b = trees[k], trees[1 - k]
        targets = rng.uniform(adapter.lower, adapter.upper, (batch, len(adapter.lower)))
        targets[rng.random(batch) < goal_bias] = b.q[0]
        new = _extend_all(adapter, a, targets, step)
        if not new:
            continue
        found = _connect_all(adapter, b, a.q[new], step)
        if found is None:
            continue
        i, reached = found
        return joined_path(a, new[i], b, reached, reverse=k == 1)
    return None


def _nearest(tree: Tree, targets: np.ndarray) -> np.ndarray:
    q = tree.q[: tree.size]
    d2 = (targets**2).sum(axis=1)[:, None] - 2.0 * targets @ q.T + (q**2).sum(axis=1)[None, :]
    return np.argmin(d2, axis=1)


def _extend_all(adapter, tree: Tree, targets: np.ndarray, step: float) -> list[int]:
    """Extends the tree towards each target by at most ``step``; returns the new nodes."""
    near = _nearest(tree, targets)
    q_near = tree.q[near]
    delta = targets - q_near
    dist = np.linalg.norm(delta, axis=1)
    keep = dist > 1e-9
    if not keep.any():
        return []
    scale = np.minimum(1.0, step / np.maximum(dist, 1e-12))
    q_new = q_near + delta * scale[:, None]
    free = np.zeros(len(targets), dtype=bool)
    free[keep] = adapter.free_prefixes(q_near[keep], q_new[keep]) >= 1.0
    return [tree.add(q_new[i], int(near[i])) for i in np.flatnonzero(free)]


def _connect_all(adapter, tree: Tree, targets: np.ndarray, step: float):
    """Grows the tree along straight lines towards each target; returns (target index, node
    that reached it) for the first target reached, or None."""
    near = _nearest(tree, targets)
    q_near = tree.q[near].copy()
    dist = np.linalg.norm(targets - q_near, axis=1)
    for i in np.flatnonzero(dist < 1e-9):
        return int(i), int(near[i])
    reach = adapter.free_prefixes(q_near, targets) * dist
    found = None
    for i in range(len(targets)):
        index = int(near[i])
        for k in range(1, int(np.floor(reach[i] / step + 1e-9)) + 1):
            if k * step >= dist[i] - 1e-9:
                break
            q = q_near[i] + (targets[i] - q_near[i]) * (k * step / dist[i])
            index = tree.add(q, index)
        if reach[i] >= dist[i] - 1e-9 and found is None:
            found = (i, tree.add(targets[i].copy(), index))
    return found


def joined_path(a: Tree, i: int, b: Tree, j: int, *, reverse: bool) -> np.ndarray:
    """The path from a's root to its node i, which meets node j of b, then on to b's root
    (the meeting point once); reversed when tree a grew from the goal."""
    path = np.asarray(a.branch(i) + b.branch(j)[::-1])
    return drop_duplicates(path[::-1] if reverse else path)
