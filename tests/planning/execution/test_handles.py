"""Action and plan handles: done(), result(timeout), cancel(), progress and status.

ActionHandle runs on a fake interface (a simulated clock with the interface's ``advance_until``)
and on a real ``MotionPlanningInterface`` joined to a stub station that tracks the command
perfectly; PlanHandle runs on a thread pool whose jobs wait on events, so nothing depends on
wall-clock speed. Property test (hypothesis, derandomized): ``check_duration`` on any float
(200 examples).
"""

import concurrent.futures
import threading
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import planning.execution.handles as mut
from planning import ErrorCode, PlanningError, PlanningScene
from tests.planning.execution.stub_station import started_interface

POLL = 0.01  # s of simulated time per step of the fake interface
GRACE = 0.1  # s after its commanded end by which the fake interface judges an action


class FakeInterface:
    """What ActionHandle uses of ``MotionPlanningInterface``: ``time``, ``advance_until`` (in
    steps of POLL, finishing actions whose end has come), ``_cancel`` (which, like the
    interface, only ends the action at a later step), ``_grace`` and ``_expire``."""

    def __init__(self):
        self.time = 0.0
        self.steps = 0
        self.cancelled = []
        self.expired = []
        self.ends = {}  # handle -> simulated time it finishes

    def start(self, duration, kind="execute"):
        handle = mut.ActionHandle(self, kind, self.time, self.time + duration)
        self.ends[handle] = self.time + duration
        return handle

    def advance_until(self, condition, timeout=None):
        end = None if timeout is None else self.time + timeout
        while not condition():
            if end is not None and self.time >= end - 1e-12:
                return
            self.time = round(self.time + POLL, 9)
            self.steps += 1
            for handle, finish in self.ends.items():
                if not handle.done() and self.time >= finish - 1e-12:
                    cancelled = handle in self.cancelled
                    code = ErrorCode.PREEMPTED if cancelled else None
                    handle._finish(
                        result(not cancelled, handle.start_time, self.time, code), cancelled
                    )

    def _cancel(self, handle):
        self.cancelled.append(handle)
        self.ends[handle] = self.time + 0.05  # comes to rest

    def _grace(self, kind):
        return GRACE

    def _expire(self, handle):
        self.expired.append(handle)
        handle._finish(result(False, handle.start_time, self.time, ErrorCode.TIMED_OUT))


def result(success, start, end, code=None):
    return mut.ExecutionResult(success, code, "", np.zeros(7), 0.04, start, end)


def test_action_result_advances_simulated_time_until_the_end():
    interface = FakeInterface()
    dut = interface.start(0.5)
    assert not dut.done() and dut.status == mut.RUNNING and dut.progress == 0.0
    first = dut.result()
    assert dut.done() and dut.status == mut.SUCCEEDED
    assert first.success and first.start_time == 0.0 and first.end_time == pytest.approx(0.5)
    assert interface.time == pytest.approx(0.5) and dut.progress == 1.0
    steps = interface.steps
    assert dut.result() is first  # a finished action returns its result without advancing
    assert interface.steps == steps


def test_action_progress_follows_simulated_time():
    interface = FakeInterface()
    interface.time = 1.0
    dut = interface.start(0.4)
    seen = []
    while not dut.done():
        seen.append(dut.progress)
        interface.advance_until(lambda: False, 0.1)
    assert seen == pytest.approx([0.0, 0.25, 0.5, 0.75])
    assert dut.progress == 1.0
    assert interface.start(0.0).progress == 1.0  # nothing to wait for


def test_action_result_timeout_is_simulated_time():
    interface = FakeInterface()
    dut = interface.start(1.0)
    with pytest.raises(TimeoutError, match="execute"):
        dut.result(timeout=0.3)
    assert interface.time == pytest.approx(0.3) and not dut.done()
    assert dut.progress == pytest.approx(0.3)
    with pytest.raises(TimeoutError):
        dut.result(timeout=0.0)  # does not advance at all
    assert interface.time == pytest.approx(0.3)
    assert dut.result(timeout=0.7).success  # just long enough


