"""Collision queries of a planning group's configurations and segments on a scene's checker.

``CheckerAdapter`` sends queries to the scene's ``SceneGraphCollisionChecker`` (so objects added
at run time are seen; ``planning.collision.sphere_checker.SphereCheckerAdapter`` answers the same
queries with sphere models first): ``CheckEdgeCollisionFree`` at the checker's edge step while
searching, and ``CheckConfigsCollisionFree`` (parallel over both cores) at a fine step to
validate. The joints outside the group stay at the scene's positions.
"""

from __future__ import annotations

import numpy as np

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

    def configs_free(self, qs) -> np.ndarray:
        """Checks many configurations (rows of qs) in parallel; returns a bool array."""
        full = np.tile(self._template, (len(qs), 1))
        full[:, self._arm] = qs
        return np.asarray(self._checker.CheckConfigsCollisionFree(list(full)), dtype=bool)


def edge_key(q_a, q_b) -> bytes:
    """The key under which an edge proven free is remembered."""
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
