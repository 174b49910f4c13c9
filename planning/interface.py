"""MotionPlanningInterface: RobotState, PlanningScene and MotionPlanner for a user's own code,
joined to a running arm station (MoveIt's ``move_group`` interface, with no ROS).

One object holds one ``PlanningScene``, one ``RobotState`` and one ``MotionPlanner`` that share
them. Joined to a diagram that has the scene's robot with the station's ports
(``<robot>.position_command`` in, ``<robot>.state`` out, the group's joints then the fingers:
``panda.*`` for the Panda; ``diagrams.arm_station``), it drives the arm and the fingers and keeps
the ``RobotState`` at the latest measured joints. An arm without finger joints has a virtual
gripper (0 closed, 1 open): in a kinematic station, closing it near the object holds the object
at the tool until it opens again. Long actions either block (``execute``,
``move_gripper``, ``move_to_pose`` ...) or return a handle (``execute_async``,
``move_gripper_async``, ``plan_async``) with ``done()``, ``result()``, ``cancel()`` and
``progress``. The simulation runs in simulated time: it advances while you wait on a handle's
``result()`` or call ``advance``, and only then, so tests are deterministic.

No call hangs: durations, timeouts and finger positions that are not finite numbers in range
raise ``ValueError`` naming the argument (and change nothing), every wait is bounded (at most
``MAX_WAIT`` s per call; an action by its deadline), and ``close()`` (or leaving a ``with``
block) ends everything, after which calls raise ``RuntimeError("the interface is closed")``.

Typical use::

    with make_planning_station(load_pickplace_scenario(), mode="kinematic") as mpi:
        result = mpi.move_to_pose(X_WG)                       # plan, check, execute, wait
        handle = mpi.execute_async(mpi.planner.plan_to_named("ready").trajectory)
        while not handle.done():
            mpi.advance(0.1)                                  # ... other work here ...
"""

from __future__ import annotations

import concurrent.futures
import math
from collections.abc import Callable

import numpy as np

from planning.errors import ErrorCode, PlanningError
from planning.execution.commander import ArmCommand, GripperCommand
from planning.execution.gate import check_before_motion
from planning.execution.handles import (
    ActionHandle,
    ExecutionResult,
    PlanHandle,
    check_duration,
    submit,
)
from planning.execution.options import InterfaceOptions
from planning.execution.station_link import StationLink
from planning.model.planning_model import touch_links
from planning.motion_planner import MotionPlanner, MotionPlannerOptions
from planning.robot_state import RobotState

VIRTUAL_GRASP = 0.02
"""m: a virtual gripper (an arm without fingers) holds the object when the object is within this
of the gripper: the attach link or a link below it (the UR5's fixed Robotiq pads)."""


