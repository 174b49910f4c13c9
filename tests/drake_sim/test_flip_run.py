"""``FlipRun.advance_to(progress=True)``: the same run, with a bar on terminals only."""

import io

import pytest

import drake_sim.flip_run as mut
from tests.flip_helpers import default_robot, flip_scenario

WALL_CLOCK_KEYS = {"wall_time_s", "real_time_factor"}


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _report(run) -> dict:
    return {k: v for k, v in run.report().to_dict().items() if k not in WALL_CLOCK_KEYS}


def test_progress_changes_nothing_but_the_display(monkeypatch):
    terminal = _Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    plain = mut.FlipRun(flip_scenario(), default_robot(), seed=1)
    plain.advance_to(1.2)
    shown = mut.FlipRun(flip_scenario(), default_robot(), seed=1)
    shown.advance_to(1.2, progress=True)
    assert shown.context.get_time() == pytest.approx(1.2)
    assert _report(shown) == _report(plain)
    assert "simulated s" in terminal.getvalue()


def test_no_bar_when_stderr_is_not_a_terminal(capsys):
    run = mut.FlipRun(flip_scenario(), default_robot(), seed=1)
    run.advance_to(0.6, progress=True)
    assert run.context.get_time() == pytest.approx(0.6)
    assert capsys.readouterr().err == ""
