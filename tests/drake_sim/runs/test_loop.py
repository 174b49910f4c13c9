"""The one run loop (drake_sim.runs.loop): ``run`` ends at the duration, at the run's own end
condition, at a user stop or at a simulation error (kept as the run's end and failure);
``advance`` moves on by a time; both keep the wall time. A toy run on a trivial diagram (an
integrator of 1: its state is the simulated time) stands in for the apps' runs."""

import io
import math

import pytest
from pydrake.systems.framework import DiagramBuilder, LeafSystem
from pydrake.systems.primitives import ConstantVectorSource, Integrator

import drake_sim.runs.loop as mut


class _Trouble(LeafSystem):
    """Raises ``error`` from a publish event at the first tick at or after ``at`` s."""

    def __init__(self, at: float, error: BaseException | None):
        super().__init__()
        self._at, self._error = at, error
        self.DeclarePeriodicPublishEvent(0.05, 0.0, self._tick)

    def _tick(self, context):
        if self._error is not None and context.get_time() >= self._at - 1e-9:
            raise self._error


class _Toy(mut.SimulationRun):
    """Integrates 1 from 0; ``check`` ends the run once the integral reaches ``end_at``."""

    doing = "integrating"

    def __init__(self, *, period=None, end_at=math.inf, trouble_at=math.inf, error=None):
        builder = DiagramBuilder()
        one = builder.AddSystem(ConstantVectorSource([1.0]))
        self.integrator = builder.AddSystem(Integrator(1))
        builder.Connect(one.get_output_port(), self.integrator.get_input_port())
        builder.AddSystem(_Trouble(trouble_at, error))
        super().__init__(builder.Build(), seed=3)
        self.check_period = period
        self.end_at = end_at
        self.checks = []

    def value(self) -> float:
        context = self.integrator.GetMyContextFromRoot(self.context)
        return self.integrator.get_output_port().Eval(context)[0]

    def check(self):
        self.checks.append(round(self.context.get_time(), 9))
        return "reached" if self.value() >= self.end_at - 1e-9 else None

    def report(self):
        return {"end": self.end, "value": self.value(), "seed": self.seed}


def test_without_a_check_period_it_runs_to_the_duration_in_one_step():
    run = _Toy()
    assert run.run(1.5) == "duration" == run.end
    assert run.context.get_time() == 1.5 and run.value() == pytest.approx(1.5)
    assert run.checks == [] and run.failure == "" and run.wall_time > 0
    assert run.report() == {"end": "duration", "value": pytest.approx(1.5), "seed": 3}


def test_the_run_s_own_end_condition_stops_it_at_the_next_check():
    run = _Toy(period=0.1, end_at=0.35)
    assert run.run(10.0) == "reached" == run.end
    assert run.checks == pytest.approx([0.1, 0.2, 0.3, 0.4])
    assert run.context.get_time() == pytest.approx(0.4)


def test_checks_end_at_the_duration_when_nothing_else_ends_it():
    run = _Toy(period=0.4)
    assert run.run(1.0) == "duration"
    assert run.checks == pytest.approx([0.4, 0.8, 1.0])


def test_a_simulation_error_is_the_run_s_failed_end_with_its_first_line():
    run = _Toy(trouble_at=0.3, error=RuntimeError("diverged\nsecond line"))
    assert run.run(1.0) == "failed" == run.end
    assert run.failure == "diverged"
    assert 0.25 <= run.context.get_time() <= 0.3 + 1e-9
    assert run.wall_time > 0
    assert run.error(run.report()) == (
        f"simulation failed at t = {run.context.get_time():.3f} s: diverged"
    )


def test_a_run_may_name_its_failed_end():
    run = _Toy(trouble_at=0.2, error=RuntimeError("diverged"))
    run.failed_end = "sim_failed"
    assert run.run(1.0, progress=True) == "sim_failed"
    assert run.error(run.report()).endswith(": diverged")


def test_a_user_stop_ends_the_run_as_stopped():
    run = _Toy(period=0.1, trouble_at=0.2, error=KeyboardInterrupt())
    assert run.run(1.0) == "stopped" and run.failure == ""
    assert run.error(run.report()) is None


def test_any_other_error_is_a_bug_and_is_raised():
    run = _Toy(trouble_at=0.1, error=ValueError("a bug"))
    with pytest.raises(ValueError, match="a bug"):
        run.run(1.0)
    assert run.wall_time > 0


def test_progress_steps_the_same_run_and_shows_a_bar_on_a_terminal_only(monkeypatch, capsys):
    quiet = _Toy()
    assert quiet.run(1.2, progress=True) == "duration"
    assert quiet.checks == pytest.approx([0.5, 1.0, 1.2])  # PROGRESS_STEP steps
    assert capsys.readouterr().err == ""

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    shown = _Toy()
    shown.run(1.2, progress=True)
    assert shown.value() == pytest.approx(quiet.value())
    assert "simulated s" in terminal.getvalue()


def test_the_wall_time_adds_up_over_calls():
    run = _Toy()
    run.run(0.5)
    first = run.wall_time
    run.run(1.0)
    assert run.wall_time > first and run.context.get_time() == 1.0


def test_advance_moves_on_by_a_time_checking_on_the_way():
    run = _Toy(period=0.25, end_at=0.6)
    run.advance(0.5)
    assert run.context.get_time() == pytest.approx(0.5) and run.end == "duration"
    assert run.checks == pytest.approx([0.25, 0.5])
    run.advance(0.5)  # past the end condition: recorded, the time still advanced
    assert run.context.get_time() == pytest.approx(1.0) and run.end == "reached"
    assert run.wall_time > 0


def test_advance_raises_simulation_errors():
    run = _Toy(trouble_at=0.2, error=RuntimeError("diverged"))
    with pytest.raises(RuntimeError, match="diverged"):
        run.advance(1.0)


def test_what_a_cli_does_with_a_run(capsys):
    run = _Toy(period=0.5)
    assert run.default_duration() == math.inf and run.summary(None) is None
    run.drive(1.0)
    assert capsys.readouterr().out == "integrating headless (Ctrl-C stops)\n"
    assert run.end == "duration" and run.context.get_time() == 1.0
    assert run.finish() == run.report()
    run.set_up_viewer(None)
    run.linger(None)
    with pytest.raises(NotImplementedError):
        mut.SimulationRun.report(run)
