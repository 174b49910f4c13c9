"""Handles of long actions (planning, arm execution, gripper moves), MoveIt-action style:
``done()``, ``result()``, ``cancel()``, ``progress`` and ``status``.

Arm and gripper actions live in simulated time: the ``MotionPlanningInterface`` checks them
after every step it advances, so they finish at the same simulated time however often the user
polls. Planning runs in a worker thread in wall time.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses as dc
import time
from collections.abc import Callable

import numpy as np

from planning.errors import ErrorCode, PlanningError

PENDING, RUNNING, SUCCEEDED, FAILED, CANCELLED = (
    "pending",
    "running",
    "succeeded",
    "failed",
    "cancelled",
)


@dc.dataclass
class ExecutionResult:
    """The outcome of an arm execution or a gripper move.

    Attributes:
        success: the motion ended where it was commanded (arm: every joint within the
            tolerance of the plan's end; gripper: the fingers reached the target or stopped on
            an object).
        code: None on success, else CONTROL_FAILED or PREEMPTED (cancelled).
        message: what happened.
        q: the 7 arm joints at the end, rad (gripper moves: unchanged arm).
        finger_position: each finger's position at the end, m.
        start_time: simulated time the action started, s.
        end_time: simulated time it finished, s.
        grasped: for a closing gripper, True when the fingers stopped on something.
    """

    success: bool
    code: ErrorCode | None
    message: str
    q: np.ndarray
    finger_position: float
    start_time: float
    end_time: float
    grasped: bool = False


class ActionHandle:
    """A running arm execution or gripper move.

    Created by ``MotionPlanningInterface.execute_async`` / ``move_gripper_async``; the interface
    calls ``_finish`` when the action is over.
    """

    def __init__(
        self,
        interface,
        kind: str,
        start_time: float,
        end_time: float,
        *,
        plan=None,
        target: float | None = None,
    ):
        self._interface = interface
        self.kind = kind  # "execute" or "gripper"
        self.start_time = start_time
        self.plan = plan  # the Plan being executed ("execute")
        self.target = target  # the requested finger position, m ("gripper")
        self.cancel_requested = False
        self._planned_end = end_time
        self._status = RUNNING
        self._result: ExecutionResult | None = None

    @property
    def status(self) -> str:
        return self._status

    def done(self) -> bool:
        """True once the action has finished (succeeded, failed or cancelled). Does not
        advance the simulation."""
        return self._result is not None

    @property
    def progress(self) -> float:
        """Share of the commanded motion's time that has passed, 0..1."""
        if self._result is not None:
            return 1.0
        span = self._planned_end - self.start_time
        if span <= 0.0:
            return 1.0
        return float(np.clip((self._interface.time - self.start_time) / span, 0.0, 1.0))

    def result(self, timeout: float | None = None) -> ExecutionResult:
        """Advances the simulation until the action is over and returns its result.

        Args:
            timeout: most simulated time to wait, s; None waits as long as the action lasts.

        Raises:
            TimeoutError: the action is still running after ``timeout`` simulated seconds.
        """
        if self._result is None:
            self._interface.advance_until(lambda: self._result is not None, timeout)
        if self._result is None:
            raise TimeoutError(f"the {self.kind} action is still running after {timeout} s")
        return self._result

    def cancel(self) -> None:
        """Stops the action: the arm comes to rest along its plan, the fingers where they are.
        The result then has code PREEMPTED."""
        if self._result is None:
            self.cancel_requested = True
            self._interface._cancel(self)

    def _finish(self, result: ExecutionResult, cancelled: bool = False) -> None:
        self._result = result
        self._status = CANCELLED if cancelled else SUCCEEDED if result.success else FAILED


class PlanHandle:
    """A planning request running in a worker thread (wall time; the simulation does not
    advance while it runs unless the caller advances it).

    ``result()`` returns the planner's ``PlanResult`` or raises its ``PlanningError``;
    after ``cancel()`` it raises ``PlanningError`` with code PREEMPTED.
    """

    def __init__(self, future: concurrent.futures.Future, timeout: float):
        self._future = future
        self._started = time.perf_counter()
        self._timeout = timeout
        self._cancelled = False

    @property
    def status(self) -> str:
        if self._cancelled:
            return CANCELLED
        if not self._future.done():
            return RUNNING if self._future.running() else PENDING
        return FAILED if self._future.exception() is not None else SUCCEEDED

    def done(self) -> bool:
        return self._cancelled or self._future.done()

    @property
    def progress(self) -> float:
        """Share of the planning timeout used so far (1 when done), 0..1."""
        if self.done():
            return 1.0
        return min(1.0, (time.perf_counter() - self._started) / self._timeout)

    def result(self, timeout: float | None = None):
        """Waits (wall time, s) for the plan.

        Raises:
            PlanningError: the planner's error, or PREEMPTED when cancelled.
            TimeoutError: not done within ``timeout``.
        """
        if self._cancelled:
            raise PlanningError(ErrorCode.PREEMPTED, "the planning request was cancelled")
        try:
            return self._future.result(timeout)
        except concurrent.futures.TimeoutError as e:
            raise TimeoutError(f"planning still running after {timeout} s") from e

    def cancel(self) -> None:
        """Drops the request: a queued one never runs; a running one's result is discarded."""
        self._cancelled = True
        self._future.cancel()


def submit(executor: concurrent.futures.Executor, fn: Callable, timeout: float, *args, **kwargs):
    """Runs ``fn(*args, **kwargs)`` on the executor and returns its ``PlanHandle``."""
    return PlanHandle(executor.submit(fn, *args, **kwargs), timeout)