def test_action_cancel_asks_the_interface_and_ends_preempted():
    interface = FakeInterface()
    dut = interface.start(1.0, kind="gripper")
    interface.advance_until(lambda: False, 0.2)
    dut.cancel()
    assert dut.cancel_requested and interface.cancelled == [dut]
    assert not dut.done() and dut.status == mut.RUNNING  # still coming to rest
    outcome = dut.result()
    assert outcome.code is ErrorCode.PREEMPTED and not outcome.success
    assert outcome.end_time == pytest.approx(0.25)
    assert dut.done() and dut.status == mut.CANCELLED and dut.progress == 1.0
    dut.cancel()  # over: nothing more to stop
    assert interface.cancelled == [dut]


def test_finished_action_cannot_be_cancelled():
    interface = FakeInterface()
    dut = interface.start(0.1)
    assert dut.result().success
    dut.cancel()
    assert interface.cancelled == [] and not dut.cancel_requested
    assert dut.status == mut.SUCCEEDED


def test_failed_result_sets_failed_status():
    dut = mut.ActionHandle(FakeInterface(), "gripper", 0.0, 1.0, target=0.01)
    assert dut.kind == "gripper" and dut.target == 0.01 and dut.plan is None
    dut._finish(result(False, 0.0, 1.2, ErrorCode.CONTROL_FAILED))
    assert dut.status == mut.FAILED and dut.result().code is ErrorCode.CONTROL_FAILED


def test_action_result_never_waits_past_its_deadline():
    interface = FakeInterface()
    dut = interface.start(0.5)
    assert dut.deadline == pytest.approx(0.5 + GRACE)
    interface.ends[dut] = float("inf")  # the interface never judges it
    outcome = dut.result(timeout=100.0)
    assert interface.expired == [dut] and interface.time == pytest.approx(dut.deadline)
    assert not outcome.success and outcome.code is ErrorCode.TIMED_OUT
    assert dut.status == mut.FAILED and dut.result() is outcome


def test_action_result_without_timeout_is_bounded_too():
    interface = FakeInterface()
    dut = interface.start(0.3, kind="gripper")
    interface.ends[dut] = float("inf")
    assert dut.result().code is ErrorCode.TIMED_OUT
    assert interface.time == pytest.approx(0.3 + GRACE)


def test_a_later_rest_extends_the_deadline():
    dut = FakeInterface().start(1.0)
    dut._extend(0.5)  # earlier than the end: no change
    assert dut.deadline == pytest.approx(1.0 + GRACE)
    dut._extend(1.2)
    assert dut.deadline == pytest.approx(1.2 + GRACE)
    dut._finish(result(False, 0.0, 0.4, ErrorCode.TIMED_OUT))
    dut._extend(5.0)  # over: its deadline stays
    assert dut.deadline == pytest.approx(1.2 + GRACE)


@pytest.mark.parametrize("timeout", [float("nan"), float("inf"), -float("inf"), -0.1, 1e300, "1"])
def test_action_result_refuses_a_bad_timeout_and_keeps_running(timeout):
    interface = FakeInterface()
    dut = interface.start(0.5)
    with pytest.raises(ValueError, match="timeout"):
        dut.result(timeout=timeout)
    assert interface.time == 0.0 and not dut.done()
    assert dut.result().success


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -1.0, mut.MAX_WAIT * 1.01, True])
def test_check_duration_refuses_and_names_the_argument(value):
    with pytest.raises(ValueError, match="^my_timeout must be a number of seconds in"):
        mut.check_duration("my_timeout", value)


def test_check_duration_bounds_zero_and_none():
    assert mut.check_duration("t", mut.MAX_WAIT) == mut.MAX_WAIT
    assert mut.check_duration("t", np.float32(0.5)) == 0.5
    assert mut.check_duration("t", None, optional=True) is None
    with pytest.raises(ValueError, match=r"in \(0, "):
        mut.check_duration("t", 0.0, positive=True)
    with pytest.raises(ValueError):
        mut.check_duration("t", None)


