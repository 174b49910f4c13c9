"""The joint positions of a planning scene: the group's, which plans move, and the others'.

``PlanningScene`` inherits ``ScenePositions``: a configuration ``q`` of the scene is the planning
group's joints (``num_joints`` values, in the group's order) with every other joint where the
scene holds it (``other_positions``: a gripper's fingers, a head, a second arm outside the
group), or all of the plant's positions. The subclass sets ``self._model`` (a
``planning.model.planning_model.PlanningModel``) and ``self._other_positions`` (its
``default_other`` at first) and keeps ``self.version``, bumped when the other joints move.
"""

from __future__ import annotations

import numpy as np


class ScenePositions:
    """The group's size and limits, and the positions of the joints outside it."""

    @property
    def num_joints(self) -> int:
        """The size of a planning configuration: the group's joints."""
        return self._model.num_joints

    @property
    def lower(self) -> np.ndarray:
        """The group's lower position limits (the robot model's: URDF, soft limits, MoveIt's
        joint_limits.yaml; -pi for a continuous joint)."""
        return self._model.robot.lower.copy()

    @property
    def upper(self) -> np.ndarray:
        """The group's upper position limits (pi for a continuous joint)."""
        return self._model.robot.upper.copy()

    @property
    def other_positions(self) -> np.ndarray:
        """The positions of the joints outside the group (``model.other_indices``), rad or m:
        where they stay while the group moves."""
        return self._other_positions.copy()

    @other_positions.setter
    def other_positions(self, value) -> None:
        shape = self._other_positions.shape
        value = np.broadcast_to(np.asarray(value, dtype=float), shape).copy()
        if not np.all(np.isfinite(value)):
            raise ValueError(f"joint positions must be finite, got {value}")
        self._other_positions = value
        self.version += 1

    @property
    def finger_positions(self) -> np.ndarray:
        """Each finger's position (the joints below the attach link; the Panda's: m, 0 closed,
        0.04 open)."""
        return self._other_positions[self._model.finger_mask].copy()

    @finger_positions.setter
    def finger_positions(self, value) -> None:
        mask = self._model.finger_mask
        value = np.broadcast_to(np.asarray(value, dtype=float), (int(mask.sum()),))
        others = self._other_positions.copy()
        others[mask] = value
        self.other_positions = others

    def set_positions(self, positions: dict[str, float]) -> None:
        """Sets joints outside the group by name (a MoveIt robot state's joint_state); names the
        robot does not have and the group's own joints are left out.

        Raises:
            ValueError: a value is not finite.
        """
        self.other_positions = self._model.others_by_name(positions, self._other_positions)

    def full_q(self, q) -> np.ndarray:
        """Returns the plant's positions for a group q (the other joints added) or for all of
        the plant's positions.

        Raises:
            ValueError: q has the wrong size or is not finite.
        """
        return self._model.full_q(q, self._other_positions)

    def arm_q(self, q) -> np.ndarray:
        """Returns the group's joints of a group or full q."""
        return self.full_q(q)[self._model.group_indices]
