"""``SphereCheckerAdapter``: the ``CheckerAdapter`` interface answered by sphere models first.

Each configuration is classified by ``spheres.SphereCollisionModel``: FREE (the conservative
outer spheres touch nothing, so Drake's checker agrees) and COLLIDING (inner balls overlap, so
Drake's checker agrees) are final; UNKNOWN configurations go to the robot's exact convex shapes
(``hull_kernel``: proven free when a separating plane shows it), then to a tighter cover, and
only what those cannot prove free to the scene's ``SceneGraphCollisionChecker``. So a
configuration is accepted exactly when the models prove it free or Drake finds it free: nothing
Drake rejects is ever accepted, and narrow passages where the outer spheres are too fat still
pass. When the scene holds
geometry without a sphere model, every query goes to Drake.

Edges are sampled at the edge step (the checker's, or ``resolution``) and classified from
their start up to the first certain collision, in compiled code; the UNKNOWN samples then go
to Drake in that order, stopping at the first collision. ``free_prefixes`` checks many
segments in one call (the batched RRT-Connect and the shortcutting use it).
"""

from __future__ import annotations

import numpy as np

from planning.collision.checker import CheckerAdapter, edge_key
from planning.collision.spheres import FREE, UNKNOWN, SphereCollisionModel

_SERIAL = 64  # at most this many configurations go to Drake one by one, more in parallel


def sphere_model(scene, slack: float = 0.015) -> SphereCollisionModel:
    """Returns the scene's sphere model for ``slack``: built once, owned by the scene (its
    ``sphere_models`` dict, so it lives and dies with the scene), then kept in sync with it."""
    models = scene.sphere_models
    if slack not in models:
        models[slack] = SphereCollisionModel(scene, slack)
    return models[slack]


