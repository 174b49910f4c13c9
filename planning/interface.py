"""MotionPlanningInterface: RobotState, PlanningScene and MotionPlanner for a user's own code,
joined to a running Panda diagram (MoveIt's ``move_group`` interface, with no ROS).

One object holds one ``PlanningScene``, one ``RobotState`` and one ``MotionPlanner`` that share
them. Joined to a diagram that has a Panda with the station's ports (``panda.position_command``
in, ``panda.state`` out; ``diagrams.panda_station``), it drives the arm and the fingers and keeps
the ``RobotState`` at the latest measured joints. Long actions either block (``execute``,
``move_gripper``, ``move_to_pose`` ...) or return a handle (``execute_async``,
``move_gripper_async``, ``plan_async``) with ``done()``, ``result()``, ``cancel()`` and
``progress``. The simulation runs in simulated time: it advances while you wait on a handle's
``result()`` or call ``advance``, and only then, so tests are deterministic.

Typical use::

    mpi = make_planning_station(load_pickplace_scenario(), mode="kinematic")  # diagrams
    result = mpi.move_to_pose(X_WG)                           # plan, check, execute, wait
    handle = mpi.execute_async(mpi.planner.plan_to_named("ready").trajectory)
    while not handle.done():
        mpi.advance(0.1)                                      # ... other work here ...
"""

from __future__ import annotations

import concurrent.futures
from collections.abc import Callable

import numpy as np
from pydrake.math import RigidTransform
from pydrake.systems.analysis import Simulator

from planning.errors import ErrorCode, PlanningError
from planning.execution.commander import ArmCommand, GripperCommand, ObjectFollower, PandaCommander
from planning.execution.handles import ActionHandle, ExecutionResult, PlanHandle, submit
from planning.execution.options import InterfaceOptions
from planning.model.layout import (
    ARM_V,
    FINGER_CLOSED,
    FINGER_OPEN,
    FINGER_Q,
    FINGER_V,
    NUM_POSITIONS,
)
from planning.model.panda import ATTACHMENT_BODY
from planning.motion_planner import MotionPlanner, MotionPlannerOptions
from planning.robot_state import RobotState

"""Each finger's fully open position, m."""


