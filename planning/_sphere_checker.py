"""``SphereCheckerAdapter``: the ``CheckerAdapter`` interface answered by sphere models first.

Each configuration is classified by ``_spheres.SphereCollisionModel``: FREE (the conservative
outer spheres touch nothing, so Drake's checker agrees) and COLLIDING (inner balls overlap, so
Drake's checker agrees) are final; only UNKNOWN configurations go to the scene's
``SceneGraphCollisionChecker``. So a configuration is accepted exactly when the sphere model
proves it free or Drake finds it free: nothing Drake rejects is ever accepted, and narrow
passages where the outer spheres are too fat still pass through Drake. When the scene holds
geometry without a sphere model, every query goes to Drake.

Edges are sampled at the edge step (the checker's, or ``resolution``) and classified in one
vectorised pass, coarse to fine (bisection order: a first batch, then the rest); the UNKNOWN
samples then go to Drake in that order, stopping at the first collision. ``free_prefixes``
checks many segments at once (the batched RRT-Connect and the shortcutting use it), near
their starts first.
"""

from __future__ import annotations

import time
import weakref

import numpy as np

from planning._rrt import CheckerAdapter, _bisection_order, _edge_key
from planning._spheres import COLLIDING, FREE, UNKNOWN, SphereCollisionModel

_MODELS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_FIRST_BATCH = 16  # samples of an edge classified before the rest
_SERIAL = 64  # at most this many configurations go to Drake one by one, more in parallel


def sphere_model(scene, slack: float = 0.015) -> SphereCollisionModel:
    """Returns the scene's sphere model (built once per scene and slack, then kept in sync)."""
    models = _MODELS.setdefault(scene, {})
    if slack not in models:
        models[slack] = SphereCollisionModel(scene, slack)
    return models[slack]


class SphereCheckerAdapter(CheckerAdapter):
    """7-joint collision queries on a ``PlanningScene``: sphere models, Drake when unsure.

    Args:
        scene: the planning scene.
        resolution: as for ``CheckerAdapter``: the edge step, rad (the checker's when None).
        slack: the sphere cover's slack, m.
        fallback_after: a ``time.perf_counter()`` value before which configurations the
            spheres cannot decide count as colliding (no Drake query; conservative): a fast
            search first, Drake for narrow passages later. None: Drake decides them always.

    Attributes:
        counts: how many configurations were decided by spheres and how many went to Drake.
    """

    def __init__(
        self,
        scene,
        resolution: float | None = None,
        *,
        slack: float = 0.015,
        fallback_after: float | None = None,
    ):
        super().__init__(scene, resolution)
        self._model = sphere_model(scene, slack)
        self._model.sync()
        self._fallback_after = fallback_after
        self.counts = {"spheres": 0, "drake": 0}

    def _fallback(self) -> bool:
        """True when UNKNOWN configurations go to Drake; before ``fallback_after`` (a
        ``time.perf_counter()`` value) they count as colliding, which is conservative."""
        return self._fallback_after is None or time.perf_counter() >= self._fallback_after

    @property
    def model(self) -> SphereCollisionModel:
        return self._model

    def config_free(self, q) -> bool:
        return bool(self.configs_free(np.asarray(q, dtype=float)[None, :])[0])

    def configs_free(self, qs) -> np.ndarray:
        """Checks many configurations (rows of qs); returns a bool array."""
        qs = np.atleast_2d(np.asarray(qs, dtype=float))
        state = self._model.classify(qs)
        free = state == FREE
        unknown = np.flatnonzero(state == UNKNOWN)
        self.counts["spheres"] += len(qs) - len(unknown)
        if len(unknown) and self._fallback():
            self.counts["drake"] += len(unknown)
            free[unknown] = self._drake_free(qs[unknown])
        return free

    def _drake_free(self, qs: np.ndarray) -> np.ndarray:
        if len(qs) <= _SERIAL:  # the parallel call costs more for a few configurations
            return np.array([self._checker.CheckConfigCollisionFree(self.full(q)) for q in qs])
        return super().configs_free(qs)

    def free_prefix(self, q_a, q_b) -> float:
        """As ``CheckerAdapter.free_prefix`` (see ``free_prefixes``)."""
        return float(self.free_prefixes(q_a[None, :], q_b[None, :])[0])

    def free_prefixes(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """``free_prefix`` of many segments (rows of q_a, q_b), (K,): the samples of all
        segments are classified in one pass; the UNKNOWN ones before each segment's first
        certain collision then go to Drake together."""
        step = self._resolution or self._checker.edge_step_size()
        delta = q_b - q_a
        n = np.maximum(1, np.ceil(np.linalg.norm(delta, axis=1) / step).astype(int))
        edge = np.repeat(np.arange(len(n)), n)
        local = np.arange(len(edge)) - np.repeat(np.cumsum(n) - n, n)  # 0..n_k-1
        t = (local + 1) / n[edge]
        samples = q_a[edge] + t[:, None] * delta[edge]
        fallback = self._fallback()
        # Near the start of each segment first: most segments that collide do so early.
        state = np.full(len(samples), FREE, dtype=np.int8)
        end = n.copy()  # per segment: index of its first colliding sample (n: none)
        done = 0
        for stop in (_FIRST_BATCH, 4 * _FIRST_BATCH, None):
            todo = (local >= done) & (local < (stop or n.max())) & (end[edge] == n[edge])
            todo = np.flatnonzero(todo)
            if len(todo):
                state[todo] = self._model.classify(samples[todo])
                blocking = COLLIDING if fallback else UNKNOWN
                hit = todo[(state[todo] == COLLIDING) | (state[todo] == blocking)]
                np.minimum.at(end, edge[hit], local[hit])
            if stop is None or stop >= n.max():
                break
            done = stop
        ask = np.flatnonzero((state == UNKNOWN) & (local < end[edge]))
        self.counts["spheres"] += int((state != UNKNOWN).sum())
        if len(ask):
            self.counts["drake"] += len(ask)
            blocked = ask[~self._drake_free(samples[ask])]
            np.minimum.at(end, edge[blocked], local[blocked])
        return np.where(end > 0, end / n, 0.0)

    def edge_free(self, q_a, q_b) -> bool:
        """True when every sample of the segment at the edge step is collision-free."""
        if self._resolution is not None and self.is_proven(q_a, q_b):
            return True
        step = self._resolution or self._checker.edge_step_size()
        n = max(1, int(np.ceil(np.linalg.norm(q_b - q_a) / step)))
        t = _bisection_order(n)
        samples = q_a + t[:, None] * (q_b - q_a)
        unknown = []
        for part in (samples[:_FIRST_BATCH], samples[_FIRST_BATCH:]):
            if not len(part):
                continue
            state = self._model.classify(part)
            if (state == COLLIDING).any() or ((state == UNKNOWN).any() and not self._fallback()):
                self.counts["spheres"] += len(part)
                return False
            unknown.append(part[state == UNKNOWN])
            self.counts["spheres"] += int((state != UNKNOWN).sum())
        unknown = np.vstack(unknown)
        chunk = 4
        for start in range(0, len(unknown), chunk):
            piece = unknown[start : start + chunk]
            self.counts["drake"] += len(piece)
            if not self._drake_free(piece).all():
                return False
            chunk *= 2
        if self._resolution is not None:
            self._proven.add(_edge_key(q_a, q_b))
        return True
