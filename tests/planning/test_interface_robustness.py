"""MotionPlanningInterface never hangs or dies: any float given as a duration, a
timeout or a finger position either works within a bounded simulated time or raises
ValueError / PlanningError, and the station keeps working afterwards.

Property tests (hypothesis, derandomized; examples per test in ``EXAMPLES``) run on one kinematic
station shared by the module, which is fine because each example leaves it working and at rest.
"""

import math

import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st

from diagrams.pickplace_scenario import load_pickplace_scenario
from diagrams.planning_station import make_planning_station
from planning import ErrorCode, PlanningError
from planning.execution.handles import MAX_WAIT, TIME_TOL
from planning.model.layout import FINGER_OPEN

EXAMPLES = 60
SPECIAL = [math.nan, math.inf, -math.inf, -0.0, 0.0, -1e-300, 5e-324, MAX_WAIT, 1e300, -1e300]
ANY_FLOAT = st.one_of(st.floats(), st.floats(0.0, 2.0), st.sampled_from(SPECIAL))
# advance(d) really waits d: valid ones kept short (the rest are refused, or as valid as these).
DURATION = st.one_of(
    st.floats(0.0, 2.0),
    st.floats(max_value=0.0, exclude_max=True),  # negative, down to -inf
    st.floats(min_value=MAX_WAIT, exclude_min=True),  # too long, up to inf
    st.sampled_from(SPECIAL).filter(lambda d: not 2.0 < d <= MAX_WAIT),  # with NaN
)
property_test = settings(max_examples=EXAMPLES, derandomize=True, deadline=None)


@pytest.fixture(scope="module")
def station():
    return make_planning_station(load_pickplace_scenario(), mode="kinematic")


def valid_duration(value: float) -> bool:
    return 0.0 <= value <= MAX_WAIT


def assert_still_works(mpi) -> None:
    """A valid command succeeds: the fingers go to the other end of their travel."""
    finger = float(mpi.read_state()[7])
    target = 0.0 if finger > 0.5 * FINGER_OPEN else FINGER_OPEN
    outcome = mpi.move_gripper(target)
    assert outcome.success and outcome.finger_position == pytest.approx(target, abs=2e-3)


def assert_refused(mpi, call, argument: str, handle=None) -> None:
    """``call()`` raises ValueError naming ``argument``, and nothing moves on."""
    t0 = mpi.time
    with pytest.raises(ValueError, match=f"^{argument} must be"):
        call()
    assert mpi.time == t0 and (handle is None or not handle.done())


def gripper_move(mpi):
    """Starts a full-travel gripper move (0.8 s) and returns its handle."""
    finger = float(mpi.read_state()[7])
    return mpi.move_gripper_async(0.0 if finger > 0.5 * FINGER_OPEN else FINGER_OPEN)


@property_test
@given(duration=DURATION)
def test_advance_any_duration(station, duration):
    t0 = station.time
    event("valid" if valid_duration(duration) else "refused")
    if valid_duration(duration):
        station.advance(duration)
        assert station.time == pytest.approx(t0 + duration, abs=1e-9)
    else:
        assert_refused(station, lambda: station.advance(duration), "duration")
    assert_still_works(station)


@pytest.mark.parametrize("how", ["advance_until", "result"])
@property_test
@given(timeout=ANY_FLOAT)
def test_waiting_on_an_action_with_any_timeout(station, how, timeout):
    """``advance_until(handle.done, timeout)`` or ``handle.result(timeout)``: refused, or over
    after exactly ``timeout`` or when the action is, never past its deadline."""
    handle = gripper_move(station)
    t0 = station.time
    wait = {
        "result": lambda: handle.result(timeout=timeout),
        "advance_until": lambda: station.advance_until(handle.done, timeout),
    }[how]
    if not valid_duration(timeout):
        event("refused")
        assert_refused(station, wait, "timeout", handle)
    else:
        try:
            wait()
        except TimeoutError:
            assert how == "result"
        event("action over" if handle.done() else "waited the timeout")
        # Within the station's time tolerance (a shorter wait is none), plus the rounding of
        # t0 + timeout at the station's clock (t0 is some 100 s in).
        assert handle.done() or station.time == pytest.approx(t0 + timeout, abs=TIME_TOL + 1e-12)
    outcome = handle.result()  # finishes the move, whatever happened above
    assert outcome.success and outcome.end_time <= handle.deadline
    assert station.time <= handle.deadline + 1e-9  # never waited past the deadline
    assert_still_works(station)