class MotionPlanningInterface:
    """Planning and execution for a user's code on one shared robot state and scene.

    Args:
        scene: the ``PlanningScene`` (kept in sync by the user: add obstacles, attach objects).
        planner_options: ``MotionPlanner`` options; ``MotionPlannerOptions()`` when None.
        options: execution settings.
    """

    def __init__(
        self,
        scene,
        planner_options: MotionPlannerOptions | None = None,
        *,
        options: InterfaceOptions | None = None,
    ):
        self.scene = scene
        self.state = RobotState(scene)
        self.planner = MotionPlanner(scene, planner_options, state=self.state)
        self.options = options or InterfaceOptions()
        self._commander: PandaCommander | None = None
        self._follower: ObjectFollower | None = None
        self._station = None
        self._simulator: Simulator | None = None
        self._arm: ActionHandle | None = None
        self._gripper: ActionHandle | None = None
        self._executor: concurrent.futures.ThreadPoolExecutor | None = None
        self._monitors: list[Callable[[MotionPlanningInterface], None]] = []

    # ------------------------------------------------------------------ joining a diagram ----
    def add_to_builder(self, builder, station) -> None:
        """Adds the command source (and, for a kinematic station, the object follower) to a
        user's ``DiagramBuilder`` and connects them to ``station``'s ports.

        Args:
            builder: the builder that holds ``station``.
            station: a system with ``panda.position_command`` (input) and ``panda.state``
                (output); optionally ``object.position_command`` (kinematic) and
                ``object.pose``.
        """
        self._station = station
        commander = builder.AddSystem(
            PandaCommander(q_arm=self.state.q, finger=float(self.scene.finger_positions[0]))
        )
        commander.set_name("panda_commander")
        builder.Connect(commander.get_output_port(), station.GetInputPort("panda.position_command"))
        self._commander = commander
        if station.HasInputPort("object.position_command") and "object" in self.scene.world_objects:
            plant = self.scene.plant
            follower = builder.AddSystem(
                ObjectFollower(
                    plant=plant,
                    body=plant.GetBodyByName(ATTACHMENT_BODY),
                    X_WO=self.scene.object_pose("object"),
                )
            )
            follower.set_name("object_follower")
            builder.Connect(station.GetOutputPort("panda.state"), follower.get_input_port())
            builder.Connect(
                follower.get_output_port(), station.GetInputPort("object.position_command")
            )
            self._follower = follower

    def start(self, diagram, *, realtime_rate: float = 0.0) -> Simulator:
        """Creates and initialises the simulator of the built ``diagram`` and reads the state.

        Args:
            diagram: the diagram built from the builder given to ``add_to_builder``.
            realtime_rate: 0 runs as fast as possible; 1 paces the simulation at real time.
        """
        if self._commander is None:
            raise RuntimeError("call add_to_builder() before start()")
        self._simulator = Simulator(diagram)
        self._simulator.set_target_realtime_rate(realtime_rate)
        self._simulator.Initialize()
        self.read_state()
        return self._simulator

    @property
    def simulator(self) -> Simulator:
        if self._simulator is None:
            raise RuntimeError("the interface is not started: call start(diagram)")
        return self._simulator

    @property
    def kinematic(self) -> bool:
        """True when the station only plays motions back (no physics; objects follow the hand)."""
        return self._follower is not None

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self.simulator.get_context().get_time()

    def add_monitor(self, callback: Callable[[MotionPlanningInterface], None]) -> None:
        """Calls ``callback(interface)`` after every ``poll_period`` of simulated time."""
        self._monitors.append(callback)

    # -------------------------------------------------------------------------- reading ----
    def _context(self, system):
        return system.GetMyMutableContextFromRoot(self.simulator.get_mutable_context())

    def read_state(self) -> np.ndarray:
        """Reads the Panda's 18 measured values (9 positions, 9 velocities), updates
        ``state`` and returns them."""
        x = self._station.GetOutputPort("panda.state").Eval(self._context(self._station))
        self.state.set_q(x[:NUM_POSITIONS])
        return np.array(x)

    def object_pose(self):
        """X_WO of the simulated object (the station's ``object.pose``), or None."""
        if not self._station.HasOutputPort("object.pose"):
            return None
        X_WO = self._station.GetOutputPort("object.pose").Eval(self._context(self._station))
        return RigidTransform(X_WO)  # a copy: Eval returns the port's cached value

    # ------------------------------------------------------------------------ advancing ----
    def advance(self, duration: float) -> None:
        """Advances the simulation by ``duration`` s of simulated time."""
        end = self.time + duration
        self.advance_until(lambda: self.time >= end - 1e-12, duration)

    def advance_until(self, condition: Callable[[], bool], timeout: float | None = None) -> None:
        """Advances in steps of ``poll_period`` until ``condition()`` or ``timeout`` s pass."""
        end = None if timeout is None else self.time + timeout
        while not condition():
            if end is not None and self.time >= end - 1e-12:
                return
            step_end = self.time + self.options.poll_period
            if end is not None:
                step_end = min(step_end, end)
            self.simulator.AdvanceTo(step_end)
            self._after_step()

    def _after_step(self) -> None:
        x = self.read_state()
        if self._arm is not None and not self._arm.done():
            self._check_arm(x)
        if self._gripper is not None and not self._gripper.done():
            self._check_gripper(x)
        for monitor in self._monitors:
            monitor(self)

    # ------------------------------------------------------------------------- planning ----
    def plan_async(self, request: Callable, *args, **kwargs) -> PlanHandle:
        """Runs a planner request in a worker thread, from the current state unless
        ``q_start`` is given, e.g. ``plan_async(mpi.planner.plan_to_pose, X_WG)``.

        Do not change the scene while it runs."""
        kwargs.setdefault("q_start", self.state.q)
        if self._executor is None:
            self._executor = concurrent.futures.ThreadPoolExecutor(1, "motion_planning")
        timeout = kwargs.get("timeout") or self.planner.options.timeout
        return submit(self._executor, request, timeout, *args, **kwargs)

    # ------------------------------------------------------------------------ execution ----
    def execute_async(self, plan) -> ActionHandle:
        """Re-checks a plan against the current scene and starts it.

        Args:
            plan: a ``Plan`` or a successful ``PlanResult``.

        Raises:
            PlanningError: INVALID_MOTION_PLAN (unsuccessful, or colliding in the scene now),
                INVALID_START (the plan starts away from the robot, or the arm is busy).
        """
        plan = self._as_plan(plan)
        if self._arm is not None and not self._arm.done():
            raise PlanningError(
                ErrorCode.INVALID_START, "the arm is still executing a plan: wait or cancel it"
            )
        self.read_state()
        gap = float(np.max(np.abs(plan.waypoints[0] - self.state.q)))
        if gap > self.options.start_tolerance:
            raise PlanningError(
                ErrorCode.INVALID_START,
                f"the plan starts {gap:.3f} rad from the robot's current joints",
            )
        plan.validate(self.scene, self.planner.options.validation.resolution)
        t = self.time
        command = ArmCommand(q_hold=plan.waypoints[-1].copy(), plan=plan, t0=t)
        self._commander.set_arm(self._context(self._commander), command)
        self._arm = ActionHandle(self, "execute", t, t + plan.duration, plan=plan)
        return self._arm

    def execute(self, plan) -> ExecutionResult:
        """``execute_async(plan).result()``: runs the plan and waits for the arm to settle."""
        return self.execute_async(plan).result()

    def move_to_joints(self, q_goal, **kwargs) -> ExecutionResult:
        """Plans from the current state to ``q_goal`` and executes (PlanningError if no plan)."""
        return self.execute(self.planner.plan_to_joints(q_goal, q_start=self.state.q, **kwargs))

    def move_to_named(self, name: str, **kwargs) -> ExecutionResult:
        return self.execute(self.planner.plan_to_named(name, q_start=self.state.q, **kwargs))

    def move_to_pose(self, X_WE=None, **kwargs) -> ExecutionResult:
        """Plans to a pose (or ``p_WE=`` / ``R_WE=`` alone) and executes."""
        return self.execute(self.planner.plan_to_pose(X_WE, q_start=self.state.q, **kwargs))

    def move_cartesian(self, X_WE, **kwargs) -> ExecutionResult:
        """Plans a straight line to X_WE and executes it; a partial line is not executed.

        Raises:
            PlanningError: PLANNING_FAILED naming the fraction achieved.
        """
        result = self.planner.plan_cartesian(X_WE, q_start=self.state.q, **kwargs)
        return self.execute(result)

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

    def _check_arm(self, x: np.ndarray) -> None:
        opts, handle = self.options, self._arm
        command = self._commander.arm(self._context(self._commander))
        t, end = self.time, command.end_time()
        if t < end + opts.settle_time:
            return
        q, v = self.state.q, x[ARM_V]
        if np.max(np.abs(v)) > opts.settle_velocity and t < end + opts.settle_timeout:
            return
        finger = float(np.mean(x[FINGER_Q]))
        if command.stop_at is not None:
            result = ExecutionResult(
                False, ErrorCode.PREEMPTED, "cancelled", q, finger, handle.start_time, t
            )
            handle._finish(result, cancelled=True)
            return
        error = float(np.max(np.abs(q - command.plan.waypoints[-1])))
        ok = error <= opts.goal_tolerance
        message = f"reached the goal (largest joint error {error:.4f} rad)"
        if not ok:
            message = f"the arm ended {error:.4f} rad from the plan's end"
        code = None if ok else ErrorCode.CONTROL_FAILED
        handle._finish(ExecutionResult(ok, code, message, q, finger, handle.start_time, t))

    # -------------------------------------------------------------------------- gripper ----
    def move_gripper_async(self, position: float) -> ActionHandle:
        """Moves each finger to ``position`` (m, 0 closed .. 0.04 open) at ``finger_speed``.

        Closing on an object stops there (physics: the fingers squeeze it with their force
        limit; kinematic: they stop at its faces and the object follows the hand until the
        gripper opens again).
        """
        if not FINGER_CLOSED <= position <= FINGER_OPEN:
            raise PlanningError(
                ErrorCode.INVALID_GOAL,
                f"finger position {position} m is outside [{FINGER_CLOSED}, {FINGER_OPEN}]",
            )
        if self._gripper is not None and not self._gripper.done():
            self._gripper.cancel()
        context = self._context(self._commander)
        t = self.time
        start = float(self._commander.gripper(context).sample(t))
        target = position
        if self._follower is not None:
            follower_context = self._context(self._follower)
            if position > start:
                self._follower.release(follower_context)
            else:
                target = max(target, self._kinematic_contact(follower_context, start))
        command = GripperCommand(start, target, t, self.options.finger_speed)
        self._commander.set_gripper(context, command)
        self._gripper = ActionHandle(self, "gripper", t, command.end_time(), target=position)
        return self._gripper

    def move_gripper(self, position: float) -> ExecutionResult:
        return self.move_gripper_async(position).result()

    def open_gripper(self) -> ExecutionResult:
        return self.move_gripper(FINGER_OPEN)

    def close_gripper(self) -> ExecutionResult:
        return self.move_gripper(0.0)

    def _kinematic_contact(self, follower_context, opening: float) -> float:
        """Kinematic mode: the finger position at which closing meets the object (0 if the
        object is not between the fingers)."""
        obj = self.scene.world_objects.get("object") or self.scene.attached_objects.get("object")
        if obj is None:
            return 0.0
        X_WT = self.state.fk()  # the TCP, between the fingertips; y is the closing axis
        X_TO = X_WT.inverse() @ self._follower.pose(follower_context)
        half = 0.5 * np.abs(X_TO.rotation().matrix()) @ np.asarray(obj.size, dtype=float)
        p = X_TO.translation()
        # Between the fingers: within the pads' reach along x and z, inside the opening along y.
        outside = abs(p[0]) > half[0] + 0.01 or abs(p[2]) > half[2] + 0.02
        if outside or abs(p[1]) + half[1] > opening:
            return 0.0
        return float(half[1] + abs(p[1]))

    def _check_gripper(self, x: np.ndarray) -> None:
        opts, handle = self.options, self._gripper
        command = self._commander.gripper(self._context(self._commander))
        t, end = self.time, command.end_time()
        if t < end + opts.settle_time:
            return
        moving = np.max(np.abs(x[FINGER_V])) > opts.finger_settle_velocity
        if moving and t < end + opts.finger_settle_timeout:
            return
        finger = float(np.mean(x[FINGER_Q]))
        if handle.cancel_requested:
            result = ExecutionResult(
                False, ErrorCode.PREEMPTED, "cancelled", self.state.q, finger, handle.start_time, t
            )
            handle._finish(result, cancelled=True)
            return
        requested = handle.target
        closing = command.target < command.start or requested < command.start
        grasped = closing and finger > requested + opts.finger_tolerance
        if grasped and self._follower is not None:
            self._follower.grab(self._context(self._follower))
        ok = grasped or abs(finger - requested) <= opts.finger_tolerance
        what = "holding an object" if grasped else "reached"
        message = f"fingers at {finger * 1000:.1f} mm each ({what})"
        code = None if ok else ErrorCode.CONTROL_FAILED
        result = ExecutionResult(
            ok, code, message, self.state.q, finger, handle.start_time, t, grasped
        )
        handle._finish(result)

    # --------------------------------------------------------------------------- cancel ----
    def _cancel(self, handle: ActionHandle) -> None:
        t = self.time
        if handle is self._arm:
            context = self._context(self._commander)
            command = self._commander.arm(context)
            accel = np.asarray(self.planner.options.timing.max_acceleration)
            self._commander.set_arm(context, command.stopped(t, accel))
        elif handle is self._gripper:
            context = self._context(self._commander)
            finger = float(self._commander.gripper(context).sample(t))
            self._commander.set_gripper(context, GripperCommand(finger, finger, t))
