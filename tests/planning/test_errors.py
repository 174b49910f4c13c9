"""PlanningError and its MoveIt-style ErrorCode."""

import pytest

import planning.errors as mut


def test_codes_are_distinct_lowercase_names():
    codes = list(mut.ErrorCode)
    assert len({c.value for c in codes}) == len(codes)
    for code in codes:
        assert code.value == code.name.lower()
        assert mut.ErrorCode(code.value) is code  # a code round-trips through its value


def test_planning_error_carries_code_and_message():
    dut = mut.PlanningError(mut.ErrorCode.GOAL_IN_COLLISION, "panda_hand <-> crate")
    assert isinstance(dut, RuntimeError)
    assert dut.code is mut.ErrorCode.GOAL_IN_COLLISION
    assert dut.message == "panda_hand <-> crate"
    assert str(dut) == "GOAL_IN_COLLISION: panda_hand <-> crate"
    with pytest.raises(RuntimeError, match="^NO_IK_SOLUTION: far away$"):
        raise mut.PlanningError(mut.ErrorCode.NO_IK_SOLUTION, "far away")


def test_planning_error_survives_pickling():
    import pickle

    from planning.errors import ErrorCode, PlanningError

    error = pickle.loads(pickle.dumps(PlanningError(ErrorCode.TIMED_OUT, "no path in 5 s")))
    assert isinstance(error, PlanningError)
    assert error.code is ErrorCode.TIMED_OUT and error.message == "no path in 5 s"
    assert str(error) == "TIMED_OUT: no path in 5 s"
