"""Planning errors with MoveIt-style codes."""

from __future__ import annotations

import enum


class ErrorCode(enum.Enum):
    """Why a planning request failed, in the spirit of ``moveit_msgs/MoveItErrorCodes``."""

    PLANNING_FAILED = "planning_failed"
    INVALID_MOTION_PLAN = "invalid_motion_plan"
    TIMED_OUT = "timed_out"
    START_IN_COLLISION = "start_in_collision"
    GOAL_IN_COLLISION = "goal_in_collision"
    INVALID_GOAL = "invalid_goal"
    INVALID_START = "invalid_start"
    NO_IK_SOLUTION = "no_ik_solution"
    INVALID_OBJECT_NAME = "invalid_object_name"
    INVALID_SCENE = "invalid_scene"
    FRAME_NOT_FOUND = "frame_not_found"
    CONTROL_FAILED = "control_failed"
    PREEMPTED = "preempted"


class PlanningError(RuntimeError):
    """A planning request that cannot be met.

    Attributes:
        code: the ``ErrorCode``.
        message: what went wrong, naming the colliding bodies where there are some.
    """

    def __init__(self, code: ErrorCode, message: str):
        super().__init__(f"{code.name}: {message}")
        self.code = code
        self.message = message

    def __reduce__(self):
        """Pickles as (code, message), so the error crosses process boundaries (sweeps)."""
        return (type(self), (self.code, self.message))
