"""The station side of ``MotionPlanningInterface``: it joins an arm station diagram, runs it
in simulated time, and judges, stops, times out and closes the arm and gripper actions.

Running actions are checked, and monitors called, at every multiple of ``poll_period`` of
simulated time, however ``advance`` calls split it, so an action ends at the same simulated time
whatever the polling. Every wait is bounded: one call advances at most ``MAX_WAIT`` s, and an
action not judged by its ``ActionHandle.deadline`` is stopped and fails with TIMED_OUT.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from pydrake.math import RigidTransform
from pydrake.systems.analysis import Simulator

from planning.errors import ErrorCode
from planning.execution.commander import ArmCommander, GripperCommand, ObjectFollower
from planning.execution.handles import (
    MAX_WAIT,
    TIME_TOL,
    ActionHandle,
    ExecutionResult,
    check_duration,
)
from planning.execution.options import InterfaceOptions
from planning.model.arm_layout import ArmLayout


class StationLink:
    """Joins an arm station and runs it; ``MotionPlanningInterface`` adds the planning.

    The station's ports are named after the scene's robot and carry its group's joints then its
    fingers (``layout``, ``planning.model.arm_layout``): ``panda.position_command`` and
    ``panda.state`` for the Panda.

    Subclasses set ``planner`` (its timing limits brake a cancelled arm). Closed (``close``, or
    leaving a ``with`` block), every call raises ``RuntimeError("the interface is closed")``: a
    mistake in the calling code, so not a ``PlanningError`` that planning code would catch.

    Args:
        scene: the ``PlanningScene`` (its robot, fingers and ``object``).
        state: the ``RobotState`` kept at the measured joints.
        options: execution settings.

    Raises:
        ValueError: an option's time (settle_time, settle_timeout, finger_settle_timeout) is
            not a number of seconds in [0, MAX_WAIT], or poll_period not one in (0, MAX_WAIT].
    """

    def __init__(self, scene, state, options: InterfaceOptions):
        self.scene, self.state, self.options = scene, state, options
        self.layout = ArmLayout.of(scene.model.robot)
        model = scene.model
        self._rows = self.layout.plant_indices(model.plant, model.instance)
        self._commander: ArmCommander | None = None
        self._follower: ObjectFollower | None = None
        self._station = None
        self._simulator: Simulator | None = None
        self._arm: ActionHandle | None = None
        self._gripper: ActionHandle | None = None
        self._monitors: list[Callable] = []
        self._closed = False
        for name in ("poll_period", "settle_time", "settle_timeout", "finger_settle_timeout"):
            value = getattr(options, name)
            check_duration(f"options.{name}", value, positive=name == "poll_period")

    # ------------------------------------------------------------------ joining a diagram ----
    def add_to_builder(self, builder, station) -> None:
        """Adds the command source (and, for a kinematic station, the object follower) to a
        user's ``DiagramBuilder`` and connects them to ``station``'s ports.

        Args:
            builder: the builder that holds ``station``.
            station: a system with ``<robot>.position_command`` (input) and ``<robot>.state``
                (output), ``<robot>`` the robot's name (``layout.robot``); optionally
                ``object.position_command`` (kinematic) and ``object.pose``.
        """
        self._check_open()
        self._station = station
        layout = self.layout
        finger = self.scene.finger_positions
        commander = builder.AddSystem(
            ArmCommander(
                q_arm=self.state.q,
                finger=float(finger[0]) if finger.size else layout.finger_open,
                num_fingers=layout.num_fingers,
            )
        )
        commander.set_name("arm_commander")
        command = station.GetInputPort(layout.port("position_command"))
        builder.Connect(commander.get_output_port(), command)
        self._commander = commander
        if station.HasInputPort("object.position_command") and "object" in self.scene.world_objects:
            model = self.scene.model
            follower = builder.AddSystem(
                ObjectFollower(
                    plant=model.plant,
                    body=model.plant.GetBodyByName(model.attachment_body, model.instance),
                    X_WO=self.scene.object_pose("object"),
                    indices=self._rows,
                    q_rest=self.state.q_full,
                )
            )
            follower.set_name("object_follower")
            state = station.GetOutputPort(layout.port("state"))
            builder.Connect(state, follower.get_input_port())
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
        self._check_open()
        if self._commander is None:
            raise RuntimeError("call add_to_builder() before start()")
        self._simulator = Simulator(diagram)
        self._simulator.set_target_realtime_rate(realtime_rate)
        self._simulator.Initialize()
        self.read_state()
        return self._simulator

    @property
    def simulator(self) -> Simulator:
        self._check_open()
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

    def add_monitor(self, callback: Callable) -> None:
        """Calls ``callback(interface)`` after every ``poll_period`` of simulated time."""
        self._check_open()
        self._monitors.append(callback)

    # ------------------------------------------------------------------------- closing ----
    def close(self) -> None:
        """Cancels the running arm and gripper actions (their results: PREEMPTED, "cancelled:
        the interface was closed"); from then on calls raise. Closing again does nothing."""
        if self._closed:
            return
        try:
            for handle in (self._arm, self._gripper):
                if handle is not None and not handle.done():
                    reason = "cancelled: the interface was closed"
                    self._end(handle, ErrorCode.PREEMPTED, reason, cancelled=True)
                    self._cancel(handle)
        finally:
            self._closed = True

    def __enter__(self):
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def _check_open(self) -> None:
        if self._closed:
            raise RuntimeError("the interface is closed")

    # -------------------------------------------------------------------------- reading ----
    def _context(self, system):
        return system.GetMyMutableContextFromRoot(self.simulator.get_mutable_context())

    def read_state(self) -> np.ndarray:
        """Reads the station's measured state (``layout``: the group's joints and the fingers,
        then their velocities; the Panda's 18 values), updates ``state`` and returns it."""
        port = self._station.GetOutputPort(self.layout.port("state"))
        x = np.array(port.Eval(self._context(self._station)))
        q = self.state.q_full
        q[self._rows] = x[: self.layout.num_positions]
        self.state.set_q(q)
        return x

    def _finger(self, x: np.ndarray) -> float:
        """The gripper's measured position: the fingers' mean, or the virtual gripper's command
        (an arm without fingers)."""
        if self.layout.num_fingers:
            return float(np.mean(x[self.layout.finger_q]))
        return float(self._commander.gripper(self._context(self._commander)).sample(self.time))

    def object_pose(self):
        """X_WO of the simulated object (the station's ``object.pose``), or None."""
        self._check_open()
        if not self._station.HasOutputPort("object.pose"):
            return None
        X_WO = self._station.GetOutputPort("object.pose").Eval(self._context(self._station))
        return RigidTransform(X_WO)  # a copy: Eval returns the port's cached value

    # ------------------------------------------------------------------------ advancing ----
    def advance(self, duration: float) -> None:
        """Advances the simulation by ``duration`` s of simulated time.

        Raises:
            ValueError: ``duration`` is not a number of seconds in [0, MAX_WAIT].
        """
        self.advance_until(lambda: False, check_duration("duration", duration))

    def advance_until(self, condition: Callable[[], bool], timeout: float | None = None) -> None:
        """Advances until ``condition()`` or ``timeout`` s pass (None: ``MAX_WAIT``).

        Running actions are checked, and monitors called, at every multiple of ``poll_period``
        of simulated time, however the calls split it: an action ends at the same simulated
        time whatever the polling.

        Raises:
            ValueError: ``timeout`` is not a number of seconds in [0, MAX_WAIT], or
                ``options.poll_period`` not one in (0, MAX_WAIT].
        """
        timeout = check_duration("timeout", MAX_WAIT if timeout is None else timeout)
        period = check_duration("options.poll_period", self.options.poll_period, positive=True)
        end = self.time + timeout
        while not condition():
            t = self.time
            if t >= end - TIME_TOL:
                return
            poll = (math.floor((t + TIME_TOL) / period) + 1) * period  # the next multiple
            if end < poll - TIME_TOL:
                self.simulator.AdvanceTo(end)  # stops between two polls: nothing to check
                continue
            self.simulator.AdvanceTo(poll)
            self._after_step()

    def _after_step(self) -> None:
        x = self.read_state()
        if self._arm is not None and not self._arm.done():
            self._check_arm(x)
        if self._gripper is not None and not self._gripper.done():
            self._check_gripper(x)
        for handle in (self._arm, self._gripper):
            if handle is not None:
                handle._expire_if_overdue()
        for monitor in self._monitors:
            monitor(self)

    # ------------------------------------------------------------------------- judging ----
    def _check_arm(self, x: np.ndarray) -> None:
        opts, handle = self.options, self._arm
        command = self._commander.arm(self._context(self._commander))
        speed = float(np.max(np.abs(x[self.layout.arm_v])))
        if not self._settled(command.end_time(), speed, opts.settle_velocity, opts.settle_timeout):
            return
        if command.stop_at is not None:
            self._end(handle, ErrorCode.PREEMPTED, "cancelled", cancelled=True)
            return
        error = float(np.max(np.abs(self.state.q - command.plan.waypoints[-1])))
        if error <= opts.goal_tolerance:
            self._end(handle, None, f"reached the goal (largest joint error {error:.4f} rad)")
        else:
            message = f"the arm ended {error:.4f} rad from the plan's end"
            self._end(handle, ErrorCode.CONTROL_FAILED, message)

    def _settled(self, end: float, speed: float, at_rest: float, timeout: float) -> bool:
        """True when a motion commanded to end at ``end`` (simulated time, s) is over:
        ``settle_time`` after it and at rest (``speed`` <= ``at_rest``), or ``timeout`` s
        after it."""
        t = self.time
        return t >= end + self.options.settle_time and (speed <= at_rest or t >= end + timeout)

    def _end(self, handle: ActionHandle, code, message: str, *, cancelled=False, grasped=False):
        """Finishes ``handle`` now at the measured joints and fingers: a success when ``code``
        is None, status CANCELLED when ``cancelled``."""
        finger = self._finger(self.read_state())
        t = self.time
        result = ExecutionResult(
            code is None, code, message, self.state.q, finger, handle.start_time, t, grasped
        )
        handle._finish(result, cancelled=cancelled)

    def _check_gripper(self, x: np.ndarray) -> None:
        opts, handle = self.options, self._gripper
        command = self._commander.gripper(self._context(self._commander))
        speed = float(np.max(np.abs(x[self.layout.finger_v]), initial=0.0))
        at_rest = opts.finger_settle_velocity
        if not self._settled(command.end_time(), speed, at_rest, opts.finger_settle_timeout):
            return
        if handle.cancel_requested:
            self._end(handle, ErrorCode.PREEMPTED, "cancelled", cancelled=True)
            return
        finger, requested = self._finger(x), handle.target
        closing = command.target < command.start or requested < command.start
        grasped = closing and finger > requested + opts.finger_tolerance
        if grasped and self._follower is not None:
            self._follower.grab(self._context(self._follower))
        ok = grasped or abs(finger - requested) <= opts.finger_tolerance
        what = "holding an object" if grasped else "reached"
        if self.layout.num_fingers:
            message = f"fingers at {finger * 1000:.1f} mm each ({what})"
        else:
            message = f"virtual gripper at {finger:.2f} ({what})"
        self._end(handle, None if ok else ErrorCode.CONTROL_FAILED, message, grasped=grasped)

    # --------------------------------------------------------------------------- cancel ----
    def _cancel(self, handle: ActionHandle) -> None:
        """Brings the action's motion to rest: the fingers at once where they are, the arm
        along its plan (which moves the handle's deadline later)."""
        t, context = self.time, self._context(self._commander)
        if handle is self._arm:
            accel = np.asarray(self.planner.options.timing.max_acceleration)
            command = self._commander.arm(context).stopped(t, accel)
            self._commander.set_arm(context, command)
            handle._extend(command.end_time())
        elif handle is self._gripper:
            finger = float(self._commander.gripper(context).sample(t))
            self._commander.set_gripper(context, GripperCommand(finger, finger, t))

    def _grace(self, kind: str) -> float:
        """How long after an action's commanded end it is judged at the latest, s: its settle
        timeout and two polls (``ActionHandle.deadline``)."""
        opts = self.options
        timeout = opts.settle_timeout if kind == "execute" else opts.finger_settle_timeout
        return max(opts.settle_time, timeout) + 2.0 * opts.poll_period

    def _expire(self, handle: ActionHandle) -> None:
        """Stops an action not judged by its deadline and fails it (TIMED_OUT)."""
        message = f"no outcome by its deadline ({handle.deadline:.3f} s): stopped"
        self._end(handle, ErrorCode.TIMED_OUT, message)
        self._cancel(handle)
