"""An app described once: ``AppRecipe`` names its robot and scenario files (schema, loader,
check, default file), where its seed lives, the flags that set scenario keys, and how to make
its run; ``load_inputs`` is the one loader every way of starting a run goes through.

The CLIs (``drake_sim.runs.command``), the sweep runners, the notebooks and the benchmarks all
start runs from a recipe, in the manner of Drake's ``hardware_sim`` (one typed scenario builds
everything) and the manipulation course's ``LoadScenario`` -> ``MakeHardwareStation``::

    from drake_sim.runs.flip import RECIPE
    run = RECIPE.start(seed=3, overrides=["flip.drive_speed=0.8"])
    run.run(8.0)  # returns why it ended; run.report() says what it did
"""

import dataclasses as dc
import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from drake_sim.base import cli, config
from drake_sim.base.config import load_checked


@dc.dataclass(frozen=True)
class InputFile:
    """One of an app's input files: its schema, its loader, its check and its default.

    ``load(path)`` returns the checked value; ``check(value, where)`` raises ``ConfigError``
    naming ``where`` and the key. An app whose loader applies overrides itself (the scenario
    fills in keys it refuses from ``--set``) gives ``load_overridden(path, overrides)``.
    """

    schema: type
    default_file: Callable[[], Path]
    check: Callable[[Any, str], Any]
    what: str = "scenario file"
    load: Callable[[Path], Any] | None = None
    load_overridden: Callable[..., Any] | None = None

    def read(
        self, path: Path | str | None, overrides: Sequence[str] = (), where="--set", **loader
    ) -> Any:
        """The file at ``path`` (the default when None) with ``KEY=VALUE`` ``overrides``
        applied, checked (errors name ``where``); ``loader`` keywords go to
        ``load_overridden``.

        Raises:
            ConfigError: naming the file, or ``--set``, and the key at fault.
        """
        path = Path(path) if path is not None else self.default_file()
        if self.load_overridden is not None:
            return self.load_overridden(path, list(overrides), **loader)
        if self.load is not None:
            value = self.load(path)
        else:
            value = load_checked(self.schema, path, self.check, what=self.what)
        if overrides:
            value = config.apply_overrides(self.schema, value, list(overrides), where)
            self.check(value, where)
        return value


@dc.dataclass(frozen=True)
class Flag:
    """One of an app's own command-line flags (``argparse`` keywords in ``kwargs``).

    A flag with a ``key`` sets that scenario key (``--mode both`` is ``--set mode=both``; a
    file argument, a ``Path`` or a list of them, is made absolute first); a ``loader`` flag is
    a keyword of the scenario file's loader (``--scene FILE``: a file that replaces a
    section); any other is an option the app's run reads. Flags that share a ``group``
    exclude each other.
    """

    name: str
    key: str | None = None
    kwargs: dict = dc.field(default_factory=dict)
    group: str | None = None
    loader: bool = False

    @property
    def dest(self) -> str:
        """The attribute of the parsed arguments."""
        return self.name.lstrip("-").replace("-", "_")

    def override(self, value) -> tuple[str, str]:
        """``(label, KEY=VALUE)`` for ``value`` (JSON, which YAML reads: a string stays one); an
        error in it names the flag and its value."""
        label = f"{self.name} {value}"
        if isinstance(value, Path):
            value = str(value.absolute())
        elif isinstance(value, list):  # nargs: files made absolute one by one
            value = [str(v.absolute()) if isinstance(v, Path) else v for v in value]
        return label, f"{self.key}={json.dumps(value)}"


def file_flag(name: str, what: str, help_text: str, *, required=False, **flag) -> "Flag":
    """A flag naming a file to read (``cli.input_file(what)``); ``flag``: ``Flag``'s ``key``,
    ``group`` or ``loader``."""
    kwargs = {"type": cli.input_file(what), "help": help_text}
    if required:
        kwargs["required"] = True
    return Flag(name, kwargs=kwargs, **flag)


def switch(name: str, help_text: str, group: str | None = None) -> "Flag":
    """An on/off option of the app's run (``store_true``)."""
    return Flag(name, kwargs={"action": "store_true", "help": help_text}, group=group)


@dc.dataclass(frozen=True)
class CliText:
    """What an app's shared flags say in its ``--help``: what ``--seed`` seeds, a ``--set``
    example, ``--duration``'s default (None: the app has no ``--duration``)."""

    seed: str = "random seed"
    set_example: str = ""
    duration: str | None = None
    headless: str = "no Meshcat, no real-time pacing"


