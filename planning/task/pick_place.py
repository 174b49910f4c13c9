"""PickPlaceTask: pick the scene's object and place it on the other side of the obstacle.

The steps (each reported as it ends, with its planning time):

1. ``move_above_object``: plan to a hand pose above the object, pointing down, and move there;
2. ``open_gripper``;
3. ``approach``: a Cartesian line straight down until the object is between the fingers;
4. ``close_gripper``: close until the fingers stop on the object;
5. ``lift``: a box of the object's size, at its measured pose, is attached to the hand in the
   PlanningScene (held: the closed fingers touch it, which the check before motion allows only
   for an attached object), then a short Cartesian line up;
6. ``attach``: the attached box is moved to the object's pose in the hand measured after the
   lift (from here on the planner keeps it clear of the world);
7. ``move_to_place``: plan over the obstacle to above the place target, then a Cartesian line
   down until the object is just above the table;
8. ``release``: open, detach the object, retreat straight up (ignoring the object, which may
   still touch the open fingers), and put the object into the scene where it came to rest.

Before moving, ``check`` (reported as step 0, its time counted as planning) looks for reasons
the task cannot work: no object or place target, an object too wide for the hand, an object or a
place target inside another object, no collision-free IK solution above the grasp or the place
with a straight line down from there. Such a scene is reported impossible, not tried. The check
also picks the grasp: the first top-down yaw, nearest the hand's, for which all of that works.
The planner models the fingers open (the planning scene keeps ``finger_positions`` at the open
hand); the check before each motion (``planning.execution.gate``) uses the measured fingers,
which touch the object from ``close_gripper`` on: so it is attached before it is lifted.

Poses are those of the grasp frame G (``PickPlaceOptions``: ``tool_xyz``, ``tool_rpy`` place it in
the end-effector frame E); the planner is asked for the E that puts G there. An arm without
finger joints (the UR5 of VAMP's set, its Robotiq fingers fixed open) closes a virtual gripper,
which in a kinematic station holds the object where it is (``MotionPlanningInterface``).
"""

from __future__ import annotations

import dataclasses as dc
import time
from collections.abc import Callable

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw

from planning.errors import PlanningError
from planning.scene_objects import SceneObject
from planning.task.geometry import boxes_overlap, rotation_distance, top_down_grasps
from planning.task.options import PickPlaceOptions

OBJECT = "object"
STEPS = (
    "check",
    "move_above_object",
    "open_gripper",
    "approach",
    "close_gripper",
    "lift",
    "attach",
    "move_to_place",
    "release",
)
"""The names of the reported steps, in order (``check`` is the feasibility check)."""


@dc.dataclass
class StepReport:
    name: str
    success: bool
    planning_time_s: float
    message: str = ""
    sim_time_s: float = 0.0  # simulated time when the step ended


@dc.dataclass
class TaskReport:
    """The task's outcome; ``to_dict`` gives the report keys of ``python -m drake_sim.pickplace
    --report`` (docs/pickplace.md, The report)."""

    success: bool = False
    impossible: bool = False
    failed_step: str | None = None
    reason: str = ""
    steps: list[StepReport] = dc.field(default_factory=list)
    place_error_m: float | None = None
    object_final_position: list[float] | None = None
    sim_time_s: float = 0.0
    wall_time_s: float = 0.0

    @property
    def planning_time_s(self) -> float:
        return float(sum(s.planning_time_s for s in self.steps))

    def to_dict(self) -> dict:
        return {
            "success": self.success,
            "impossible": self.impossible,
            "failed_step": self.failed_step,
            "reason": self.reason,
            "place_error_m": self.place_error_m,
            "object_final_position": self.object_final_position,
            "planning_time_s": self.planning_time_s,
            "sim_time_s": self.sim_time_s,
            "wall_time_s": self.wall_time_s,
            "real_time_factor": self.sim_time_s / self.wall_time_s if self.wall_time_s else None,
            "steps": [dc.asdict(s) for s in self.steps],
        }


