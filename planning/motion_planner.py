"""MotionPlanner: joint, named, pose and Cartesian goals on a ``PlanningScene``.

Every request checks its start and goal (limits, finite values, collisions naming the bodies),
then finds a joint path: the straight line when it is collision-free, else RRT-Connect followed
by shortcutting. With sphere models of the robot (the default) all of that runs in one compiled
call on the spheres (``planning.search.compiled_rrt``: what they prove free is free for Drake
too); when it gives up, the Python pipeline (batched RRT-Connect, ``planning.search.rrt``, and
``planning.search.shortcut``) asks the scene's ``SceneGraphCollisionChecker`` about what the
spheres cannot decide. Every path is re-checked at ``validation.resolution`` (0.01 rad) before it
is returned, accepting a configuration only when the spheres prove it free or Drake's checker
finds it free; a segment failing that check is re-planned with edges checked at that
resolution. The path is then timed within the scaled velocity and acceleration limits
(``planning.timing.retime``: TOPP-RA, stopping only at sharp corners; rest to rest where the
rounded corners would graze an obstacle) into a ``Plan``.

Requests start from the planner's ``RobotState`` (its current q; MoveIt's "current state")
unless given ``q_start``. Failures raise ``PlanningError`` with a code; a Cartesian path that
is only partly achievable is returned with ``success=False`` and the fraction achieved.
"""

import dataclasses as dc
import functools
import time

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix

from planning import planner_kernels
from planning.collision.checker import CheckerAdapter
from planning.errors import ErrorCode, PlanningError
from planning.paths import path_length
from planning.plan import Plan, PlanResult, plan_robot
from planning.planner_options import MotionPlannerOptions, load_planner_options, request_timeout
from planning.planner_setup import kernels_now, make_search, warm_up_timing
from planning.robot_state import RobotState
from planning.scene_objects import describe_scene
from planning.search.cartesian import cartesian_path
from planning.timing.retime import RetimeOptions

__all__ = ["MotionPlanner", "MotionPlannerOptions", "load_planner_options"]