@dc.dataclass(frozen=True)
class Inputs:
    """What a run is made of: the loaded robot (None for an app without a robot file) and
    scenario, and the seed the scenario holds."""

    scenario: Any
    robot: Any = None
    seed: int = 0


@dc.dataclass(frozen=True)
class AppRecipe:
    """One app, described once.

    Args:
        name: the app's name (``python -m drake_sim.<app>``, the sweep runner's name).
        scenario: the scenario file.
        robot: the robot file, or None.
        seed_key: the scenario's one seed (a ``--set`` key path).
        make_run: ``make_run(inputs, options, *, meshcat, realtime) -> run``: the app's run
            (diagram, simulator, report), ``options`` the app's own (a namespace or dict).
        flags: the app's own flags (``Flag``).
        scenario_flag: the flag naming the scenario file (``--config`` is an alias).
        cli: the help texts of its command line (``CliText``).
    """

    name: str
    scenario: InputFile
    make_run: Callable[..., Any]
    seed_key: str
    robot: InputFile | None = None
    flags: tuple[Flag, ...] = ()
    scenario_flag: str = "--config"
    cli: "CliText" = dc.field(default_factory=lambda: CliText())

    def load(
        self,
        *,
        scenario: Path | str | None = None,
        robot: Path | str | None = None,
        overrides: Sequence[str] = (),
        seed: int | None = None,
        **loader,
    ) -> Inputs:
        """``load_inputs`` for this recipe."""
        return load_inputs(
            self, scenario=scenario, robot=robot, overrides=overrides, seed=seed, **loader
        )

    def start(self, *, meshcat=None, realtime: bool = False, **kwargs):
        """Loads the inputs and makes the run: the first of a notebook's two calls (the second
        is ``run.run(duration)``, then ``run.report()`` says what it did). ``kwargs``: ``load``'s
        (``scenario``, ``robot``, ``overrides``, ``seed``, a loader's keywords); the rest are
        the app's own options (see its ``make_run``)."""
        names = {"scenario", "robot", "overrides", "seed"} | {
            f.dest for f in self.flags if f.loader
        }
        load = {k: v for k, v in kwargs.items() if k in names}
        options = {k: v for k, v in kwargs.items() if k not in names}
        inputs = self.load(**load)
        return self.make_run(inputs, options, meshcat=meshcat, realtime=realtime)


def option(options, name: str, default=None):
    """An app option from a CLI's parsed arguments or a caller's dict."""
    if isinstance(options, dict):
        return options.get(name, default)
    return getattr(options, name, default)


def split_overrides(overrides: Sequence[str]) -> tuple[list[str], list[str]]:
    """``KEY=VALUE`` strings split into the robot file's (``robot.`` keys, without that
    prefix) and the scenario's."""
    robot, scenario = [], []
    for item in overrides:
        if isinstance(item, str) and item.startswith("robot."):
            robot.append(item[len("robot.") :])
        else:
            scenario.append(item)
    return robot, scenario


def load_inputs(
    recipe: AppRecipe,
    *,
    scenario: Path | str | None = None,
    robot: Path | str | None = None,
    overrides: Sequence[str] = (),
    seed: int | None = None,
    **loader,
) -> Inputs:
    """Loads an app's robot and scenario: the files (the recipe's defaults when None), the
    ``KEY=VALUE`` overrides (``robot.``-prefixed ones on the robot file, for an app that has
    one), then the seed at the recipe's ``seed_key`` (the scenario's own when None), each
    checked. ``loader`` keywords go to the scenario's ``load_overridden``.

    Raises:
        ConfigError: naming the file or ``--set`` and the key, for anything malformed or out of
            range.
    """
    on_robot, on_scenario = split_overrides(overrides) if recipe.robot else ([], list(overrides))
    if seed is not None:
        on_scenario.append(f"{recipe.seed_key}={int(seed)}")
    loaded_robot = None
    if recipe.robot is not None:
        loaded_robot = recipe.robot.read(robot, on_robot, where="--set (robot file)")
    loaded = recipe.scenario.read(scenario, on_scenario, **loader)
    value = loaded
    for step in config.parse_key_path(recipe.seed_key, "seed key"):
        value = value[step] if isinstance(step, int) else getattr(value, step)
    return Inputs(scenario=loaded, robot=loaded_robot, seed=int(value))