@property_test
@given(position=st.one_of(st.floats(), st.floats(0.0, FINGER_OPEN), st.sampled_from(SPECIAL)))
def test_move_gripper_any_position(station, position):
    t0 = station.time
    valid = math.isfinite(position) and 0.0 <= position <= FINGER_OPEN
    event("valid" if valid else "refused")
    if not math.isfinite(position):
        with pytest.raises(ValueError, match="^position must be a finite number"):
            station.move_gripper(position)
    elif not 0.0 <= position <= FINGER_OPEN:
        with pytest.raises(PlanningError) as error:
            station.move_gripper(position)
        assert error.value.code is ErrorCode.INVALID_GOAL
    else:
        outcome = station.move_gripper(position)
        assert outcome.success and outcome.finger_position == pytest.approx(position, abs=2e-3)
        grace = station.options.finger_settle_timeout + 2 * station.options.poll_period
        assert outcome.end_time - t0 <= FINGER_OPEN / station.options.finger_speed + grace
    if not valid:
        assert station.time == t0  # refused: nothing moved, no time passed
    assert_still_works(station)


@property_test
@given(timeout=ANY_FLOAT)
def test_plan_async_any_timeout(station, timeout):
    def request(*args, q_start, timeout=None):
        return timeout

    if math.isnan(timeout) or not 0.0 < timeout <= MAX_WAIT:
        with pytest.raises(ValueError, match="^timeout must be"):
            station.plan_async(request, timeout=timeout)
    else:
        assert station.plan_async(request, timeout=timeout).result(timeout=60.0) == timeout
    assert station.plan_async(request).result(timeout=60.0) is None  # the pool still works


# ------------------------------------------------------------------------ abuse, one each ----
@pytest.mark.parametrize("timeout", [math.nan, -1.0, math.inf])
def test_planning_timeouts_are_checked_before_planning(station, timeout):
    q0 = station.read_state()[:7]
    with pytest.raises(ValueError, match="^timeout must be"):
        station.move_to_named("extended", timeout=timeout)
    with pytest.raises(ValueError, match="^timeout must be"):
        station.plan_async(station.planner.plan_to_named, "extended").result(timeout=timeout)
    assert (station.read_state()[:7] == q0).all()
    assert_still_works(station)


def test_a_refused_gripper_command_leaves_the_running_one_alone(station):
    handle = gripper_move(station)
    for position in (math.nan, math.inf, 0.5, -0.01):
        with pytest.raises((ValueError, PlanningError)):
            station.move_gripper_async(position)
    assert not handle.done()
    assert handle.result().success and handle.status == "succeeded"


def test_a_non_number_is_refused_with_the_argument_named(station):
    with pytest.raises(ValueError, match="^duration must be"):
        station.advance("0.1")
    with pytest.raises(ValueError, match="^timeout must be"):
        gripper_move(station).result(timeout=True)
    assert_still_works(station)


def test_a_station_that_never_settles_still_ends_each_action(station, monkeypatch):
    monkeypatch.setattr(station.options, "finger_settle_velocity", -1.0)  # never "at rest"
    handle = gripper_move(station)
    outcome = handle.result()
    end = handle._planned_end
    assert outcome.end_time == pytest.approx(end + station.options.finger_settle_timeout, abs=0.011)
    assert outcome.end_time <= handle.deadline


@pytest.mark.parametrize("speed", [math.nan, 0.0, -0.05, math.inf])
def test_a_bad_finger_speed_refuses_the_move_and_changes_nothing(station, monkeypatch, speed):
    handle = gripper_move(station)
    t0 = station.time
    with monkeypatch.context() as patch:
        patch.setattr(station.options, "finger_speed", speed)
        with pytest.raises(ValueError, match="^speed must be"):
            station.move_gripper_async(0.02)
    assert station.time == t0 and not handle.done()  # the running move goes on
    assert handle.result().success
    assert_still_works(station)