class MotionPlanningInterface(StationLink):
    """Planning and execution for a user's code on one shared robot state and scene.

    Joining the station, advancing, reading and judging actions: ``StationLink``. A context
    manager: ``with`` ... ``as mpi`` closes it on the way out (``close``).

    Args:
        scene: the ``PlanningScene`` (kept in sync by the user: add obstacles, attach objects).
        planner_options: ``MotionPlanner`` options; ``MotionPlannerOptions()`` when None.
        options: execution settings.

    Raises:
        ValueError: an option's time (settle_time, settle_timeout, finger_settle_timeout) is
            not a number of seconds in [0, MAX_WAIT], or poll_period not one in (0, MAX_WAIT].
    """

    def __init__(
        self,
        scene,
        planner_options: MotionPlannerOptions | None = None,
        *,
        options: InterfaceOptions | None = None,
    ):
        super().__init__(scene, RobotState(scene), options or InterfaceOptions())
        self.planner = MotionPlanner(scene, planner_options, state=self.state)
        self._executor: concurrent.futures.ThreadPoolExecutor | None = None
        self._plans: list[PlanHandle] = []  # requests not known to be over

    # ------------------------------------------------------------------------- closing ----
    def close(self) -> None:
        """Ends the interface: cancels the running arm and gripper actions (their results:
        PREEMPTED, "cancelled: the interface was closed") and the planning requests (their
        ``result()`` raises PREEMPTED), and shuts the planning thread down, waiting for a
        request that is running (its planner timeout bounds it). Closing again does nothing.

        From then on every other call raises ``RuntimeError("the interface is closed")``.
        """
        try:
            super().close()
        finally:
            for plan in self._plans:
                if not plan.done():  # a finished one keeps its result
                    plan.cancel("cancelled: the interface was closed")
            if self._executor is not None:
                self._executor.shutdown(wait=True, cancel_futures=True)

    # ------------------------------------------------------------------------- planning ----
    def plan_async(self, request: Callable, *args, **kwargs) -> PlanHandle:
        """Runs a planner request in a worker thread, from the current state unless
        ``q_start`` is given, e.g. ``plan_async(mpi.planner.plan_to_pose, X_WG, timeout=2.0)``.

        Do not change the scene while it runs.

        Raises:
            ValueError: ``timeout`` (passed on to the request) is not a number of seconds in
                (0, MAX_WAIT].
        """
        kwargs = self._request(kwargs)
        timeout = kwargs.get("timeout") or self.planner.options.timeout
        if self._executor is None:
            self._executor = concurrent.futures.ThreadPoolExecutor(1, "motion_planning")
        handle = submit(self._executor, request, timeout, *args, **kwargs)
        self._plans = [plan for plan in self._plans if not plan.done()] + [handle]
        return handle

    def _request(self, kwargs: dict) -> dict:
        """A planning request's keyword arguments, its ``timeout`` checked (ValueError unless
        None or in (0, MAX_WAIT] s), starting from the joints now unless ``q_start`` is given."""
        self._check_open()
        check_duration("timeout", kwargs.get("timeout"), optional=True, positive=True)
        return {"q_start": self.state.q, **kwargs}

    # ------------------------------------------------------------------------ execution ----
    def execute_async(self, plan) -> ActionHandle:
        """Checks a plan against the robot and the scene as they are now, and starts it.

        The check (``planning.execution.gate.check_before_motion``) is the one gate before
        motion: finite values, the robot's position limits, its velocity and acceleration limits
        (the planner's ``TimingOptions``), the start at the measured joints, no collision with
        the measured fingers and the attached objects. A refused plan sends no command.

        Args:
            plan: a ``Plan`` or a successful ``PlanResult``.

        Raises:
            PlanningError: INVALID_MOTION_PLAN (unsuccessful, or refused by the check, naming
                the first violation), INVALID_START (the plan starts away from the robot, or
                the arm is busy).
            RuntimeError: the interface is closed.
        """
        self._check_open()
        plan = self._as_plan(plan)
        if self._arm is not None and not self._arm.done():
            raise PlanningError(
                ErrorCode.INVALID_START, "the arm is still executing a plan: wait or cancel it"
            )
        x = self.read_state()
        check_before_motion(
            plan,
            self.scene,
            self.state.q,
            x[self.layout.finger_q],
            self.planner.options.timing,
            start_tolerance=self.options.start_tolerance,
            resolution=self.planner.options.validation.resolution,
        )
        t = self.time
        command = ArmCommand(q_hold=plan.waypoints[-1].copy(), plan=plan, t0=t)
        self._commander.set_arm(self._context(self._commander), command)
        self._arm = ActionHandle(self, "execute", t, t + plan.duration, plan=plan)
        return self._arm

    def execute(self, plan) -> ExecutionResult:
        """``execute_async(plan).result()``: runs the plan and waits for the arm to settle."""
        return self.execute_async(plan).result()

    def move_to_joints(self, q_goal, **kwargs) -> ExecutionResult:
        """Plans from the current state to ``q_goal`` and executes (PlanningError if no plan;
        ValueError for a ``timeout`` not in (0, MAX_WAIT] s)."""
        return self.execute(self.planner.plan_to_joints(q_goal, **self._request(kwargs)))

    def move_to_named(self, name: str, **kwargs) -> ExecutionResult:
        return self.execute(self.planner.plan_to_named(name, **self._request(kwargs)))

    def move_to_pose(self, X_WE=None, **kwargs) -> ExecutionResult:
        """Plans to a pose (or ``p_WE=`` / ``R_WE=`` alone) and executes."""
        return self.execute(self.planner.plan_to_pose(X_WE, **self._request(kwargs)))

    def move_cartesian(self, X_WE, **kwargs) -> ExecutionResult:
        """Plans a straight line to X_WE and executes it; a partial line is not executed.

        Raises:
            PlanningError: PLANNING_FAILED naming the fraction achieved.
        """
        return self.execute(self.planner.plan_cartesian(X_WE, **self._request(kwargs)))

    @staticmethod
    def _as_plan(plan):
        if hasattr(plan, "trajectory"):  # a PlanResult
            if not plan.success:
                raise PlanningError(
                    plan.code or ErrorCode.INVALID_MOTION_PLAN,
                    f"the request did not succeed: {plan.message}",
                )
            plan = plan.trajectory
        if plan is None or not hasattr(plan, "waypoints"):
            raise PlanningError(ErrorCode.INVALID_MOTION_PLAN, "no plan to execute")
        return plan

    # -------------------------------------------------------------------------- gripper ----
    def move_gripper_async(self, position: float) -> ActionHandle:
        """Moves each finger to ``position`` (``layout.finger_closed`` .. ``finger_open``: the
        Panda's m, 0 closed .. 0.04 open) at ``finger_speed``; a virtual gripper (an arm without
        fingers, 0 closed .. 1 open) moves in one ``poll_period``.

        Closing on an object stops there (physics: the fingers squeeze it with their force
        limit; kinematic: they stop at its faces, or a virtual gripper where it is when the
        object is at the tool, and the object follows the hand until the gripper opens again).
        A gripper move still running is superseded: it finishes at once, cancelled (PREEMPTED,
        "superseded by ...").

        Raises:
            ValueError: ``position`` is NaN or infinite, or ``options.finger_speed`` is not a
                finite number > 0 (the command is refused, a running move goes on).
            PlanningError: INVALID_GOAL, ``position`` is outside the gripper's range.
        """
        self._check_open()
        if not math.isfinite(position):
            raise ValueError(f"position must be a finite number of metres, not {position!r}")
        closed, open_ = self.layout.finger_closed, self.layout.finger_open
        if not closed <= position <= open_:
            raise PlanningError(
                ErrorCode.INVALID_GOAL,
                f"finger position {position} is outside [{closed:g}, {open_:g}]",
            )
        context, t = self._context(self._commander), self.time
        start = float(self._commander.gripper(context).sample(t))
        target, opening = position, position > start
        if self._follower is not None and not opening:
            target = max(target, self._kinematic_contact(self._context(self._follower), start))
        speed = self.options.finger_speed
        if not self.layout.num_fingers:  # a virtual gripper: open or closed at the next poll
            speed = (open_ - closed) / self.options.poll_period
        command = GripperCommand(start, target, t, speed)  # checks the speed
        if self._gripper is not None and not self._gripper.done():
            reason = f"superseded by a gripper move to {position} m"
            self._end(self._gripper, ErrorCode.PREEMPTED, reason, cancelled=True)
        if self._follower is not None and opening:
            self._follower.release(self._context(self._follower))
        self._commander.set_gripper(context, command)
        self._gripper = ActionHandle(self, "gripper", t, command.end_time(), target=position)
        return self._gripper

    def move_gripper(self, position: float) -> ExecutionResult:
        return self.move_gripper_async(position).result()

    def open_gripper(self) -> ExecutionResult:
        return self.move_gripper(self.layout.finger_open)

    def close_gripper(self) -> ExecutionResult:
        return self.move_gripper(self.layout.finger_closed)

    def _kinematic_contact(self, follower_context, opening: float) -> float:
        """Kinematic mode: the finger position at which closing meets the object (closed if the
        object is not between the fingers); a virtual gripper stops half-way when the object is
        within ``VIRTUAL_GRASP`` of the gripper."""
        closed = self.layout.finger_closed
        obj = self.scene.world_objects.get("object") or self.scene.attached_objects.get("object")
        if obj is None:
            return closed
        if not self.layout.num_fingers:
            if "object" not in self.scene.world_objects:
                return closed
            robot = self.scene.model.robot
            links = [robot.attach_link, *touch_links(robot)]
            gap = self.scene.distance_to_links("object", links, self.state.q, 2 * VIRTUAL_GRASP)
            return 0.5 * (closed + self.layout.finger_open) if gap <= VIRTUAL_GRASP else closed
        X_WT = self.state.fk()  # the TCP, between the fingertips; y is the closing axis
        X_TO = X_WT.inverse() @ self._follower.pose(follower_context)
        half = 0.5 * np.abs(X_TO.rotation().matrix()) @ np.asarray(obj.size, dtype=float)
        p = X_TO.translation()
        # Between the fingers: within the pads' reach along x and z, inside the opening along y.
        outside = abs(p[0]) > half[0] + 0.01 or abs(p[2]) > half[2] + 0.02
        if outside or abs(p[1]) + half[1] > opening:
            return closed
        return float(half[1] + abs(p[1]))