@settings(max_examples=200, derandomize=True, deadline=None)
@given(value=st.floats())
def test_check_duration_property(value):
    """Property: any float is returned unchanged when in [0, MAX_WAIT], else refused."""
    if 0.0 <= value <= mut.MAX_WAIT:
        assert mut.check_duration("d", value) == value
    else:
        with pytest.raises(ValueError, match="^d must"):
            mut.check_duration("d", value)


# --------------------------------------------------------------------------- PlanHandle ----
class Job:
    """A planning job that runs until released (and records that it ran)."""

    def __init__(self, value="plan", error=None):
        self.started, self.release = threading.Event(), threading.Event()
        self.value, self.error, self.ran = value, error, False

    def __call__(self, *args, **kwargs):
        self.ran, self.args, self.kwargs = True, args, kwargs
        self.started.set()
        assert self.release.wait(60.0), "the test never released the job"
        if self.error is not None:
            raise self.error
        return self.value


@pytest.fixture
def executor():
    pool = concurrent.futures.ThreadPoolExecutor(1)
    yield pool
    pool.shutdown(wait=True, cancel_futures=True)


def test_submit_runs_the_function_with_its_arguments(executor):
    job = Job(value="the plan")
    dut = mut.submit(executor, job, 5.0, 1, 2, q_start="here")
    assert job.started.wait(60.0)
    assert dut.status == mut.RUNNING and not dut.done()
    job.release.set()
    assert dut.result() == "the plan"
    assert dut.done() and dut.status == mut.SUCCEEDED and dut.progress == 1.0
    assert job.args == (1, 2) and job.kwargs == {"q_start": "here"}


def test_plan_result_timeout_raises_timeout_error(executor):
    job = Job()
    dut = mut.submit(executor, job, 5.0)
    with pytest.raises(TimeoutError, match="still running"):
        dut.result(timeout=0.01)
    job.release.set()
    assert dut.result(timeout=60.0) == "plan"


def test_plan_progress_is_the_share_of_the_timeout(executor, monkeypatch):
    clock = SimpleNamespace(now=100.0)
    monkeypatch.setattr(mut, "time", SimpleNamespace(perf_counter=lambda: clock.now))
    job = Job()
    dut = mut.submit(executor, job, 4.0)
    assert dut.progress == 0.0
    clock.now += 1.0
    assert dut.progress == pytest.approx(0.25)
    clock.now += 10.0
    assert dut.progress == 1.0  # past the timeout, still running
    job.release.set()
    dut.result(timeout=60.0)
    assert dut.progress == 1.0


def test_planner_errors_reach_the_caller(executor):
    job = Job(error=PlanningError(ErrorCode.GOAL_IN_COLLISION, "goal collides: a <-> b"))
    job.release.set()
    dut = mut.submit(executor, job, 5.0)
    with pytest.raises(PlanningError) as error:
        dut.result(timeout=60.0)
    assert error.value.code is ErrorCode.GOAL_IN_COLLISION
    assert dut.status == mut.FAILED and dut.done()


def test_cancelled_queued_request_never_runs(executor):
    first, second = Job(), Job()
    running = mut.submit(executor, first, 5.0)
    assert first.started.wait(60.0)
    dut = mut.submit(executor, second, 5.0)
    assert dut.status == mut.PENDING and not dut.done()
    dut.cancel()
    assert dut.done() and dut.status == mut.CANCELLED
    first.release.set()
    assert running.result(timeout=60.0) == "plan"
    executor.shutdown(wait=True)
    assert not second.ran
    with pytest.raises(PlanningError) as error:
        dut.result()
    assert error.value.code is ErrorCode.PREEMPTED


