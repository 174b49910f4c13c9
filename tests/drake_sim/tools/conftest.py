"""Fixtures the tools' tests share."""

import pytest

from tests.mbm_helpers import mbm_problems


@pytest.fixture(scope="session")
def mbm_folder():
    """The unpacked MotionBenchMaker Panda problems (``tests/mbm_helpers.py``), for the
    benchmark's tests; the test skips, saying why, when they cannot be had."""
    return mbm_problems()
