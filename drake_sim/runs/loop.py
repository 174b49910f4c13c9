"""The one run loop: ``SimulationRun`` simulates until the run's own end condition, a stop
signal (Ctrl-C, SIGTERM) or the duration, with a progress bar on a terminal, and keeps the wall
time for the report. Each app's run subclasses it and adds its diagram, its end conditions
(``check``) and its report."""

import math
import time

from pydrake.systems.analysis import ApplySimulatorConfig, Simulator
from tqdm import tqdm

from drake_sim.base import cli
from drake_sim.base.simulation import start_simulator

PROGRESS_STEP = 0.5
"""s simulated between progress-bar updates of a run that has no check period of its own."""

BAR_FORMAT = "{l_bar}{bar}| {n:.1f}/{total:.1f} simulated s [{elapsed}<{remaining}]"


class SimulationRun:
    """A diagram's simulator, advanced by ``run`` (to an end) or ``advance`` (by a time).

    Subclasses set ``check_period`` (s simulated between calls of ``check``, None for a run
    whose only end is its duration) and override ``check`` (the end condition met, or None),
    ``default_duration``, ``set_up_viewer``, ``report``, ``summary`` and ``error``.

    Attributes:
        end: why the run ended: "duration" until something else ends it; "stopped" for a user
            stop; ``failed_end`` for a simulation error (its first line in ``failure``).
        wall_time: s of wall time spent simulating.
    """

    check_period: float | None = None
    failed_end = "failed"
    doing = "running"  # What the announcement says the run is doing.
    progress_from = 0.0  # s: a CLI's headless run this long or longer shows a progress bar.

    def __init__(self, diagram, seed: int, *, realtime=False, config=None, meshcat=None):
        """Starts the simulator of ``diagram`` with every random source drawn from ``seed``.
        ``realtime`` paces it (None: when there is a ``meshcat``): with Drake's
        ``SimulatorConfig`` ``config`` when given (else flat out), else at a real-time rate
        of 1."""
        self.diagram = diagram
        self.seed = seed
        if realtime is None:
            realtime = meshcat is not None
        if config is not None:
            configure = (lambda s: ApplySimulatorConfig(config, s)) if realtime else None
        else:
            configure = lambda s: s.set_target_realtime_rate(1.0 if realtime else 0.0)  # noqa: E731
        self.simulator: Simulator
        self.simulator, self.context = start_simulator(diagram, seed, configure)
        self.end = "duration"
        self.failure = ""
        self.wall_time = 0.0

    # --- what subclasses say ---------------------------------------------------------------

    def check(self) -> str | None:
        """The end condition met now (an end's name), or None to go on."""
        return None

    def default_duration(self, *, viewer: bool = False) -> float:
        """Simulated s of a run without ``--duration``."""
        return math.inf

    def set_up_viewer(self, meshcat) -> None:
        """Points Meshcat's camera at the scene (and says what the page offers)."""

    def report(self):
        """The run's report so far."""
        raise NotImplementedError

    def summary(self, report) -> str | None:
        """The one line printed after a run (None: nothing)."""
        return None

    def error(self, report) -> str | None:
        """Why the run failed, in one line (exit code 1), or None."""
        if self.end == self.failed_end:
            return f"simulation failed at t = {self.context.get_time():.3f} s: {self.failure}"
        return None

    def drive(self, duration: float, *, meshcat=None, headless: bool = True) -> None:
        """What a CLI's run does: says it has started (at Meshcat's URL, or headless) and
        runs until ``duration``, with a progress bar when ``headless`` (and the run is at least
        ``progress_from`` long)."""
        cli.announce(meshcat, self.doing)
        self.run(duration, progress=headless and duration >= self.progress_from)

    def finish(self):
        """Ends a CLI's run (saving what it made) and returns its report."""
        return self.report()

    def linger(self, meshcat) -> None:
        """After a CLI's run with a viewer: keeps the page alive while the user looks (until
        Ctrl-C), for an app whose run ends before the user does. Most end at once."""

    # --- the loop --------------------------------------------------------------------------

    def run(self, duration: float, *, progress: bool = False) -> str:
        """Simulates until ``duration`` (s), an end condition (``check``, every
        ``check_period``), a user stop ("stopped") or a simulation error (``failed_end``,
        its first line in ``failure``); returns why it ended, also in ``end``.

        A run without a check period advances in one step, or in ``PROGRESS_STEP`` steps with
        ``progress``. With ``progress`` a bar shows on stderr when it is a terminal.
        """
        period = self.check_period
        if period is None and progress and math.isfinite(duration):
            period = PROGRESS_STEP
        start = time.perf_counter()
        bar = None
        try:
            t = self.context.get_time()
            if period is None:
                self.simulator.AdvanceTo(duration)
                return self.end
            if progress and math.isfinite(duration):
                bar = tqdm(total=duration - t, leave=False, disable=None, bar_format=BAR_FORMAT)
            while t < duration and self.end == "duration":
                step_start, t = t, min(duration, t + period)
                self.simulator.AdvanceTo(t)
                self.end = self.check() or "duration"
                if bar is not None:
                    bar.update(t - step_start)
        except BaseException as e:
            self.end, self.failure = cli.run_ending(e)
            if self.end == "failed":
                self.end = self.failed_end
        finally:
            if bar is not None:
                bar.close()
            self.wall_time += time.perf_counter() - start
        return self.end

    def advance(self, duration: float) -> None:
        """Simulates ``duration`` more seconds, checking every ``check_period`` (for callers
        that drive the run themselves, e.g. by sending goals); errors are raised."""
        end = self.context.get_time() + duration
        period = self.check_period or duration
        start = time.perf_counter()
        try:
            while self.context.get_time() < end - 1e-9:
                self.simulator.AdvanceTo(min(end, self.context.get_time() + period))
                ended = self.check()
                if ended is not None:
                    self.end = ended
        finally:
            self.wall_time += time.perf_counter() - start