class SphereCheckerAdapter(CheckerAdapter):
    """Collision queries of the arm's joints on a ``PlanningScene``: sphere models, Drake when
    unsure.

    Args:
        scene: the planning scene.
        resolution: as for ``CheckerAdapter``: the edge step, rad (the checker's when None).
        slack: the sphere cover's slack, m.
        fallback_after: how many configurations the spheres classify before Drake decides
            those they cannot; until then these count as colliding (conservative): a fast
            search first, Drake for narrow passages later. None: Drake decides them always.
        refine_slack: m; when given (> 0), a second, tighter cover decides what the first
            cannot before Drake is asked (it proves some free, some colliding).
        hulls: the robot's exact convex shapes prove free what the first cover cannot decide,
            where they can (``SphereCollisionModel.prove_free``), before the tighter cover and
            Drake are asked.

    Attributes:
        counts: how many configurations were decided by spheres and how many went to Drake.
    """

    def __init__(
        self,
        scene,
        resolution: float | None = None,
        *,
        slack: float = 0.015,
        fallback_after: int | None = None,
        refine_slack: float | None = None,
        hulls: bool = True,
    ):
        super().__init__(scene, resolution)
        self._model = sphere_model(scene, slack)
        self._model.sync()
        self._refine = sphere_model(scene, refine_slack) if refine_slack else None
        if self._refine is not None:
            self._refine.sync()
        self._fallback_after = fallback_after
        self._hulls = hulls
        self.counts = {"spheres": 0, "drake": 0}

    def _fallback(self) -> bool:
        """True when UNKNOWN configurations go to Drake; before ``fallback_after`` sphere
        classifications they count as colliding, which is conservative."""
        return self._fallback_after is None or self.counts["spheres"] >= self._fallback_after

    @property
    def model(self) -> SphereCollisionModel:
        return self._model

    def config_free(self, q) -> bool:
        return bool(self.configs_free(np.asarray(q, dtype=float)[None, :])[0])

    def configs_free(self, qs, motion=None) -> np.ndarray:
        """Checks many configurations (rows of qs); returns a bool array. ``motion`` (rows, rad
        per joint): a row is free only when every configuration within that motion of it is
        free too (see ``CheckerAdapter.configs_free``)."""
        qs = np.atleast_2d(np.asarray(qs, dtype=float))
        if motion is not None:
            motion = np.array(np.broadcast_to(motion, qs.shape), dtype=float)
        state = self._model.classify(qs, motion)
        free = state == FREE
        unknown = np.flatnonzero(state == UNKNOWN)
        self.counts["spheres"] += len(qs) - len(unknown)
        if len(unknown) and self._fallback():
            more = None if motion is None else motion[unknown]
            free[unknown] = self.undecided_free(qs[unknown], more)
        return free

    def cell_ratios(self, qs, motion) -> np.ndarray:
        """As ``CheckerAdapter.cell_ratios``, the models first: inf for a row they prove free
        with the margins of its ``motion``, 0 for one the spheres prove colliding; Drake's
        ratio for the others."""
        qs = np.atleast_2d(np.asarray(qs, dtype=float))
        motion = np.array(np.broadcast_to(motion, qs.shape), dtype=float)
        state = self._model.classify(qs, motion)
        ratio = np.where(state == FREE, np.inf, 0.0)
        unknown = np.flatnonzero(state == UNKNOWN)
        self.counts["spheres"] += len(qs) - len(unknown)
        if not len(unknown):
            return ratio
        q, m = qs[unknown], motion[unknown]
        proven = self._model.prove_free(q, m) if self._hulls else np.zeros(len(q), bool)
        ask = ~proven
        if self._refine is not None and self._refine.active and ask.any():
            refined = self._refine.classify(q[ask], m[ask])
            proven[ask] = refined == FREE
            ask[ask] = refined == UNKNOWN
        ratio[unknown[proven]] = np.inf
        self.counts["spheres"] += int(len(q) - ask.sum())
        self.counts["drake"] += int(ask.sum())
        if ask.any():
            ratio[unknown[ask]] = super().cell_ratios(q[ask], m[ask])
        return ratio

    def undecided_free(self, qs: np.ndarray, motion=None) -> np.ndarray:
        """Decides configurations the first cover cannot (rows of qs; a bool array): the
        robot's exact shapes first (``SphereCollisionModel.prove_free``), then the tighter
        cover (when there is one), Drake for the rest; counts them. ``motion`` as
        ``configs_free``'s: each of them then proves the row free with margins for it."""
        if motion is not None:
            motion = np.array(np.broadcast_to(motion, qs.shape), dtype=float)
        free = self._model.prove_free(qs, motion) if self._hulls else np.zeros(len(qs), bool)
        ask = ~free
        if self._refine is not None and self._refine.active and ask.any():
            state = self._refine.classify(qs[ask], None if motion is None else motion[ask])
            free[ask] = state == FREE
            ask[ask] = state == UNKNOWN
        self.counts["spheres"] += int(len(qs) - ask.sum())
        self.counts["drake"] += int(ask.sum())
        if not ask.any():
            return free
        if motion is not None:
            free[ask] = super().configs_free(qs[ask], motion[ask])
        elif ask.sum() <= _SERIAL:  # the parallel call costs more for a few configurations
            checker = self._checker
            free[ask] = [checker.CheckConfigCollisionFree(self.full(q)) for q in qs[ask]]
        else:
            free[ask] = super().configs_free(qs[ask])
        return free

    def free_prefix(self, q_a, q_b) -> float:
        """As ``CheckerAdapter.free_prefix`` (see ``free_prefixes``)."""
        return float(self.free_prefixes(q_a[None, :], q_b[None, :])[0])

    def free_prefixes(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """``free_prefix`` of many segments (rows of q_a, q_b), (K,): each segment's samples
        are classified from its start up to its first certain collision (or first uncertain
        sample before the Drake fallback); the uncertain ones before that then go to Drake
        together."""
        step = self._resolution or self._checker.edge_step_size()
        fallback = self._fallback()
        end, n, edge, local = self._model.prefixes(q_a, q_b, step, stop_at_unknown=not fallback)
        self.counts["spheres"] += int(np.minimum(end + 1, n).sum()) - len(edge)
        if fallback and len(edge):
            samples = q_a[edge] + ((local + 1) / n[edge])[:, None] * (q_b[edge] - q_a[edge])
            blocked = ~self.undecided_free(samples)
            np.minimum.at(end, edge[blocked], local[blocked])
        return np.where(end > 0, end / n, 0.0)

    def edge_free(self, q_a, q_b) -> bool:
        """True when every sample of the segment at the edge step, q_a included, is
        collision-free: q_a, then the samples from q_a up to the first certain collision,
        then the uncertain ones to Drake in growing chunks (sphere checks cost microseconds,
        so their order hardly matters)."""
        if self._resolution is not None and self.is_proven(q_a, q_b):
            return True
        step = self._resolution or self._checker.edge_step_size()
        fallback = self._fallback()
        starts = np.vstack([q_a, q_a]).astype(float)  # q_a alone (one sample), then the edge
        ends = np.vstack([q_a, q_b]).astype(float)
        end, n, edge, local = self._model.prefixes(starts, ends, step, stop_at_unknown=not fallback)
        self.counts["spheres"] += int(np.minimum(end + 1, n).sum()) - len(local)
        if np.any(end < n):
            return False
        t = (local + 1) / n[edge]
        unknown = starts[edge] + t[:, None] * (ends[edge] - starts[edge])
        chunk = 4
        for start in range(0, len(unknown), chunk):
            piece = unknown[start : start + chunk]
            if not self.undecided_free(piece).all():
                return False
            chunk *= 2
        if self._resolution is not None:
            self._proven.add(edge_key(q_a, q_b))
        return True
