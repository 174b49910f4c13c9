"""The joint path pipeline of ``MotionPlanner``: from two collision-free configurations to a path
checked at the fine resolution.

With sphere models (``spheres.enabled``, every shape covered) and neither GCS nor KTO,
``JointPathSearch.find`` first runs the whole search in one compiled call on the spheres alone
(``planning.search.compiled_rrt``: straight line, RRT-Connect, shortcutting), then checks the
result at ``validation.resolution`` there too, asking Drake only about the samples the spheres
cannot decide. When that search gives up (``spheres.drake_fallback_after`` configurations) or
its path fails the fine check, the Python pipeline below takes over, with Drake deciding what
the spheres cannot from the start.

The Python pipeline tries the straight line; otherwise GCS (when regions are set) or
RRT-Connect with restarts (its run times are heavy-tailed), then shortcutting. The path is then
re-checked at ``validation.resolution``: a failing segment is re-planned on fine edge checks, at
most ``validation.max_repairs`` times, or the whole path when a segment cannot be repaired; KTO
smoothing is kept when it is shorter and passes the same check. Collision queries go to sphere
models first when ``spheres.enabled`` (``planning.collision.sphere_checker``). Both fine checks
cover the path between its samples too (``validation.swept``; ``checker.swept_free``).

``options`` is a ``planning.planner_options.MotionPlannerOptions`` (read, not imported: the
options belong to the planner's layer).
"""

import time

import numpy as np

from planning.collision import pair_tables
from planning.collision.checker import CheckerAdapter, first_invalid_segment, swept_free
from planning.collision.sphere_checker import SphereCheckerAdapter, sphere_model
from planning.collision.spheres import FREE
from planning.errors import ErrorCode, PlanningError
from planning.search import compiled_rrt
from planning.search.rrt import rrt_connect
from planning.search.shortcut import shortcut

_REPAIR_CHECKS = 50_000  # configurations a compiled repair of one segment may check, at most
_CHECK_S = 2e-6  # s, a generous time per configuration of the compiled search (measured 1.5 us)


