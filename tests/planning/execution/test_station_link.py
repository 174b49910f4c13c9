"""StationLink (the station side of MotionPlanningInterface) on a stub station that tracks the
command perfectly: the polling grid, bounded waits, deadlines, option checks and closing.

Property test (hypothesis, derandomized): the gripper's end under any polling pattern
(25 examples).
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import planning.execution.station_link as mut
from planning import ErrorCode, InterfaceOptions, PlanningError, PlanningScene
from planning.execution.commander import GripperCommand
from planning.model.layout import FINGER_OPEN
from tests.planning.execution.stub_station import started_interface


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


@pytest.fixture
def dut(scene):
    return started_interface(scene)


def test_monitors_run_on_multiples_of_the_poll_period_however_time_is_split(dut):
    times = []
    dut.add_monitor(lambda link: times.append(link.time))
    for duration in (0.037, 0.013, 0.0, 0.0049, 0.1):
        dut.advance(duration)
    assert dut.time == pytest.approx(0.1549, abs=1e-12)  # stops where asked, between polls
    np.testing.assert_allclose(times, 0.01 * np.arange(1, 16), atol=1e-12)


@settings(max_examples=25, derandomize=True, deadline=None)
@given(polls=st.lists(st.floats(0.0, 0.3), min_size=1, max_size=8))
def test_gripper_action_end_is_the_same_under_any_polling_pattern(scene, polls):
    """Property: advancing by any sequence of durations (ten times over, then ``result()``)
    ends the gripper move at the time ``result()`` alone gives."""
    link = started_interface(scene)
    handle = link.move_gripper_async(0.0)
    for poll in polls * 10:
        if handle.done():
            break
        link.advance(poll)
    assert handle.result().end_time == pytest.approx(0.85, abs=1e-9)


@pytest.mark.parametrize("duration", [float("nan"), float("inf"), -0.01, 3600.5, None])
def test_advance_refuses_a_bad_duration_and_changes_nothing(dut, duration):
    with pytest.raises(ValueError, match="^duration must be"):
        dut.advance(duration)
    with pytest.raises(ValueError, match="^timeout must be"):
        dut.advance_until(lambda: False, duration if duration is not None else -1.0)
    assert dut.time == 0.0
    assert dut.move_gripper(0.02).success  # and the station still works


def test_advance_until_without_timeout_is_bounded(dut, monkeypatch):
    monkeypatch.setattr(mut, "MAX_WAIT", 0.25)  # the bound None stands for
    dut.advance_until(lambda: False)
    assert dut.time == pytest.approx(0.25, abs=1e-12)


@pytest.mark.parametrize(
    "field,value",
    [("poll_period", 0.0), ("poll_period", float("nan")), ("settle_timeout", -1.0)],
)
def test_options_that_could_hang_are_refused(scene, field, value):
    with pytest.raises(ValueError, match=f"^options.{field} must be"):
        started_interface(scene, InterfaceOptions(**{field: value}))


def test_a_poll_period_broken_after_start_is_refused_when_advancing(dut):
    dut.options.poll_period = 0.0
    with pytest.raises(ValueError, match="options.poll_period"):
        dut.advance(0.1)
    dut.options.poll_period = 0.01
    dut.advance(0.1)
    assert dut.time == pytest.approx(0.1)


def test_an_action_never_judged_times_out_at_its_deadline(dut):
    handle = dut.move_gripper_async(0.0)
    assert handle.deadline == pytest.approx(0.8 + 0.5 + 0.02)  # end, settle timeout, 2 polls
    context = dut._context(dut._commander)  # the command now ends 100 s later: never judged
    dut._commander.set_gripper(context, GripperCommand(FINGER_OPEN, 0.0, 100.0))
    outcome = handle.result()
    assert handle.status == "failed" and outcome.code is ErrorCode.TIMED_OUT
    assert "deadline" in outcome.message
    assert outcome.end_time == pytest.approx(handle.deadline, abs=0.011)
    assert dut.move_gripper(0.01).success  # stopped, and the gripper works again


def test_an_overdue_action_also_ends_while_the_user_only_advances(dut):
    handle = dut.move_gripper_async(0.0)
    context = dut._context(dut._commander)
    dut._commander.set_gripper(context, GripperCommand(FINGER_OPEN, 0.0, 100.0))
    dut.advance(2.0)
    assert handle.done() and handle.result().code is ErrorCode.TIMED_OUT


def test_close_cancels_the_running_action_and_then_every_call_raises(dut):
    handle = dut.move_gripper_async(0.0)
    dut.advance(0.2)
    dut.close()
    outcome = handle.result()  # over: returns without the simulator
    assert handle.status == "cancelled" and outcome.code is ErrorCode.PREEMPTED
    assert outcome.message == "cancelled: the interface was closed"
    calls = [
        lambda: dut.advance(0.1),
        lambda: dut.advance_until(lambda: True),
        lambda: dut.time,
        dut.read_state,
        dut.object_pose,
        lambda: dut.move_gripper(0.01),
        lambda: dut.add_monitor(print),
        lambda: dut.simulator,
    ]
    for call in calls:
        with pytest.raises(RuntimeError, match="^the interface is closed$") as error:
            call()
        assert not isinstance(error.value, PlanningError)
    dut.close()  # again: nothing to do


def test_with_block_closes_even_when_it_raises(scene):
    with pytest.raises(KeyError), started_interface(scene) as link:
        handle = link.move_gripper_async(0.0)
        raise KeyError("user code failed")
    assert handle.status == "cancelled"
    with pytest.raises(RuntimeError, match="closed"):
        link.advance(0.1)
