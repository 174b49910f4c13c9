"""What a planner makes before its first request (planning.planner_setup): whether the compiled
search can be had now (cached, built and waited for, or building in the background), the timing's
kernels, and the joint path search on the spheres or, while the build runs, on Drake's checker."""

import pytest

from planning import PlanningScene, planner_kernels
from planning import planner_setup as mut
from planning.planner_options import MotionPlannerOptions


def test_kernels_now_when_cached(monkeypatch, capsys):
    monkeypatch.setenv(planner_kernels.ENV_MODE, "background")
    monkeypatch.setattr(planner_kernels, "start_background", lambda: False)  # cached
    assert mut.kernels_now()
    assert capsys.readouterr().err == ""


def test_not_now_while_a_background_build_runs(monkeypatch, capsys):
    monkeypatch.setenv(planner_kernels.ENV_MODE, "background")
    monkeypatch.setattr(planner_kernels, "start_background", lambda: True)
    monkeypatch.setattr(planner_kernels, "read_status", lambda: {})
    assert not mut.kernels_now()
    assert "until they are ready, plans use Drake's collision checker" in capsys.readouterr().err


def test_wait_mode_waits_for_the_build(monkeypatch):
    waited = []
    monkeypatch.setenv(planner_kernels.ENV_MODE, "wait")
    monkeypatch.setattr(planner_kernels, "wait_ready", lambda progress: waited.append(progress))
    monkeypatch.setattr(planner_kernels, "start_background", lambda: pytest.fail("built"))
    assert mut.kernels_now()
    assert waited == [None]  # no progress line: stderr is not a terminal here


def test_warm_up_timing_loads_the_timing_kernels():
    mut.warm_up_timing()
    assert mut.toppra.solve.signatures and mut.cubic.evaluate.signatures


@pytest.mark.parametrize("pending", [True, False])
def test_make_search_uses_the_spheres_unless_pending(pending):
    options = MotionPlannerOptions()
    dut = mut.make_search(PlanningScene(), options, pending)
    assert (dut._sphere_model() is None) == pending
    assert options.spheres.enabled  # the caller's options are left alone
