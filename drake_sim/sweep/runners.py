"""What a sweep can run: one ``Runner`` per app, a table entry naming the app's run module
(``drake_sim.runs.<app>``, whose ``RECIPE`` loads and builds it) and the sweep's options; and
``run_rollout``, the function a worker calls.

A rollout reaches its worker as plain data (the job: runner name, scenario file, options; the
rollout: index, seed, overrides) and its diagram is built there, because Drake systems do not
pickle. Its result comes back as a plain dict. Any exception inside a rollout (a bad value that
only the scenario's own checks catch, a simulation that diverges) becomes a row with
``status: failed`` and the reason, so that one bad rollout never ends a sweep.
"""

import dataclasses as dc
import importlib
import json
import os
import socket
import time

from drake_sim.base import cli
from drake_sim.base.errors import ConfigError


def override_strings(overrides: dict) -> list[str]:
    """``--set``-style ``KEY=VALUE`` strings for ``overrides`` (path -> value), in order.

    Values are written as JSON (which YAML reads), so strings stay strings; an indexed path
    (``scene.object.position[1]``) sets that one item (``config.apply_overrides``).
    """
    return [f"{path}={json.dumps(value)}" for path, value in overrides.items()]


@dc.dataclass(frozen=True)
class Runner:
    """An app as a sweep runs it, headless: its run module and the sweep's options.

    Paths under ``robot.`` vary the robot file (``options.robot``, default the app's robot);
    every other path varies the scenario. ``generated`` names the parameters the run module
    draws itself (``random: N``: its ``generate_<name>(scenario, k)`` gives draw k). The
    rollout's seed goes to the scenario's seed unless the sweep varies that key itself.
    """

    name: str
    module: str  # drake_sim.runs.<app>: RECIPE, report_keys(), optionally sweep_row(report)
    options: dict = dc.field(default_factory=dict)  # the sweep's options and their defaults
    file_options: tuple[str, ...] = ()  # options naming files (relative to the sweep file)
    generated: tuple[str, ...] = ()

    def app(self):
        """The run module (imported here: a worker imports only the app it runs)."""
        return importlib.import_module(self.module)

    def load(self, scenario: str, options: dict, overrides: dict, seed=None):
        """The inputs (robot and scenario) of one rollout, overridden and checked."""
        app, overrides = self.app(), dict(overrides)
        drawn = {name: overrides.pop(name) for name in self.generated if name in overrides}
        recipe = app.RECIPE
        if recipe.seed_key in overrides:
            seed = None
        inputs = recipe.load(
            scenario=scenario,
            robot=options.get("robot"),
            overrides=override_strings(overrides),
            seed=seed,
        )
        loaded = inputs.scenario
        for name, k in drawn.items():
            loaded = getattr(app, f"generate_{name}")(loaded, int(k))
        return dc.replace(inputs, scenario=loaded)

    def metric_keys(self) -> tuple[str, ...]:
        return self.app().report_keys()

    def run(self, scenario: str, options: dict, overrides: dict, seed: int) -> dict:
        """One headless rollout: its report as a dict (``sweep_row`` flattens it if the app
        has one). A simulation error raises ``RuntimeError`` with its first line."""
        app = self.app()
        inputs = self.load(scenario, options, overrides, seed)
        run = app.RECIPE.make_run(inputs, options)
        duration = options.get("duration") or run.default_duration(viewer=False)
        if run.run(float(duration)) == run.failed_end:
            raise RuntimeError(run.failure)
        report = run.report().to_dict()
        return app.sweep_row(report) if hasattr(app, "sweep_row") else report


RUNNERS = {
    r.name: r
    for r in (
        Runner("flip", "drake_sim.runs.flip", {"duration": 6.0, "robot": None}, ("robot",)),
        Runner("pickplace", "drake_sim.runs.pickplace", generated=("scene",)),
        Runner("walle", "drake_sim.runs.walle", {"duration": None, "robot": None}, ("robot",)),
        Runner(
            "navigation",
            "drake_sim.runs.navigate",
            {"goals": 3, "map": None, "global_localization": False, "robot": None},
            ("robot", "map"),
        ),
        Runner("explore", "drake_sim.runs.explore", {"duration": None, "robot": None}, ("robot",)),
    )
}
"""flip: ``duration`` s simulated; walle: ``duration`` (None: the app's own, a lap's worth
when following); navigation: ``goals`` random goals drawn with the rollout's seed (the same sets
at every value of the other parameters), ``map`` a map_server YAML (default: the arena's ground
truth at the lidar's height), ``global_localization``; explore: ``duration`` (None: the
scenario's ``time_limit``; the map is not saved); each with ``robot``, a robot YAML."""


def get_runner(name: str, where: str = "sweep") -> Runner:
    """The runner called ``name``.

    Raises:
        ConfigError: for an unknown name, listing the known ones.
    """
    if name not in RUNNERS:
        raise ConfigError(f"{where}: unknown runner {name!r} (known: {', '.join(RUNNERS)})")
    return RUNNERS[name]


def worker_id() -> str:
    """Which worker ran a rollout: host and process id."""
    return f"{socket.gethostname()}:{os.getpid()}"


def run_rollout(job: dict, rollout: dict) -> dict:
    """Builds and runs one rollout; the function every backend sends to its workers.

    Returns:
        A row: ``index``, ``seed``, ``overrides``, ``status`` ("ok" or "failed"), ``reason``,
        ``report`` (the runner's report dict, empty if it failed), ``wall_time_s``, ``worker``.
    """
    cli.quiet_drake_logger()  # stderr is for errors only
    start = time.perf_counter()
    report, status, reason = {}, "ok", ""
    try:
        runner = get_runner(job["runner"])
        report = runner.run(job["scenario"], job["options"], rollout["overrides"], rollout["seed"])
    except Exception as e:  # noqa: BLE001 (any failure of one rollout is that rollout's row)
        lines = str(e).strip().splitlines()
        status, reason = "failed", f"{type(e).__name__}: {lines[0] if lines else ''}".strip()
    return {
        "index": rollout["index"],
        "seed": rollout["seed"],
        "overrides": rollout["overrides"],
        "status": status,
        "reason": reason,
        "report": report,
        "wall_time_s": time.perf_counter() - start,
        "worker": worker_id(),
    }
