"""What a station commands and measures of a robot: its group's joints, then its fingers.

A station's ``<robot>.position_command`` and ``<robot>.state`` (``diagrams.arm_station``) carry
the planning group's joints, in the group's order, then the finger joints (the moving joints
below the SRDF's attach link, in the URDF's order): the Panda's 7 arm joints and 2 fingers, the
UR5's 6 joints and none (its Robotiq fingers are fixed). Every other moving joint (a head, a
second arm outside the group) stays at the description's default position.

The fingers move together: one gripper position is sent to each of them, within the range every
finger can reach (``finger_closed`` .. ``finger_open``, the largest lower and the smallest upper
limit), as a parallel gripper's fingers do. An arm without finger joints (the UR5 of VAMP's set,
whose Robotiq fingers are fixed) has a virtual gripper instead: positions 0 (closed) to 1 (open)
that no joint carries; closing it on an object holds the object at the tool (kinematic stations).
``ArmLayout.of`` reads the files only (no plant).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_sim.base.errors import ConfigError
from planning.model.robot_model import RobotModel


@dataclass(frozen=True)
class ArmLayout:
    """The positions a station carries, by joint name.

    Attributes:
        robot: the robot's model instance name (the URDF's robot name): the ports' prefix.
        group: the group's joints, in the group's order.
        fingers: the finger joints, in the URDF's order.
        others: every other moving joint.
        other_positions: the others' positions (the description's defaults), rad or m.
        finger_closed, finger_open: the gripper's range, m or rad (0 and 1, the virtual
            gripper's, without fingers).
    """

    robot: str
    group: tuple[str, ...]
    fingers: tuple[str, ...]
    others: tuple[str, ...]
    other_positions: tuple[float, ...]
    finger_closed: float
    finger_open: float

    @classmethod
    def of(cls, robot: RobotModel) -> ArmLayout:
        """The layout of a loaded robot model.

        Raises:
            ConfigError: a finger joint without both limits, or fingers with no common range.
        """
        below, stack = set(), [robot.attach_link]
        while stack:
            for joint in robot.tree.child_joints(stack.pop()):
                below.add(joint.child)
                stack.append(joint.child)
        moving = [j for j in robot.tree.joints.values() if j.name in robot.default_positions]
        fingers = [j for j in moving if j.child in below]
        others = [j for j in moving if j.child not in below]
        closed, open_ = 0.0, 1.0  # the virtual gripper's
        if fingers:
            for joint in fingers:
                if joint.lower is None or joint.upper is None:
                    raise ConfigError(f"{robot.name}: finger joint {joint.name} has no limits")
            closed = max(j.lower for j in fingers)
            open_ = min(j.upper for j in fingers)
            if closed > open_:
                names = ", ".join(j.name for j in fingers)
                raise ConfigError(f"{robot.name}: the fingers {names} have no common range")
        return cls(
            robot=robot.name,
            group=tuple(robot.joint_names),
            fingers=tuple(j.name for j in fingers),
            others=tuple(j.name for j in others),
            other_positions=tuple(float(robot.default_positions[j.name]) for j in others),
            finger_closed=float(closed),
            finger_open=float(open_),
        )

    @property
    def num_joints(self) -> int:
        """The group's joints."""
        return len(self.group)

    @property
    def num_fingers(self) -> int:
        return len(self.fingers)

    @property
    def num_positions(self) -> int:
        """Entries of a station's position command: the group's joints, then the fingers."""
        return len(self.group) + len(self.fingers)

    @property
    def num_states(self) -> int:
        """Entries of a station's state: positions, then velocities."""
        return 2 * self.num_positions

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The joints of a station's positions, in order."""
        return self.group + self.fingers

    @property
    def arm_q(self) -> slice:
        """The group's positions in a station's positions (or state)."""
        return slice(0, self.num_joints)

    @property
    def finger_q(self) -> slice:
        return slice(self.num_joints, self.num_positions)

    @property
    def arm_v(self) -> slice:
        """The group's velocities in a station's state."""
        return slice(self.num_positions, self.num_positions + self.num_joints)

    @property
    def finger_v(self) -> slice:
        return slice(self.num_positions + self.num_joints, self.num_states)

    def port(self, signal: str) -> str:
        """A station port's name: ``<robot>.<signal>`` (``panda.position_command``)."""
        return f"{self.robot}.{signal}"

    def positions(self, q_group, finger: float) -> np.ndarray:
        """A station's positions: the group's q, then ``finger`` for each finger."""
        q_group = np.asarray(q_group, dtype=float).reshape(-1)
        if q_group.size != self.num_joints:
            raise ConfigError(
                f"{self.robot}: {q_group.size} joint values for a group of {self.num_joints}"
            )
        return np.concatenate([q_group, np.full(self.num_fingers, float(finger))])

    def plant_indices(self, plant, instance, names=None) -> np.ndarray:
        """Where the joints ``names`` (default ``joint_names``) sit in ``plant``'s positions."""
        names = self.joint_names if names is None else names
        return np.array(
            [plant.GetJointByName(n, instance).position_start() for n in names], dtype=int
        )
