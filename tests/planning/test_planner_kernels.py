"""The planner's kernels: built once, in the background, while planners plan on Drake's checker.

The build itself is not run here (the session's own build, ``tests/conftest.py``, is the real
one); these tests drive the lock, the status and the planner's switch with stand-ins.
"""

import io
import sys

import numpy as np
import pytest

from drake_sim.base.errors import ConfigError
from planning import MotionPlanner, PlanningScene
from planning import planner_kernels as mut


@pytest.fixture
def state(tmp_path, monkeypatch):
    """The build's lock and status in a folder of the test's own."""
    monkeypatch.setattr(mut, "state_dir", lambda: tmp_path)
    return tmp_path


def test_the_mode_comes_from_the_environment(monkeypatch):
    monkeypatch.delenv(mut.ENV_MODE, raising=False)
    assert mut.mode() == "background"
    monkeypatch.setenv(mut.ENV_MODE, "wait")
    assert mut.mode() == "wait"
    monkeypatch.setenv(mut.ENV_MODE, "sometimes")
    with pytest.raises(ConfigError, match="DRAKE_SIM_KERNELS='sometimes': expected one of"):
        mut.mode()


def test_one_build_holds_the_lock_at_a_time(state):
    lock = mut._try_lock()
    assert lock is not None
    try:
        assert mut._try_lock() is None  # another taker is refused at once
        assert mut.building()
    finally:
        lock.close()
    assert not mut.building()


def test_a_background_build_is_started_once_and_handed_the_lock(state, monkeypatch):
    started = []

    class FakePopen:
        pid = 4242

        def __init__(self, args, **kwargs):
            started.append((args, kwargs))
            assert mut.building()  # the lock is held while the build process starts

    monkeypatch.setattr(mut, "ready", lambda: False)
    monkeypatch.setattr(mut.subprocess, "Popen", FakePopen)
    assert mut.start_background()
    ((args, kwargs),) = started
    assert args[:3] == [sys.executable, "-m", "planning.planner_kernels"]
    assert "--background" in args and "--lock-fd" in args
    assert kwargs["pass_fds"] == (int(args[args.index("--lock-fd") + 1]),)
    assert kwargs["start_new_session"]  # Ctrl-C in the terminal does not stop it
    assert mut.read_status()["state"] == "building"
    assert mut.read_status()["pid"] == FakePopen.pid  # whoever must end it can

    lock = mut._try_lock()  # a build already runs: no second one
    try:
        assert mut.start_background()
    finally:
        lock.close()
    assert len(started) == 1


def test_no_build_starts_when_the_kernels_are_ready(state, monkeypatch):
    monkeypatch.setattr(mut, "ready", lambda: True)
    monkeypatch.setattr(mut.subprocess, "Popen", lambda *a, **k: pytest.fail("started a build"))
    assert not mut.start_background()


def test_waiting_follows_the_build_another_process_runs(state, monkeypatch):
    looks = iter([False, False, False, True])
    monkeypatch.setattr(mut, "ready", lambda: next(looks))
    monkeypatch.setattr(mut, "_POLL_S", 0.0)
    monkeypatch.setattr(mut, "build", lambda **_: pytest.fail("built while another builds"))
    mut._write_status(
        {"state": "building", "step": 3, "steps": 7, "name": "the fine check", "started": 0.0}
    )
    stream = io.StringIO()
    lock = mut._try_lock()  # the other process's lock
    try:
        mut.wait_ready(progress=mut.ProgressLine("test", stream))
    finally:
        lock.close()
    lines = stream.getvalue().splitlines()
    assert len(lines) == 1  # off a terminal: once
    assert "step 3 of 7: the fine check" in lines[0] and "of about" in lines[0]


def test_waiting_builds_here_when_no_one_else_does(state, monkeypatch):
    built = []
    monkeypatch.setattr(mut, "ready", lambda: bool(built))
    monkeypatch.setattr(mut, "build", lambda **_: built.append(True))
    mut.wait_ready()
    assert built == [True]
    assert not mut.building()  # the lock is let go


def test_a_build_that_cannot_make_everything_ready_does_not_loop(state, monkeypatch):
    built = []
    monkeypatch.setattr(mut, "ready", lambda: False)
    monkeypatch.setattr(mut, "build", lambda **_: built.append(True))
    mut.wait_ready()
    assert built == [True]


def test_the_status_in_words():
    assert mut.describe({}).startswith("starting, about ")
    text = mut.describe(
        {"state": "building", "step": 2, "steps": 7, "name": "the sphere covers", "started": 0}
    )
    assert text.startswith("step 2 of 7: the sphere covers, ")


def test_the_command_says_when_there_is_nothing_to_build(monkeypatch, capsys):
    monkeypatch.setattr(mut, "ready", lambda: True)
    assert mut.main([]) == 0
    assert "compiled and cached" in capsys.readouterr().out


def test_a_planner_plans_on_drakes_checker_until_the_build_is_done_then_switches(monkeypatch):
    mut.wait_ready()  # the real kernels, for the switch (the session's build)
    done = {"ready": False}
    monkeypatch.setenv(mut.ENV_MODE, "background")
    monkeypatch.setattr(mut, "ready", lambda: done["ready"])
    monkeypatch.setattr(mut, "start_background", lambda: True)
    scene = PlanningScene()
    dut = MotionPlanner(scene)
    assert dut._search._sphere_model() is None  # Drake's checker alone
    assert dut.options.spheres.enabled  # the options are the caller's still
    ready = scene.model.named_configurations["ready"]
    goal = ready + np.array([0.4, 0.2, 0.0, 0.1, 0.0, 0.1, 0.0])
    assert dut.plan_to_joints(goal, q_start=ready).success

    done["ready"] = True  # the build has finished
    assert dut.plan_to_joints(goal, q_start=ready).success
    assert dut._search._sphere_model() is not None  # the compiled search on the spheres


def test_a_planner_waits_for_the_builds_ik_steps_instead_of_compiling_them_too(monkeypatch):
    looks = []

    def cold(dispatcher):  # cold at the first two looks, then cached by the build
        looks.append(dispatcher)
        return len(looks) <= 2

    monkeypatch.setattr(mut.sphere_kernel, "cache_is_cold", cold)
    monkeypatch.setattr(mut, "building", lambda: True)
    monkeypatch.setattr(mut, "_POLL_S", 0.0)
    mut.await_shared()
    assert len(looks) == 4  # two waits, then both kernels found cached


def test_no_wait_for_ik_steps_when_no_build_runs(monkeypatch):
    monkeypatch.setattr(mut.sphere_kernel, "cache_is_cold", lambda d: True)
    monkeypatch.setattr(mut, "building", lambda: False)
    monkeypatch.setattr(mut.time, "sleep", lambda s: pytest.fail("waited with no build"))
    mut.await_shared()
