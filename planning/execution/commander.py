"""The systems a ``MotionPlanningInterface`` adds to a diagram: the command source of the arm
and its fingers and, in kinematic mode, the held object's pose.

Both keep what they are doing in abstract Drake state. The interface changes that state between
``Simulator.AdvanceTo`` calls (a new plan, a gripper move, a stop), like a ROS action server
receiving a goal; their outputs are functions of the state and the time only.
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np
from pydrake.common.value import Value
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem

from planning.scene_objects import free_body_positions


@dc.dataclass(frozen=True)
class ArmCommand:
    """What the arm follows: a plan started at ``t0``, or a fixed configuration.

    A stop (``cancel``) leaves the plan's path at the cancel time and slows down along it: the
    path parameter's rate falls linearly from 1 to 0 over ``stop_duration``, so the arm never
    leaves the collision-checked path and comes to rest on it.

    Attributes:
        q_hold: the group's joints held when there is no plan, rad or m.
        plan: a ``Plan`` (its ``sample(t)`` gives the group's joints) or None.
        t0: simulated time at which the plan starts, s.
        stop_at: simulated time a stop began, s, or None.
        stop_duration: s, time to come to rest from ``stop_at``.
    """

    q_hold: np.ndarray
    plan: object | None = None
    t0: float = 0.0
    stop_at: float | None = None
    stop_duration: float = 0.0

    def plan_time(self, t: float) -> float:
        """The time along the plan at simulated time t (slowed down after a stop), s."""
        tau = t - self.t0
        if self.stop_at is None or t <= self.stop_at:
            return tau
        elapsed = min(max(t - self.stop_at, 0.0), self.stop_duration)
        t_c = self.stop_at - self.t0
        if self.stop_duration <= 0.0:
            return t_c
        return t_c + elapsed - elapsed * elapsed / (2.0 * self.stop_duration)

    def end_time(self) -> float:
        """Simulated time at which the command comes to rest, s."""
        if self.plan is None:
            return self.t0
        if self.stop_at is not None:
            return self.stop_at + self.stop_duration
        return self.t0 + self.plan.duration

    def sample(self, t: float) -> np.ndarray:
        """The group's commanded joints at simulated time t, rad or m."""
        if self.plan is None:
            return self.q_hold
        return self.plan.sample(self.plan_time(t))[0]

    def stopped(self, t: float, max_acceleration: np.ndarray) -> ArmCommand:
        """Returns the command that brings the arm to rest along the plan from time t (past the
        plan's end, one that marks it stopped at t: it already rests there)."""
        if self.plan is None:
            return self
        if t >= self.end_time():
            return self if self.stop_at is not None else dc.replace(self, stop_at=t)
        _, v, _ = self.plan.sample(self.plan_time(t))
        # Slowing the path rate linearly over T scales the velocity by (1 - s/T) and adds -v/T:
        # twice the most limited joint's braking time keeps that term under half its limit.
        duration = max(0.05, 2.0 * float(np.max(np.abs(v) / np.asarray(max_acceleration))))
        return dc.replace(self, stop_at=t, stop_duration=duration)


@dc.dataclass(frozen=True)
class GripperCommand:
    """Each finger moves from ``start`` to ``target`` at ``speed``, starting at ``t0``.

    Attributes:
        start: finger position at t0, m (the Panda's: 0 closed, 0.04 open).
        target: finger position commanded at the end, m.
        t0: simulated time the move starts, s.
        speed: m/s per finger.
    """

    start: float
    target: float
    t0: float = 0.0
    speed: float = 0.05

    def __post_init__(self):
        """Raises ValueError for a command that would never end (or not be one): a speed that
        is not finite and > 0, or positions and times that are not finite."""
        if not (np.isfinite(self.speed) and self.speed > 0.0):
            raise ValueError(f"speed must be a finite number of m/s > 0, not {self.speed!r}")
        if not np.all(np.isfinite([self.start, self.target, self.t0])):
            raise ValueError(f"start, target and t0 must be finite, not {self}")

    def end_time(self) -> float:
        return self.t0 + abs(self.target - self.start) / self.speed

    def sample(self, t: float) -> float:
        travel = min(max(t - self.t0, 0.0) * self.speed, abs(self.target - self.start))
        return self.start + np.sign(self.target - self.start) * travel


class ArmCommander(LeafSystem):
    """A station's position command: the group's joints from an ``ArmCommand``, the fingers from
    a ``GripperCommand``, both held in abstract state.

    .. pydrake_system::

        name: ArmCommander
        output_ports:
        - position_command

    ``position_command`` has the group's joints then one value per finger, each the gripper's
    position (``planning.model.arm_layout``: the Panda's 7 arm joints, rad, and 2 fingers, m).
    Without fingers the gripper command is still kept (a virtual gripper) and not sent.

    Args:
        q_arm: the group's joints to hold at first.
        finger: the gripper's position at first.
        num_fingers: the finger joints the command carries.
    """

    def __init__(self, *, q_arm: np.ndarray, finger: float, num_fingers: int):
        super().__init__()
        q_arm = np.asarray(q_arm, dtype=float).copy()
        self._n, self._fingers = q_arm.size, int(num_fingers)
        self._arm = self.DeclareAbstractState(Value[object](ArmCommand(q_hold=q_arm)))
        self._gripper = self.DeclareAbstractState(Value[object](GripperCommand(finger, finger)))
        size = self._n + self._fingers
        self.DeclareVectorOutputPort("position_command", size, self.CalcCommand)

    def CalcCommand(self, context, output) -> None:
        t = context.get_time()
        arm = context.get_abstract_state(self._arm).get_value()
        finger = context.get_abstract_state(self._gripper).get_value().sample(t)
        values = np.empty(self._n + self._fingers)
        values[: self._n] = arm.sample(t)
        values[self._n :] = finger
        output.SetFromVector(values)

    def arm(self, context) -> ArmCommand:
        return context.get_abstract_state(self._arm).get_value()

    def gripper(self, context) -> GripperCommand:
        return context.get_abstract_state(self._gripper).get_value()

    def set_arm(self, context, command: ArmCommand) -> None:
        context.get_mutable_abstract_state(self._arm).set_value(command)

    def set_gripper(self, context, command: GripperCommand) -> None:
        context.get_mutable_abstract_state(self._gripper).set_value(command)


@dc.dataclass(frozen=True)
class Grip:
    """Where the object is: held (``X_AO``, in the hand's attachment frame A) or resting
    (``X_WO``)."""

    X_WO: RigidTransform
    X_AO: RigidTransform | None = None


class ObjectFollower(LeafSystem):
    """Kinematic mode's stand-in for friction: the object's positions, resting or carried by the
    hand.

    .. pydrake_system::

        name: ObjectFollower
        input_ports:
        - robot_state
        output_ports:
        - object_positions

    ``robot_state`` is a station's state (its positions first: the group's joints, then the
    fingers); ``object_positions`` the object's 7 free-body positions [qw, qx, qy, qz, x, y, z].

    Args:
        plant: a plant holding the robot (e.g. the planning scene's), used for the hand's pose.
        body: its attachment body A.
        X_WO: the object's initial pose.
        indices: where the station's positions sit in ``plant``'s positions.
        q_rest: ``plant``'s positions for the joints the station does not carry.
    """

    def __init__(self, *, plant, body, X_WO: RigidTransform, indices, q_rest):
        super().__init__()
        self._plant, self._body = plant, body
        self._plant_context = plant.CreateDefaultContext()  # a cache for forward kinematics
        self._indices = np.asarray(indices, dtype=int)
        self._q = np.array(q_rest, dtype=float)
        self._grip = self.DeclareAbstractState(Value[object](Grip(X_WO)))
        self._state = self.DeclareVectorInputPort("robot_state", 2 * self._indices.size)
        self.DeclareVectorOutputPort("object_positions", 7, self.CalcPositions)

    def X_WA(self, x: np.ndarray) -> RigidTransform:
        """The attachment frame's pose at the station's state (or positions) x."""
        self._q[self._indices] = x[: self._indices.size]
        self._plant.SetPositions(self._plant_context, self._q)
        return self._plant.EvalBodyPoseInWorld(self._plant_context, self._body)

    def pose(self, context) -> RigidTransform:
        grip = context.get_abstract_state(self._grip).get_value()
        if grip.X_AO is None:
            return grip.X_WO
        return self.X_WA(self._state.Eval(context)) @ grip.X_AO

    def CalcPositions(self, context, output) -> None:
        output.SetFromVector(free_body_positions(self.pose(context)))

    def grab(self, context) -> None:
        """The hand carries the object from now on, keeping its current pose relative to A."""
        X_WO = self.pose(context)
        X_AO = self.X_WA(self._state.Eval(context)).inverse() @ X_WO
        context.get_mutable_abstract_state(self._grip).set_value(Grip(X_WO, X_AO))

    def release(self, context) -> None:
        """The object stays where it is now."""
        context.get_mutable_abstract_state(self._grip).set_value(Grip(self.pose(context)))
