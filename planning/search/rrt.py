"""RRT-Connect in joint space on a collision adapter (``planning.collision.checker``).

Paths are arrays of shape (N, 7): arm joint waypoints (rad) whose straight-line interpolation
is the path.

References:
    J. Kuffner, S. LaValle, "RRT-Connect: An efficient approach to single-query path
    planning", ICRA 2000.
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
    trees = [Tree(np.asarray(q_start, float)), Tree(np.asarray(q_goal, float))]
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


def _extend(adapter, tree: Tree, target: np.ndarray, step: float) -> int | None:
    near = tree.nearest(target)
    q_new, dist = _steer(tree.q[near], target, step)
    if dist < 1e-9 or not adapter.edge_free(tree.q[near], q_new):
        return None
    return tree.add(q_new, near)


def _connect(adapter, tree: Tree, target: np.ndarray, step: float) -> int | None:
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


def joined_path(a: Tree, i: int, b: Tree, j: int, *, reverse: bool) -> np.ndarray:
    """The path from a's root to its node i, which meets node j of b, then on to b's root
    (the meeting point once); reversed when tree a grew from the goal."""
    path = np.asarray(a.branch(i) + b.branch(j)[::-1])
    return drop_duplicates(path[::-1] if reverse else path)
