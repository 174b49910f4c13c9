"""Shared fixtures: a per-session cache folder so tests never touch ~/.cache."""

import pytest


@pytest.fixture(autouse=True, scope="session")
def _session_cache(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("DRAKE_SIM_CACHE", str(tmp_path_factory.mktemp("drake_sim_cache")))
    yield
    mp.undo()