class MotionPlanner:
    """Plans collision-free motions of a robot's planning group in a ``PlanningScene``.

    Args:
        scene: the planning scene (robot, objects, collision checker).
        options: planner options; ``MotionPlannerOptions()`` (the defaults) when None.
        state: the current state requests start from; ``RobotState(scene)`` (the model's
            home) when None.
    """

    def __init__(self, scene, options: MotionPlannerOptions | None = None, *, state=None):
        self._scene = scene
        options = options if options is not None else MotionPlannerOptions()
        options.check()
        timing = options.timing.with_robot_limits(scene.model.robot)  # empty ones: the robot's
        self._options = dc.replace(options, timing=timing)
        self._state = state if state is not None else RobotState(scene)
        # Until the compiled search is in numba's cache, plan on Drake's checker while it is
        # built in the background (``planning.planner_setup``), then switch to it.
        self._pending = self._options.spheres.enabled and not kernels_now()
        warm_up_timing()
        self._search = make_search(scene, self._options, self._pending)  # .gcs set by use_gcs()
        lower, upper = self._search.limits  # for _as_arm: the limits, and with their tolerance
        self._limits = (lower, upper, lower - 1e-6, upper + 1e-6)
        if self._pending:  # IK's steps come from the background build, compiled once
            planner_kernels.await_shared()
        self._state.ik_solver()  # made now rather than in the first pose request

    def _switch_when_ready(self) -> None:
        """At a request's start: switches to the compiled search once its background build has
        finished (it is then loaded from the cache, ~0.5 s)."""
        if not self._pending or not planner_kernels.ready():  # ~1 ms: numba's index files
            return
        self._pending = False
        gcs = self._search.gcs
        self._search = make_search(self._scene, self._options, pending=False)
        self._search.gcs = gcs

    def use_gcs(self, regions, region_options=None, gcs_options=None) -> None:
        """Plans through IRIS regions with ``GcsTrajectoryOptimization`` first (opt-in).

        While the scene is the one the regions were grown in (same cache key), a request whose
        straight line collides tries GCS (``planning.search.gcs``) before RRT-Connect; its path is
        validated like any other. Measured on the pick-and-place scene: GCS takes 0.7 to 1.7 s
        per request against 0.01 to 0.24 s for RRT-Connect, for paths up to 45 % shorter, so
        RRT-Connect stays the default.

        Args:
            regions: a ``planning.search.iris_regions.RegionSet`` (``load_or_build_regions``).
            region_options: the ``RegionOptions`` they were grown with (defaults when None).
            gcs_options: ``GcsOptions``; the planner's validation step and speed limits when
                None.
        """
        from planning.search.gcs import GcsOptions, SceneGcs

        opts = self._options
        gcs_options = gcs_options or GcsOptions(
            validation_resolution=opts.validation.resolution,
            max_velocity=list(opts.timing.max_velocity),
        )
        self._search.gcs = SceneGcs(self._scene, regions, region_options, gcs_options)

    def prepare(self) -> None:
        """Brings the planner's collision models up to date with the scene now. Requests do it
        themselves when the scene has changed; calling it after a change keeps that work (the
        world's shapes re-read into the sphere model) out of the next request, as a scene
        update does in MoveIt. The tighter cover (``spheres.refine_slack``) is remade here only
        after held objects or finger positions change (~45 ms); until then requests leave what
        the first cover cannot decide to Drake."""
        self._switch_when_ready()
        self._search.prepare()

    @property
    def scene(self):
        """The ``PlanningScene`` every request is planned and checked in."""
        return self._scene

    @property
    def options(self) -> MotionPlannerOptions:
        """The options, checked when the planner was made."""
        return self._options

    @property
    def state(self) -> RobotState:
        """The current state requests start from unless given ``q_start``."""
        return self._state

    # ------------------------------------------------------------------------ requests ----
    def plan_to_joints(self, q_goal, *, q_start=None, timeout: float | None = None) -> PlanResult:
        """Plans to a joint configuration (7 arm joints in rad, or 9 with the fingers).

        Raises:
            PlanningError: INVALID_START, START_IN_COLLISION, INVALID_GOAL, GOAL_IN_COLLISION,
                PLANNING_FAILED or TIMED_OUT; INVALID_MOTION_PLAN for a ``timeout`` that is not
                a finite number of seconds > 0.
        """
        budget = request_timeout(timeout, self._options.timeout)
        self._switch_when_ready()
        t0 = time.perf_counter()
        deadline = t0 + budget
        path, how = self._find(q_start, q_goal, deadline)
        return self._result(path, how, t0)

    def plan_to_named(self, name: str, *, q_start=None, timeout: float | None = None):
        """Plans to a named configuration of the robot's description or SRDF (e.g. "ready")."""
        return self.plan_to_joints(self._state.named(name), q_start=q_start, timeout=timeout)

    def plan_to_pose(
        self,
        X_WE: RigidTransform | None = None,
        *,
        p_WE=None,
        R_WE: RotationMatrix | None = None,
        q_start=None,
        timeout: float | None = None,
    ) -> PlanResult:
        """Plans to a pose of the end effector E, a position alone or an orientation alone.

        IK (``RobotState.ik``, with the scene's IK tolerances) gives up to
        ``options.pose.ik_solutions`` distinct collision-free goals, the first seeded at the start;
        each is tried in turn until a path is found.

        Args:
            X_WE: the goal pose of E in the world W.
            p_WE: the goal position of E, m, any orientation (when X_WE is None).
            R_WE: the goal orientation of E, any position (when X_WE is None).

        Raises:
            PlanningError: NO_IK_SOLUTION, GOAL_IN_COLLISION (every IK solution found without
                collision constraints collides; the bodies are named), or as ``plan_to_joints``.
        """
        budget = request_timeout(timeout, self._options.timeout)
        self._switch_when_ready()
        t0 = time.perf_counter()
        deadline = t0 + budget
        q_start = self._check_start(q_start)
        if X_WE is None and p_WE is None and R_WE is None:
            raise PlanningError(ErrorCode.INVALID_GOAL, "a pose goal needs X_WE, p_WE or R_WE")
        rng = np.random.default_rng(self._options.seed)
        adapter = CheckerAdapter(self._scene)
        goals, last_error = [], None
        for k in range(self._options.pose.ik_solutions):
            if time.perf_counter() > deadline:
                break
            seed = q_start if k == 0 else rng.uniform(adapter.lower, adapter.upper)
            try:
                ik = self._state.ik(X_WE, p_WE=p_WE, R_WE=R_WE, q_seed=seed)
            except PlanningError as e:
                last_error = e
                if not goals:  # the IK solver has already made its own restarts
                    break
                continue
            if any(np.linalg.norm(ik.q - g) < 1e-3 for g in goals):
                continue
            goals.append(ik.q)
            try:
                path, how = self._search.find(q_start, ik.q, deadline)
            except PlanningError as e:
                last_error = e
                continue
            return self._result(path, how, t0)
        if not goals:
            self._raise_if_goal_collides(X_WE, p_WE, R_WE, q_start)
        raise last_error or PlanningError(ErrorCode.TIMED_OUT, "no time left for IK")

    def plan_cartesian(
        self, X_WG: RigidTransform, *, q_start=None, frame: str | None = None
    ) -> PlanResult:
        """Plans a straight line of the end effector (or ``frame``) to the pose X_WG.

        Returns a result with ``fraction`` < 1 and ``success`` False (code PLANNING_FAILED)
        when only part of the line is achievable; the partial motion is in ``trajectory``.

        Raises:
            PlanningError: INVALID_START, START_IN_COLLISION, INVALID_GOAL, FRAME_NOT_FOUND.
        """
        self._switch_when_ready()
        t0 = time.perf_counter()
        q_start = self._check_start(q_start)
        if not np.all(np.isfinite(X_WG.GetAsMatrix4())):
            raise PlanningError(ErrorCode.INVALID_GOAL, "the Cartesian goal pose is not finite")
        plant, scene = self._scene.plant, self._scene
        name = frame or scene.model.ee_frame
        if not plant.HasFrameNamed(name, scene.model.instance):
            raise PlanningError(ErrorCode.FRAME_NOT_FOUND, f"the Panda has no frame {name!r}")
        opts = self._options
        frame_E = plant.GetFrameByName(name, scene.model.instance)
        result = cartesian_path(
            scene,
            self._search.adapter(opts.validation.resolution),
            frame_E,
            q_start,
            X_WG,
            max_step=opts.cartesian.step,
            max_rotation_step=opts.cartesian.rotation_step,
            jump_threshold=opts.cartesian.jump_threshold,
            resolution=opts.validation.resolution,
            solver=self._state.ik_solver().newton(frame_E),
        )
        plan = self._make_plan(result.waypoints, "cartesian", t0)
        if result.fraction < 1.0:
            return PlanResult(
                False,
                plan,
                ErrorCode.PLANNING_FAILED,
                f"Cartesian path stopped at {result.fraction:.0%}: {result.reason}",
                time.perf_counter() - t0,
                result.fraction,
            )
        return PlanResult(True, plan, None, "Cartesian path complete", time.perf_counter() - t0)

    def plan_path(self, q_start, q_goal, *, timeout: float | None = None) -> tuple[np.ndarray, str]:
        """Returns a validated collision-free path (N, 7) between two valid configurations and
        how it was found ("straight", "rrt_connect", ...); for benchmarks and callers that time
        paths themselves."""
        budget = request_timeout(timeout, self._options.timeout)
        self._switch_when_ready()
        deadline = time.perf_counter() + budget
        return self._find(q_start, q_goal, deadline)

    def _find(self, q_start, q_goal, deadline: float) -> tuple[np.ndarray, str]:
        """The search between two joint configurations, the ends checked on the way: their
        values here, their collisions in the search's first (compiled) call, Drake deciding
        what the spheres cannot (``_check_ends``)."""
        q_start = self._as_arm(
            self._state.q if q_start is None else q_start, ErrorCode.INVALID_START, "start"
        )
        q_goal = self._as_arm(q_goal, ErrorCode.INVALID_GOAL, "goal")
        ends = functools.partial(self._check_ends, q_start, q_goal)
        return self._search.find(q_start, q_goal, deadline, ends)

    # ------------------------------------------------------------------------- checking ----
    def _check_ends(self, q_start, q_goal, start: bool, goal: bool) -> None:
        """Raises START_IN_COLLISION or GOAL_IN_COLLISION (naming the bodies) when Drake finds
        the start (when ``start``) or the goal (when ``goal``) colliding."""
        if start:
            self._raise_if_colliding(q_start, ErrorCode.START_IN_COLLISION, "start")
        if goal:
            self._raise_if_colliding(q_goal, ErrorCode.GOAL_IN_COLLISION, "goal")

    def _check_start(self, q_start) -> np.ndarray:
        q = self._state.q if q_start is None else q_start
        return self._check(q, ErrorCode.INVALID_START, ErrorCode.START_IN_COLLISION, "start")

    def _check(self, q, invalid: ErrorCode, colliding: ErrorCode, what: str) -> np.ndarray:
        """Returns ``q`` as 7 arm joints, or raises ``invalid`` (not finite, wrong size, out of
        limits) or ``colliding`` (naming the bodies in collision)."""
        q = self._as_arm(q, invalid, what)
        # The spheres cover the geometry: what they prove free, Drake finds free too.
        if not self._search.proves_free(q):
            self._raise_if_colliding(q, colliding, what)
        return q

    def _raise_if_colliding(self, q, code: ErrorCode, what: str) -> None:
        if not self._scene.is_collision_free(q):
            raise PlanningError(code, f"the {what} collides: {self._scene.describe_collisions(q)}")

    def _as_arm(self, q, code: ErrorCode, what: str) -> np.ndarray:
        """q as the group's joints clamped into their limits (a copy), or raises ``code`` when
        it is not the group's or all the plant's positions, finite, or lies beyond a limit by
        more than 1e-6 rad. A few array operations (~4 us warm; a loop over plain floats took
        ~12 us on the Panda's 7 values)."""
        values = np.asarray(q, dtype=float).reshape(-1)
        lower, upper, low, high = self._limits
        n, total = self._scene.num_joints, self._scene.plant.num_positions()
        sizes = (n, total)
        if values.size == total and total != n:
            arm = values[self._scene.model.group_indices]
        else:
            arm = values[:n]
        inside = values.size in sizes and ((arm >= low) & (arm <= high)).all()  # NaN: outside
        if not (inside and np.isfinite(values).all()):
            if values.size not in sizes or not np.isfinite(values).all():
                listed = values.tolist()
                raise PlanningError(
                    code, f"the {what} must be {n} or {total} finite values, got {listed}"
                )
            raise PlanningError(code, f"the {what} {np.round(arm, 4).tolist()} is out of limits")
        return arm.clip(lower, upper)

    def _raise_if_goal_collides(self, X_WE, p_WE, R_WE, q_start) -> None:
        """Raises GOAL_IN_COLLISION when IK without collision avoidance finds only colliding
        solutions; returns when it finds none at all."""
        options = dc.replace(
            self._scene.config.ik, minimum_distance=None, check_collisions=False, max_restarts=3
        )
        try:
            ik = self._state.ik(X_WE, p_WE=p_WE, R_WE=R_WE, q_seed=q_start, options=options)
        except PlanningError:
            return
        if not self._scene.is_collision_free(ik.q):
            raise PlanningError(
                ErrorCode.GOAL_IN_COLLISION,
                f"the goal pose is only reachable in collision: "
                f"{self._scene.describe_collisions(ik.q)}",
            )

    # --------------------------------------------------------------------------- output ----
    def _result(self, path: np.ndarray, how: str, t0: float) -> PlanResult:
        plan = self._make_plan(path, how, t0)
        return PlanResult(True, plan, None, f"planned ({how})", time.perf_counter() - t0)

    def _make_plan(self, path: np.ndarray, how: str, t0: float) -> Plan:
        opts = self._options.timing
        plan = Plan(
            waypoints=path,
            max_velocity=np.asarray(opts.max_velocity) * opts.velocity_scaling,
            max_acceleration=np.asarray(opts.max_acceleration) * opts.acceleration_scaling,
            velocity_scaling=opts.velocity_scaling,
            acceleration_scaling=opts.acceleration_scaling,
            finger_positions=self._scene.finger_positions,
            scene=describe_scene(self._scene),
            robot=plan_robot(self._scene),
            info={
                "planner": how,
                "planning_time_s": time.perf_counter() - t0,
                "path_length": path_length(path),
            },
        )
        # The timing rounds gentle corners within 2 mrad of the checked path: check those
        # sections too, and where they graze something, stop at the waypoints instead.
        resolution = self._options.validation.resolution
        if plan.smoothing_collision(self._search.adapter(resolution), resolution) is not None:
            plan = dc.replace(plan, timing=RetimeOptions(method="rest_to_rest"))
        return plan
