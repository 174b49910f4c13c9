"""The public API of ``planning``: the documented import works, each name documented and tested."""

import inspect
from pathlib import Path

import planning as mut

TESTS = Path(__file__).resolve().parent.parent


def test_design_contract_import():
    from planning import (  # noqa: F401 (the import is the test)
        MotionPlanner,
        MotionPlanningInterface,
        PickPlaceTask,
        Plan,
        PlanningError,
        PlanningScene,
        RobotState,
    )


def test_every_public_name_exists_and_has_a_docstring():
    for name in mut.__all__:
        value = getattr(mut, name)
        assert (inspect.getdoc(value) or "").strip(), f"planning.{name} has no docstring"


def test_every_public_name_is_used_by_a_test():
    texts = [p.read_text() for p in TESTS.rglob("test_*.py") if p.name != Path(__file__).name]
    for name in mut.__all__:
        assert any(name in text for text in texts), f"no test uses planning.{name}"