def test_cancelled_running_request_discards_its_result(executor):
    job = Job()
    dut = mut.submit(executor, job, 5.0)
    assert job.started.wait(60.0)
    dut.cancel()
    assert dut.done() and dut.status == mut.CANCELLED and dut.progress == 1.0
    job.release.set()
    executor.shutdown(wait=True)
    assert job.ran
    with pytest.raises(PlanningError) as error:
        dut.result()
    assert error.value.code is ErrorCode.PREEMPTED
    assert dut.status == mut.CANCELLED


def test_submit_passes_a_timeout_argument_to_the_request(executor):
    job = Job()
    job.release.set()
    dut = mut.submit(executor, job, 2.0, "goal", timeout=2.0)
    assert dut.result(timeout=60.0) == "plan" and job.kwargs == {"timeout": 2.0}
    for timeout in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="timeout"):
            mut.submit(executor, job, timeout)


@pytest.mark.parametrize("timeout", [float("nan"), float("inf"), -1.0])
def test_plan_result_refuses_a_bad_timeout(executor, timeout):
    job = Job()
    dut = mut.submit(executor, job, 5.0)
    with pytest.raises(ValueError, match="timeout"):
        dut.result(timeout=timeout)
    job.release.set()
    assert dut.result(timeout=60.0) == "plan"


def test_request_dropped_by_a_shut_down_pool_is_preempted(executor):
    first, second = Job(), Job()
    running = mut.submit(executor, first, 5.0)
    assert first.started.wait(60.0)
    dut = mut.submit(executor, second, 5.0)
    executor.shutdown(wait=False, cancel_futures=True)
    assert dut.done() and dut.status == mut.CANCELLED
    with pytest.raises(PlanningError, match="dropped before it ran") as error:
        dut.result(timeout=60.0)
    assert error.value.code is ErrorCode.PREEMPTED
    first.release.set()
    assert running.result(timeout=60.0) == "plan" and not second.ran


def test_plan_result_without_timeout_is_bounded(executor, monkeypatch):
    monkeypatch.setattr(mut, "PLAN_GRACE", 0.0)
    job = Job()
    dut = mut.submit(executor, job, 0.01)  # waits its 0.01 s planning timeout, no more
    with pytest.raises(TimeoutError, match="still running"):
        dut.result()
    job.release.set()
    assert dut.result(timeout=60.0) == "plan"


def test_cancel_reason_is_the_error_message(executor):
    job = Job()
    dut = mut.submit(executor, job, 5.0)
    dut.cancel("the interface was closed")
    dut.cancel("a second reason")  # the first one stays
    job.release.set()
    with pytest.raises(PlanningError, match="the interface was closed"):
        dut.result()


# ------------------------------------------------------ on a real interface, simulated time ----
@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


def close_gripper_polling(scene, poll):
    """Closes the gripper (0.8 s), polling ``done()`` every ``poll`` s (None: ``result()``)."""
    interface = started_interface(scene)
    handle = interface.move_gripper_async(0.0)
    assert handle._planned_end > 0.0
    while poll is not None and not handle.done():
        interface.advance(poll)
    return handle.result()


def test_gripper_action_ends_at_the_same_simulated_time_however_often_polled(scene):
    expected = close_gripper_polling(scene, None)
    assert expected.success and expected.finger_position == pytest.approx(0.0)
    assert expected.end_time == pytest.approx(0.85)  # 0.04 m at 0.05 m/s, then settle_time
    for poll in (0.01, 0.05, 0.2):  # whole poll periods: the same steps, the same end
        assert close_gripper_polling(scene, poll).end_time == pytest.approx(
            expected.end_time, abs=1e-9
        )


def test_gripper_action_end_does_not_depend_on_an_uneven_poll(scene):
    expected = close_gripper_polling(scene, None)
    for poll in (0.037, 0.013, 0.1234, 0.005):  # not whole poll periods
        end = close_gripper_polling(scene, poll).end_time
        assert end == expected.end_time  # checked on the same grid: the very same time
