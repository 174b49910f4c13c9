"""The joint path pipeline of ``MotionPlanner``: from two collision-free configurations to a path
checked at the fine resolution.

``JointPathSearch.find`` tries the straight line; otherwise GCS (when regions are set) or
RRT-Connect with restarts (its run times are heavy-tailed), then shortcutting. The path is then
re-checked at ``validation.resolution``: a failing segment is re-planned on fine edge checks, at
most ``validation.max_repairs`` times, or the whole path when a segment cannot be repaired; KTO
smoothing is kept when it is shorter and passes the same check. Collision queries go to sphere
models first when ``spheres.enabled`` (``planning.collision.sphere_checker``).

``options`` is a ``planning.planner_options.MotionPlannerOptions`` (read, not imported: the
options belong to the planner's layer).
"""

import time

import numpy as np

from planning.collision.checker import CheckerAdapter, first_invalid_segment
from planning.collision.sphere_checker import SphereCheckerAdapter
from planning.errors import ErrorCode, PlanningError
from planning.paths import path_length
from planning.search.rrt import rrt_connect
from planning.search.shortcut import shortcut


class JointPathSearch:
    """Finds validated joint paths in a scene with a planner's options.

    Args:
        scene: the ``PlanningScene``.
        options: the ``MotionPlannerOptions``.

    Attributes:
        gcs: a ``planning.search.gcs.SceneGcs`` tried before RRT-Connect, or None.
    """

    def __init__(self, scene, options):
        self._scene = scene
        self._options = options
        self.gcs = None

    def adapter(self, resolution: float | None = None, *, search: bool = False):
        """Collision queries: sphere models first when enabled
        (``planning.collision.sphere_checker``). A search adapter leaves Drake out for
        ``spheres.drake_fallback_after`` sphere-checked configurations (what the spheres cannot
        decide counts as colliding), then asks it too; a validating one always does, so validation
        accepts exactly what Drake's checker accepts."""
        opts = self._options.spheres
        if not opts.enabled:
            return CheckerAdapter(self._scene, resolution)
        after = None
        if search:
            after = opts.drake_fallback_after
            resolution = opts.search_resolution
        return SphereCheckerAdapter(self._scene, resolution, slack=opts.slack, fallback_after=after)

    def find(self, q_start, q_goal, deadline: float) -> tuple[np.ndarray, str]:
        opts = self._options
        adapter = self.adapter(search=True)
        fine = self.adapter(opts.validation.resolution)
        rng = np.random.default_rng(opts.seed)
        how = "straight"
        path = np.vstack([q_start, q_goal])
        if not adapter.edge_free(q_start, q_goal):
            how = "rrt_connect"
            path = self.gcs.path(q_start, q_goal, deadline) if self.gcs else None
            if path is not None:
                how = "gcs"
            while path is None and time.perf_counter() < deadline:
                # Restart with fresh trees now and then: RRT run times are heavy-tailed.
                path = self._rrt(
                    adapter,
                    q_start,
                    q_goal,
                    deadline=min(deadline, time.perf_counter() + opts.rrt.restart_interval),
                    rng=rng,
                )
            if path is None:
                raise self._failure(deadline, "RRT-Connect found no path")
            path = self._shortcut(adapter, path, deadline, rng)
        path, how = self._validated(fine, path, how, deadline, rng)
        if opts.kto.enabled and how != "straight":
            path, how = self._refined(path, how)
        return path, how

    def _shortcut(self, adapter, path: np.ndarray, deadline: float, rng) -> np.ndarray:
        """Shortcuts a path with ``shortcut.time_fraction`` of the time left."""
        opts = self._options.shortcut
        budget = opts.time_fraction * max(0.0, deadline - time.perf_counter())
        return shortcut(
            adapter,
            path,
            iterations=opts.iterations,
            deadline=time.perf_counter() + budget,
            rng=rng,
        )

    def _rrt(self, adapter, q_a, q_b, *, deadline: float, rng, step=None) -> np.ndarray | None:
        """RRT-Connect (``planning.search.rrt``) with ``rrt.batch`` extensions per query."""
        opts = self._options.rrt
        return rrt_connect(
            adapter,
            q_a,
            q_b,
            step=step or opts.step,
            goal_bias=opts.goal_bias,
            deadline=deadline,
            rng=rng,
            batch=opts.batch,
        )

    def _refined(self, path: np.ndarray, how: str) -> tuple[np.ndarray, str]:
        from planning.search.kto import kto_refine

        max_velocity = np.asarray(self._options.timing.max_velocity)
        dense = kto_refine(self._scene, path, max_velocity=max_velocity)
        if dense is None or path_length(dense) >= path_length(path):
            return path, how
        resolution = self._options.validation.resolution
        if first_invalid_segment(self.adapter(), dense, resolution) is not None:
            return path, how
        return dense, how + "+kto"

    def _validated(self, fine, path, how, deadline, rng) -> tuple[np.ndarray, str]:
        """Re-checks the path at the fine resolution; re-plans a failing segment with
        RRT-Connect on fine edge checks (whose edges are then not checked twice), at most
        ``validation.max_repairs`` times. When a segment cannot be repaired within
        ``validation.repair_timeout``
        (its ends sit in a tight spot), the whole path is re-planned and shortened with fine
        edge checks instead."""
        opts = self._options.validation
        for _ in range(opts.max_repairs + 1):
            bad = first_invalid_segment(fine, path, opts.resolution)
            if bad is None:
                return path, how
            # Measured: a fine-checked RRT-Connect between the segment's ends (usually a few
            # nodes) beats random two-segment detours, whose candidates mostly graze too.
            piece = None
            for step in (self._options.rrt.step, opts.repair_step):  # long steps first, then short
                local = min(deadline, time.perf_counter() + opts.repair_timeout)
                piece = self._rrt(
                    fine, path[bad], path[bad + 1], deadline=local, rng=rng, step=step
                )
                if piece is not None:
                    break
            if piece is not None:
                path = np.vstack([path[:bad], piece, path[bad + 2 :]])
                how += "+repaired"
                continue
            step = opts.repair_step
            whole = self._rrt(fine, path[0], path[-1], deadline=deadline, rng=rng, step=step)
            if whole is None:
                break
            path = self._shortcut(fine, whole, deadline, rng)
            how += "+replanned"
        raise self._failure(deadline, "no path passed the fine collision check")

    @staticmethod
    def _failure(deadline: float, why: str) -> PlanningError:
        if time.perf_counter() > deadline:
            return PlanningError(ErrorCode.TIMED_OUT, f"{why} before the timeout")
        return PlanningError(ErrorCode.PLANNING_FAILED, why)
