"""Handles of long actions (planning, arm execution, gripper moves), MoveIt-action style:
``done()``, ``result()``, ``cancel()``, ``progress`` and ``status``.

Arm and gripper actions live in simulated time: the ``MotionPlanningInterface`` checks them
at every multiple of its poll period, so they finish at the same simulated time however the user
polls. Waiting is bounded: an action that the interface has not judged by its deadline (its
commanded end plus the settle timeout) is stopped and fails with TIMED_OUT. Planning runs in a
worker thread in wall time.

Durations and timeouts are checked by ``check_duration``: a value that is not a number of seconds
in [0, ``MAX_WAIT``] raises ``ValueError`` naming the argument.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses as dc
import math
import numbers
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

MAX_WAIT = 3600.0
"""The longest duration or timeout one call accepts, s (wait longer in several calls)."""

TIME_TOL = 1e-9
"""Simulated times closer than this are the same time, s."""

PLAN_GRACE = 60.0
"""How long past its planning timeout ``PlanHandle.result()`` waits for a request, s."""


def check_duration(name: str, value, *, optional: bool = False, positive: bool = False):
    """Returns ``value`` as a float after checking that it is a duration a call can wait for.

    Args:
        name: the argument's name, for the message.
        value: a number of seconds.
        optional: None is allowed (and returned).
        positive: 0 is refused too.

    Raises:
        ValueError: ``value`` is not a real number (a bool or a string is not), or is NaN,
            infinite, negative (or zero when ``positive``) or more than ``MAX_WAIT`` s.
    """
    if value is None and optional:
        return None
    number = isinstance(value, numbers.Real) and not isinstance(value, bool)
    seconds = float(value) if number else math.nan
    low_ok = seconds > 0.0 if positive else seconds >= 0.0
    if not (low_ok and seconds <= MAX_WAIT):
        bounds = f"{'(' if positive else '['}0, {MAX_WAIT:g}]"
        raise ValueError(f"{name} must be a number of seconds in {bounds}, not {value!r}")
    return seconds


@dc.dataclass
class ExecutionResult:
    """The outcome of an arm execution or a gripper move.

    Attributes:
        success: the motion ended where it was commanded (arm: every joint within the
            tolerance of the plan's end; gripper: the fingers reached the target or stopped on
            an object).
        code: None on success, else CONTROL_FAILED, PREEMPTED (cancelled, superseded by a
            new gripper move, or the interface closed; the message says which) or TIMED_OUT
            (not judged by the handle's deadline).
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
    calls ``_finish`` when the action is over. ``deadline`` is the simulated time, s, by which it
    is over: the commanded end plus the interface's ``_grace(kind)`` (its settle timeout and two
    polls); a cancel that ends the motion later moves it (``_extend``).
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
        self.deadline = end_time + interface._grace(kind)
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

        Never waits past ``deadline``: an action still undecided then is stopped and its result
        is a failure with code TIMED_OUT.

        Args:
            timeout: most simulated time to wait, s; None waits until the action is over (at
                most until its deadline).

        Raises:
            ValueError: ``timeout`` is not a number of seconds in [0, MAX_WAIT].
            TimeoutError: the action is still running after ``timeout`` simulated seconds.
        """
        timeout = check_duration("timeout", timeout, optional=True)
        if self._result is None:
            left = self.deadline - self._interface.time
            left = min(left, MAX_WAIT) if left > 0.0 else 0.0
            wait = left if timeout is None else min(timeout, left)
            self._interface.advance_until(lambda: self._result is not None, wait)
            self._expire_if_overdue()
        if self._result is None:
            raise TimeoutError(f"the {self.kind} action is still running after {wait} s")
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

    def _extend(self, end_time: float) -> None:
        """The motion now comes to rest at ``end_time``, s: the deadline of a running action is
        at least its grace after that."""
        if self._result is None:
            self.deadline = max(self.deadline, end_time + self._interface._grace(self.kind))

    def _expire_if_overdue(self) -> None:
        """Has the interface stop and fail (TIMED_OUT) the action if its deadline has passed."""
        if self._result is None and self._interface.time >= self.deadline - TIME_TOL:
            self._interface._expire(self)


class PlanHandle:
    """A planning request running in a worker thread (wall time; the simulation does not
    advance while it runs unless the caller advances it).

    ``result()`` returns the planner's ``PlanResult`` or raises its ``PlanningError``;
    after ``cancel()`` (or once its thread pool is shut down before it ran) it raises
    ``PlanningError`` with code PREEMPTED.
    """

    def __init__(self, future: concurrent.futures.Future, timeout: float):
        self._future = future
        self._started = time.perf_counter()
        self._timeout = timeout
        self._cancelled = False
        self._reason = "the planning request was cancelled"

    @property
    def status(self) -> str:
        if self._cancelled or self._future.cancelled():
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
        """Waits for the plan.

        Args:
            timeout: most wall time to wait, s; None waits for the request's planning timeout
                plus ``PLAN_GRACE`` at most (a planner honours its timeout well before).

        Raises:
            ValueError: ``timeout`` is not a number of seconds in [0, MAX_WAIT].
            PlanningError: the planner's error, or PREEMPTED when cancelled.
            TimeoutError: not done within the wait.
        """
        timeout = check_duration("timeout", timeout, optional=True)
        wait = self._timeout + PLAN_GRACE if timeout is None else timeout
        if not self._cancelled:
            try:
                return self._future.result(wait)
            except concurrent.futures.TimeoutError as e:
                raise TimeoutError(f"planning still running after {wait} s") from e
            except concurrent.futures.CancelledError:
                self._reason = "the planning request was dropped before it ran"
        raise PlanningError(ErrorCode.PREEMPTED, self._reason)

    def cancel(self, reason: str = "the planning request was cancelled") -> None:
        """Drops the request: a queued one never runs; a running one's result is discarded.

        Args:
            reason: the message of the PREEMPTED error ``result()`` raises from now on.
        """
        if not self._cancelled:
            self._reason = reason
        self._cancelled = True
        self._future.cancel()


def submit(executor: concurrent.futures.Executor, fn: Callable, timeout: float, /, *args, **kwargs):
    """Runs ``fn(*args, **kwargs)`` on the executor and returns its ``PlanHandle``.

    Args:
        executor: the thread pool.
        fn: the planning request; ``args`` and ``kwargs`` (``timeout=`` too) are passed to it.
        timeout: the request's planning timeout, s of wall time (for ``progress``).

    Raises:
        ValueError: ``timeout`` is not a number of seconds in (0, MAX_WAIT].
    """
    timeout = check_duration("timeout", timeout, positive=True)
    return PlanHandle(executor.submit(fn, *args, **kwargs), timeout)