class JointPathSearch:
    """Finds validated joint paths in a scene with a planner's options.

    Args:
        scene: the ``PlanningScene``.
        options: the ``MotionPlannerOptions``.

    Attributes:
        gcs: a ``planning.search.gcs.SceneGcs`` tried before RRT-Connect, or None.
        fused: the compiled search checks the ends, searches and fine-checks in one call
            (``compiled_rrt.solve``); False (the benchmark's profiler) makes those separate
            calls, each timed, at the cost of their dispatches.
    """

    fused = True

    def __init__(self, scene, options):
        self._scene = scene
        self._options = options
        self.gcs = None
        adapter = CheckerAdapter(scene)
        self.limits = (adapter.lower, adapter.upper)  # the arm's joint limits, rad (fixed)

    def adapter(self, resolution: float | None = None, *, search: bool = False, hulls: bool = True):
        """Collision queries: sphere models first when enabled
        (``planning.collision.sphere_checker``). A search adapter leaves Drake out for
        ``spheres.drake_fallback_after`` sphere-checked configurations (what the spheres cannot
        decide counts as colliding), then asks it too; a validating one always does, so validation
        accepts exactly what Drake's checker accepts. ``hulls`` False: the exact shapes are not
        asked (the caller has asked them already), whatever ``spheres.hull_proofs`` says."""
        opts = self._options.spheres
        if not opts.enabled:
            return CheckerAdapter(self._scene, resolution)
        after = None
        if search:
            after = opts.drake_fallback_after
            resolution = opts.search_resolution
        refine = opts.refine_slack if self._refine_model() is not None else None
        return SphereCheckerAdapter(
            self._scene, resolution, slack=opts.slack, fallback_after=after,
            refine_slack=refine, hulls=opts.hull_proofs and hulls
        )  # fmt: skip

    def _sphere_model(self):
        """The scene's sphere model when it can answer (enabled, all shapes covered), or None."""
        opts = self._options.spheres
        if not opts.enabled:
            return None
        model = sphere_model(self._scene, opts.slack)
        return model if model.active else None

    def _refine_model(self, rebuild: bool = False):
        """The tighter cover that decides what the first cannot (``spheres.refine_slack``),
        when enabled and able to answer, else None. Its robot part is remade in ``prepare``
        (``rebuild``) only: when held objects, allowed pairs or fingers changed since, a
        request lets Drake decide instead of spending ~45 ms remaking it."""
        opts = self._options.spheres
        if not (opts.enabled and opts.refine_slack):
            return None
        model = sphere_model(self._scene, opts.refine_slack)
        if not model.sync(rebuild_robot=rebuild):
            return None
        return model if model.active else None

    def prepare(self) -> None:
        """Syncs the sphere models with the scene (``MotionPlanner.prepare``), packs their data."""
        model = self._compiled_model()  # the synced sphere model, when the compiled search runs
        if model is not None:
            model.packed_data()
            self._hulls(model)
        else:
            self._sphere_model()
        self._refine_model(rebuild=True)

    def warm_up(self) -> None:
        """Has the compiled search ready (compiled, or loaded from numba's cache), once."""
        model = self._sphere_model()
        if model is not None:
            compiled_rrt.warm_up(model.kernel_data(), *self.limits, self._hulls(model))
            if self._options.spheres.hull_proofs:  # the Python side's exact proofs (~18 ms)
                model.prove_free((self.limits[0] + self.limits[1])[None, :] / 2.0)

    def warm_up_steps(self) -> list:
        """Everything the compiled search compiles, as named steps ``(name, callable)``: the
        sphere covers, the search's entry points, the exact shapes' proofs, the batched
        sphere checks and the own pairs' clearance tables (``pair_tables``, made by another
        robot's first model); ``planning.planner_kernels`` builds with them. Empty when the
        spheres are disabled or cannot answer."""
        model = self._sphere_model()
        if model is None:
            return []
        middle = ((self.limits[0] + self.limits[1]) / 2.0)[None, :]
        steps = [("the sphere covers", lambda: (self._refine_model(), model.packed_data()))]
        steps += compiled_rrt.warm_up_steps(model.kernel_data(), *self.limits, self._hulls(model))
        steps.append(("the exact shapes' proofs", lambda: model.prove_free(middle)))
        steps.append(("the batched sphere checks", lambda: model.classify(middle)))
        packed = (*model.packed_data(), *model.packed_hulls(), np.zeros(0, dtype=np.int64))
        steps.append(("the clearance tables", lambda: pair_tables.clearances(middle, *packed)))
        return steps

    def proves_free(self, q, *, first: bool = True) -> bool:
        """True when the sphere models prove the arm configuration q (D,) collision-free (then
        Drake's checker finds it free too): the first cover, then the tighter one; False when
        they cannot tell or there are none. ``first`` False: the tighter one alone (the first
        has been asked)."""
        for model in (self._sphere_model() if first else None, self._refine_model()):
            if model is not None and model.classify(q)[0] == FREE:
                return True
        return False

    def find(self, q_start, q_goal, deadline: float, check_ends=None) -> tuple[np.ndarray, str]:
        """A validated path from q_start to q_goal (D,) and how it was found.

        Args:
            check_ends: None when the caller has checked both ends; else a callable
                ``check_ends(start, goal)`` that decides with Drake the ends whose flag is True
                (those the spheres could not prove free) and raises when one collides. It is
                called before any search (in the compiled search, after the ends' sphere check,
                which is part of that one call).
        """
        opts = self._options
        if time.perf_counter() > deadline:
            raise self._failure(deadline, "no time was left to search")
        model = self._compiled_model()
        if check_ends is not None and not (self.fused and model is not None):
            check_ends(not self.proves_free(q_start), not self.proves_free(q_goal))
            check_ends = None
        compiled = self._compiled(model, q_start, q_goal, deadline, check_ends)
        if compiled is not None and compiled[0] is not None:
            return compiled[0], compiled[1]
        adapter = self.adapter(search=True)
        fine = self.adapter(opts.validation.resolution)
        rng = np.random.default_rng(opts.seed)
        attempt = 0
        while compiled is not None and compiled[2] is not None:
            # The compiled search's path failed the fine check: repair it; when that fails with
            # time left (a segment in a tight spot), a fresh compiled search with the next seed
            # rather than giving up (MBM: 3 UR5 and 3 Fetch requests failed in 0.25-1.5 s).
            _, how, path = compiled
            try:
                return self._validated(fine, path, how, deadline, rng)
            except PlanningError as e:
                if e.code is not ErrorCode.PLANNING_FAILED or time.perf_counter() >= deadline:
                    raise
            attempt += 1
            compiled = self._compiled(model, q_start, q_goal, deadline, None, attempt)
            if compiled[0] is not None:
                return compiled[0], f"{compiled[1]}+seed{attempt}"
        if compiled is not None:
            adapter.counts["spheres"] += opts.spheres.drake_fallback_after  # Drake from the start
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
            from planning.search.kto import kto_shorter

            speeds = opts.timing.max_velocity
            path, how = kto_shorter(self._scene, path, how, speeds, self.adapter(), opts.validation)
        return path, how

    def _hulls(self, model) -> tuple[np.ndarray, np.ndarray]:
        """The packed exact shapes the compiled search proves with (``spheres.hull_proofs``),
        or ``compiled_rrt.NO_HULLS``."""
        if not self._options.spheres.hull_proofs:
            return compiled_rrt.NO_HULLS
        return model.packed_hulls()

    def _compiled_model(self):
        """The sphere model of the compiled search, or None when that search does not apply
        (no sphere model, GCS or KTO in use)."""
        if self.gcs is not None or self._options.kto.enabled:
            return None
        return self._sphere_model()

    def _compiled(self, model, q_start, q_goal, deadline: float, check_ends=None, attempt=0):
        """The compiled search and its fine check (``planning.search.compiled_rrt.solve``: one
        call, the ends' sphere check first when ``check_ends`` is given, see ``find``), with up
        to ``validation.max_repairs`` compiled repairs of a segment that fails it, its random
        numbers seeded with ``seed`` + ``attempt``; ``model`` is
        ``_compiled_model()``.

        Returns:
            None when it does not apply (``_compiled_model``); else (path, how, None) for a
            checked path, (None, how, path) for a path that still fails the fine check, or
            (None, "rrt_connect", None) when the search gave up.
        """
        opts = self._options
        if model is None:
            return None
        data = model.kernel_data()
        lower, upper = self.limits
        rng = compiled_rrt.seed_state(opts.seed + attempt)
        # Compiled code cannot read the clock: the time left becomes a count of checks (at a
        # generous _CHECK_S each), which only binds when the timeout is short; otherwise a seed
        # gives the same path on any machine.
        left = max(0.0, deadline - time.perf_counter())
        budget = max(1, min(opts.spheres.drake_fallback_after, int(left / _CHECK_S)))
        spheres, fine = opts.spheres, opts.validation.resolution

        def arguments(edge_step, step, anchor_radius, kernel=(data,), checks=budget):
            # By position: numba's dispatch of keyword arguments costs ~0.5 ms a call.
            # ``kernel``: the KernelData (``plan``) or its two packed buffers (``solve``); then
            # the search's settings, one tuple (``compiled_rrt.plan``).
            settings = (
                edge_step,
                step,
                opts.rrt.goal_bias,
                checks,
                opts.shortcut.iterations,
                rng,
                anchor_radius,
                opts.rrt.balance,
                opts.rrt.dynamic_domain or np.inf,
                opts.rrt.dynamic_domain_min,
                spheres.search_hull_proofs,
            )
            return (lower, upper, *kernel, settings)

        search = (spheres.search_resolution, opts.rrt.step, spheres.anchor_radius)
        q_start = np.asarray(q_start, dtype=float)
        q_goal = np.asarray(q_goal, dtype=float)
        hulls = self._hulls(model)
        swept = opts.validation.swept
        if self.fused:  # the kernel data packed: two arrays to pass, not 35 (and the hulls' two)
            packed = arguments(*search, (*model.packed_data(), *hulls))
            result = compiled_rrt.solve(q_start, q_goal, *packed, bool(check_ends), fine, swept)
            if result[0] == compiled_rrt.ENDS_UNPROVEN:  # the tighter cover, then Drake
                check_ends(
                    bool(result[4] & 1) and not self.proves_free(q_start, first=False),
                    bool(result[4] & 2) and not self.proves_free(q_goal, first=False),
                )  # raises when one collides
                result = compiled_rrt.solve(q_start, q_goal, *packed, False, fine, swept)
            status, path, how, _, _, bad, unknown, segment = result
            checked = (bad, unknown, segment)
        else:  # the same steps as separate calls (the ends checked in find), each timed
            status, path, how, _ = compiled_rrt.plan(q_start, q_goal, *arguments(*search), *hulls)
            checked = None
        name = "straight" if how == 0 else "rrt_connect"
        if status != compiled_rrt.FOUND:
            return None, "rrt_connect", None
        # Segments before ``verified`` passed the fine check (Drake deciding what the spheres
        # could not): after a repair, only the new piece and what follows are checked.
        verified = 0
        for attempt in range(opts.validation.max_repairs + 1):
            bad = self._first_failing_segment(path[verified:], fine, data, hulls, checked)
            checked = None
            if bad < 0:
                return path, name, None
            bad += verified
            if attempt == opts.validation.max_repairs:
                break
            # A repair re-plans the segment on finer edges (``validation.repair_resolution``), the
            # spheres and the exact shapes alone deciding (nothing to ask Drake); the fine check
            # then looks at it again. A short segment needs no whole search's budget: one that
            # cannot be repaired within _REPAIR_CHECKS leaves the time to the Python pipeline.
            repair = arguments(
                opts.validation.repair_resolution,
                opts.validation.repair_step,
                0.0,
                checks=min(budget, _REPAIR_CHECKS),
            )
            status, piece, _, _ = compiled_rrt.plan(path[bad], path[bad + 1], *repair, *hulls)
            if status != compiled_rrt.FOUND:
                break
            path = np.vstack([path[:bad], piece, path[bad + 2 :]])
            verified = bad
            name = "rrt_connect+repaired"
        return None, name, path

    def _first_failing_segment(self, path, resolution: float, data, hulls, checked=None) -> int:
        """The first segment of the path with a sample at ``resolution`` (a cell, with
        ``validation.swept``: ``swept_free``) that the spheres prove colliding or Drake finds
        colliding among those they, the exact shapes (``hulls``, packed) and the tighter cover
        cannot decide; -1 when none. ``checked``: the spheres' fine check, when made already."""
        swept = self._options.validation.swept
        if checked is None:
            checked = compiled_rrt.fine_check(path, resolution, data, *hulls, swept)[:3]
        bad, unknown, segment = checked
        if bad >= 0:  # only samples before the colliding segment matter
            unknown, segment = unknown[segment < bad], segment[segment < bad]
        if len(unknown):  # what the exact shapes could not prove free (the compiled check)
            adapter = self.adapter(resolution, hulls=False)
            if swept:  # the smaller cells go to the exact shapes too
                halves = compiled_rrt.cell_halves(path, segment, resolution)
                free = swept_free(self.adapter(resolution), unknown, halves, adapter.cell_ratios)
            blocked = segment[~(free if swept else adapter.undecided_free(unknown))]
            if len(blocked):
                return int(blocked.min())
        return int(bad)

    def _shortcut(self, adapter, path: np.ndarray, deadline: float, rng) -> np.ndarray:
        """Shortcuts a path with ``shortcut.time_fraction`` of the time left."""
        opts = self._options.shortcut
        budget = opts.time_fraction * max(0.0, deadline - time.perf_counter())
        deadline = time.perf_counter() + budget
        return shortcut(adapter, path, iterations=opts.iterations, deadline=deadline, rng=rng)

    def _rrt(self, adapter, q_a, q_b, *, deadline: float, rng, step=None) -> np.ndarray | None:
        """RRT-Connect (``planning.search.rrt``) with ``rrt.batch`` extensions per query."""
        opts = self._options.rrt
        return rrt_connect(
            adapter, q_a, q_b, step=step or opts.step, goal_bias=opts.goal_bias,
            deadline=deadline, rng=rng, batch=opts.batch, balance=opts.balance
        )  # fmt: skip

    def _validated(self, fine, path, how, deadline, rng) -> tuple[np.ndarray, str]:
        """Re-checks the path at the fine resolution; re-plans a failing segment with
        RRT-Connect on fine edge checks (whose edges are then not checked twice), at most
        ``validation.max_repairs`` times. When a segment cannot be repaired within
        ``validation.repair_timeout`` (its ends sit in a tight spot), the whole path is
        re-planned and shortened with fine edge checks instead."""
        opts = self._options.validation
        for _ in range(opts.max_repairs + 1):
            bad = first_invalid_segment(fine, path, opts.resolution, opts.swept)
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