class _StepError(Exception):
    pass


class PickPlaceTask:
    """Picks the scene's ``object`` and places it at ``scene.place_position``.

    Args:
        interface: a started ``MotionPlanningInterface`` whose scene has an ``object`` box.
        options: heights and margins.
        on_step: called with each ``StepReport`` as the step ends.
    """

    def __init__(
        self,
        interface,
        options: PickPlaceOptions | None = None,
        *,
        on_step: Callable[[StepReport], None] | None = None,
    ):
        self._mpi = interface
        self._scene = interface.scene
        self.options = options or PickPlaceOptions()
        self._on_step = on_step
        opts = self.options
        self._X_EG = RigidTransform(RollPitchYaw(opts.tool_rpy), np.asarray(opts.tool_xyz, float))
        self._grasp: RigidTransform | None = None  # X_OG of the chosen top-down grasp
        self._scene_object: SceneObject | None = None  # the object as the scene had it

    # ---------------------------------------------------------------------- feasibility ----
    def check(self) -> str | None:
        """Returns why the task is impossible in this scene, or None; picks the grasp."""
        scene, opts = self._scene, self.options
        obj = scene.world_objects.get(OBJECT)
        if obj is None or obj.shape != "box":
            return "the scene has no box named 'object' to pick"
        if scene.place_position is None:
            return "the scene has no place target"
        X_WO = self._object_pose()
        if min(obj.size[:2]) < opts.min_object_width:
            return f"the object is thinner than {opts.min_object_width} m"
        X_WP = self._place_pose(X_WO)
        for name, other in scene.world_objects.items():
            if name in (OBJECT, "table") or other.shape != "box":
                continue
            if boxes_overlap(obj.size, X_WO, other.size, other.X_PO, opts.overlap_margin):
                return f"the object overlaps {name!r}"
            if boxes_overlap(obj.size, X_WP, other.size, other.X_PO):
                return f"the place target is inside {name!r}"
        grasps = top_down_grasps(X_WO, obj.size, opts.max_object_width)
        if not grasps:
            return f"the object is wider than the hand can hold ({opts.max_object_width} m)"
        hand = self._tcp().rotation()
        grasps.sort(key=lambda X: rotation_distance(hand, X.rotation()))
        why = ""
        for X_WG in grasps:
            X_OG = X_WO.inverse() @ X_WG
            approaches, why = self._approaches(X_WO, X_OG, obj.size)
            if approaches is not None:
                self._grasp = X_OG
                self._q_pregrasp, self._q_preplace = approaches
                return None
        return why

    def _approaches(self, X_WO, X_OG, size) -> tuple[list[np.ndarray] | None, str]:
        """For a grasp X_OG: collision-free IK above the grasp and above the place, each with a
        straight line down to it (the place one without the held object, which the planner
        adds when the object is attached). Returns (the two configurations above, "") or
        (None, why not)."""
        X_WG = self._grasp_pose(X_WO, X_OG, size)
        X_WP = self._place_pose(X_WO) @ X_WO.inverse() @ X_WG  # the TCP when placing
        opts, q_high = self.options, []
        for what, X_low, height in (
            ("the object", X_WG, opts.pregrasp_height),
            ("the place target", X_WP, opts.preplace_height),
        ):
            try:
                q = self._mpi.state.ik(self._ee(self._up(X_low, height))).q
            except PlanningError as e:
                return None, f"no collision-free IK above {what} (out of reach?): {e.message}"
            line = self._mpi.planner.plan_cartesian(self._ee(X_low), q_start=q)
            if not line.success:
                return None, f"no straight way down to {what}: {line.message}"
            q_high.append(q)
        return q_high, ""

    def _tcp(self) -> RigidTransform:
        """X_WG of the grasp frame now."""
        return self._mpi.state.hand_pose() @ self._X_EG

    def _ee(self, X_WG: RigidTransform) -> RigidTransform:
        """X_WE of the end-effector frame that puts the grasp frame at X_WG."""
        return X_WG @ self._X_EG.inverse()

    @staticmethod
    def _up(X: RigidTransform, height: float) -> RigidTransform:
        return RigidTransform(X.rotation(), X.translation() + [0.0, 0.0, height])

    def _grasp_pose(self, X_WO, X_OG, size) -> RigidTransform:
        """The TCP pose that holds the object ``grasp_depth`` below its top (at most its middle),
        and clear of the table."""
        depth = self._grasp_depth(size)
        X_WG = X_WO @ X_OG
        top = X_WO.translation()[2] + 0.5 * size[2]
        z = max(top - depth, self._table_top() + self.options.finger_clearance)
        return RigidTransform(X_WG.rotation(), [*X_WG.translation()[:2], z])

    def _grasp_depth(self, size) -> float:
        return min(self.options.grasp_depth, 0.5 * size[2])

    def _place_pose(self, X_WO) -> RigidTransform:
        """X_WO at the place target: same orientation, resting ``place_clearance`` above the
        table (or at the target's height when it says so)."""
        obj = self._scene.world_objects.get(OBJECT) or self._scene.attached_objects[OBJECT]
        p = np.asarray(self._scene.place_position, dtype=float).copy()
        p[2] = max(p[2], self._table_top() + 0.5 * obj.size[2]) + self.options.place_clearance
        return RigidTransform(X_WO.rotation(), p)

    def _table_top(self) -> float:
        table = self._scene.world_objects.get("table")
        if table is None:
            return 0.0
        return float(table.X_PO.translation()[2] + 0.5 * table.size[2])

    def _object_pose(self) -> RigidTransform:
        """The object's pose: measured in the simulation when the station has it."""
        X = self._mpi.object_pose()
        if X is None:
            X = self._scene.object_pose(OBJECT)
        return X

    # ------------------------------------------------------------------------------ run ----
    def run(self) -> TaskReport:
        """Runs the task and returns its report (never raises for a failed step)."""
        wall0, sim0 = time.perf_counter(), self._mpi.time
        report = TaskReport()
        t0 = time.perf_counter()
        reason = self.check()
        check = StepReport("check", reason is None, time.perf_counter() - t0, reason or "feasible")
        report.steps.append(check)
        if self._on_step is not None:
            self._on_step(check)
        if reason is not None:
            report.impossible, report.failed_step, report.reason = True, "check", reason
        else:
            steps = [
                self._move_above_object,
                lambda: self._gripper(self._mpi.layout.finger_open),
                self._approach,
                self._close,
                self._lift,
                self._attach,
                self._move_to_place,
                self._release,
            ]
            for name, step in zip(STEPS[1:], steps, strict=True):
                ok, planning, message = self._run_step(step)
                report.steps.append(StepReport(name, ok, planning, message, self._mpi.time))
                if self._on_step is not None:
                    self._on_step(report.steps[-1])
                if not ok:
                    report.failed_step, report.reason = name, message
                    break
            else:
                self._mpi.advance(self.options.settle_time)
        p_WO = self._object_pose().translation()
        report.object_final_position = [float(v) for v in p_WO]
        if self._scene.place_position is not None:
            report.place_error_m = float(np.linalg.norm(p_WO[:2] - self._scene.place_position[:2]))
        placed = report.place_error_m is not None
        placed = placed and report.place_error_m <= self.options.place_tolerance
        report.success = report.failed_step is None and placed
        if report.failed_step is None and not report.success:
            report.failed_step = "release"
            report.reason = f"the object ended {report.place_error_m:.3f} m from the place target"
        report.sim_time_s = self._mpi.time - sim0
        report.wall_time_s = time.perf_counter() - wall0
        return report

    def _run_step(self, step) -> tuple[bool, float, str]:
        self._planning = 0.0
        try:
            message = step() or "done"
        except (PlanningError, _StepError) as e:
            return False, self._planning, str(e)
        except (RuntimeError, ValueError) as e:  # e.g. a timing that cannot be computed
            return False, self._planning, f"{type(e).__name__}: {e}"
        return True, self._planning, message

    def _execute(self, result) -> str:
        self._planning += result.planning_time
        if not result.success:
            raise _StepError(result.message)
        outcome = self._mpi.execute(result)
        if not outcome.success:
            raise _StepError(outcome.message)
        return result.message

    # ---------------------------------------------------------------------------- steps ----
    def _move_above_object(self) -> str:
        obj = self._scene.world_objects[OBJECT]
        self._X_WG = self._grasp_pose(self._object_pose(), self._grasp, obj.size)
        request = self._mpi.planner.plan_to_joints
        return self._execute(self._plan_timed(request, self._q_pregrasp))

    def _plan_timed(self, request, *args, **kwargs):
        """Runs a planner request from the current state; counts its time if it raises (a
        result's own planning time is counted by ``_execute``)."""
        t0 = time.perf_counter()
        try:
            return request(*args, q_start=self._mpi.state.q, **kwargs)
        except PlanningError:
            self._planning += time.perf_counter() - t0
            raise

    def _gripper(self, position: float) -> str:
        outcome = self._mpi.move_gripper(position)
        if not outcome.success:
            raise _StepError(outcome.message)
        return outcome.message

    def _approach(self) -> str:
        target = self._ee(self._X_WG)
        return self._execute(self._plan_timed(self._mpi.planner.plan_cartesian, target))

    def _close(self) -> str:
        outcome = self._mpi.close_gripper()
        if not outcome.grasped:
            raise _StepError(f"the fingers closed on nothing ({outcome.message})")
        return outcome.message

    def _cartesian_up(self, height: float) -> str:
        target = self._up(self._mpi.state.hand_pose(), height)  # E rises as G does
        return self._execute(self._plan_timed(self._mpi.planner.plan_cartesian, target))

    def _lift(self) -> str:
        self._hold()
        return self._cartesian_up(self.options.lift_height)

    def _attach(self) -> str:
        self._hold()  # where the lift left the object in the hand
        size = self._scene_object.size
        return f"attached a {size[0]:.3f} x {size[1]:.3f} x {size[2]:.3f} m box"

    def _hold(self) -> None:
        """Attaches a box of the object's size to the hand at the object's measured pose (the
        world object the first time, the attached box again after that)."""
        scene, q = self._scene, self._mpi.state.q
        if OBJECT in scene.world_objects:
            self._scene_object = scene.world_objects[OBJECT]
        X_WO = self._object_pose()
        scene.remove_object(OBJECT)
        X_AO = scene.attachment_pose(q).inverse() @ X_WO
        scene.attach_new(SceneObject(OBJECT, "box", tuple(self._scene_object.size), X_AO))
        self._X_OG = X_WO.inverse() @ self._tcp()

    def _move_to_place(self) -> str:
        X_WO_place = self._place_pose(self._object_pose())
        X_WG = X_WO_place @ self._X_OG  # with the grasp as measured now
        above = self._up(X_WG, self.options.preplace_height)
        t0 = time.perf_counter()
        try:  # the arm configuration checked before the task, corrected for the real grasp
            q_above = self._mpi.state.ik(self._ee(above), q_seed=self._q_preplace).q
        finally:
            self._planning += time.perf_counter() - t0
        self._execute(self._plan_timed(self._mpi.planner.plan_to_joints, q_above))
        return self._execute(self._plan_timed(self._mpi.planner.plan_cartesian, self._ee(X_WG)))

    def _release(self) -> str:
        self._gripper(self._mpi.layout.finger_open)
        scene = self._scene
        scene.detach(OBJECT, self._mpi.state.q)
        # The released object may still touch the open hand (it can tip against a finger as it
        # settles): like MoveIt's retreat with the object's touch links allowed, the straight
        # retreat up ignores the object, which goes back into the scene where it came to rest.
        scene.remove_object(OBJECT)
        try:
            return self._cartesian_up(self.options.retreat_height)
        finally:
            obj = self._scene_object
            scene.add_object(obj.with_pose(self._object_pose()))
