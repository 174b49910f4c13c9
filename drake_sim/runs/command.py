"""An app's command line from its recipe: the shared flags declared once (``parser``), the
inputs loaded from them (``load_from_args``), and one run from set-up to exit code
(``run_app``). An app's ``main`` adds its own options and makes one call."""

import argparse
import json
import sys

from drake_sim.base import cli
from drake_sim.base.errors import ConfigError
from drake_sim.runs.recipe import AppRecipe, Inputs

SHARED_FLAGS = ("--headless", "--record", "--report", "--seed", "--set")
"""The flags every app has (with ``--robot`` for an app with a robot file, the scenario flag
and, for a simulated app, ``--duration``)."""


def main(recipe: AppRecipe, doc: str, argv=None) -> int:
    """An app's whole ``main``: parses ``argv`` with ``parser`` and runs ``run_app``."""
    return run_app(recipe, parser(recipe, doc).parse_args(argv))


def parser(recipe: AppRecipe, doc: str) -> cli.ArgumentParser:
    """The app's parser with the shared flags (``doc``'s first line its description), the
    recipe's flags after its files; the help texts are the recipe's ``cli``."""
    text = recipe.cli
    p = cli.ArgumentParser(
        prog=f"python -m drake_sim.{recipe.name}", description=doc.split("\n")[0]
    )
    add_file_options(p, recipe)
    groups = {}
    for flag in recipe.flags:
        where = p
        if flag.group is not None:
            if flag.group not in groups:
                groups[flag.group] = p.add_mutually_exclusive_group()
            where = groups[flag.group]
        where.add_argument(flag.name, **flag.kwargs)
    if text.duration is not None:
        p.add_argument("--duration", type=cli.positive_float, help=text.duration)
    p.add_argument("--headless", action="store_true", help=text.headless)
    p.add_argument("--record", type=cli.output_file("replay"), help="write an HTML replay")
    p.add_argument("--report", type=cli.output_file("report"), help="write the JSON report")
    p.add_argument("--seed", type=cli.non_negative_int, help=text.seed)
    example = f", e.g. --set {text.set_example}" if text.set_example else ""
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help=f"override a scenario value{example} (repeatable; robot.KEY for the robot file)"
        if recipe.robot is not None
        else f"override a scenario value{example} (repeatable)",
    )
    return p


def add_file_options(p: argparse.ArgumentParser, recipe: AppRecipe, default_scenario=None) -> None:
    """Adds ``--robot FILE`` (for an app with a robot file) and the scenario flag (with
    ``--config`` and ``--scenario`` as aliases), checked as ``input_file``s when given; None
    means the recipe's default (or ``default_scenario``)."""
    if recipe.robot is not None:
        p.add_argument(
            "--robot",
            type=cli.input_file("robot file"),
            help=f"robot YAML (default {_config_name(recipe.robot.default_file())})",
        )
    aliases = [f for f in ("--config", "--scenario") if f != recipe.scenario_flag]
    default = default_scenario or recipe.scenario.default_file()
    p.add_argument(
        recipe.scenario_flag,
        *aliases,
        dest="scenario",
        type=cli.input_file("scenario file"),
        default=default_scenario,
        help=f"scenario YAML (default {_config_name(default)})",
    )


def _config_name(path) -> str:
    parts = path.parts
    return "/".join(parts[parts.index("config") :]) if "config" in parts else str(path)


def overrides_from_args(recipe: AppRecipe, args: argparse.Namespace) -> list[str]:
    """``--set`` and the recipe's flags as ``KEY=VALUE`` strings (the flags last: they win)."""
    flags = []
    for flag in recipe.flags:
        value = getattr(args, flag.dest)
        if flag.key is not None and value is not None:
            flags.append(flag.override(value))
    return [*args.set, *flags]


def load_from_args(recipe: AppRecipe, args: argparse.Namespace) -> Inputs:
    """The inputs the command line names: files, ``--set``, the recipe's flags, ``--seed``."""
    loader = {f.dest: getattr(args, f.dest) for f in recipe.flags if f.loader}
    return recipe.load(
        scenario=args.scenario,
        robot=getattr(args, "robot", None),
        overrides=overrides_from_args(recipe, args),
        seed=args.seed,
        **loader,
    )


def refuse_teleop_headless(args: argparse.Namespace) -> None:
    """Raises ConfigError for ``--teleop`` with ``--headless`` (teleop is the page's keys)."""
    if getattr(args, "teleop", False) and args.headless:
        raise ConfigError("--teleop needs the viewer: drop --headless")


def run_app(recipe: AppRecipe, args: argparse.Namespace, inputs: Inputs | None = None) -> int:
    """One run of the app from its command line: load, build (with Meshcat unless
    ``--headless``; recording for ``--record``), run until done, stopped or ``--duration``,
    print the summary line, write ``--report`` and the replay, and return the exit code: 0
    for a completed or stopped run, 1 for a failed one (one ``error:`` line on stderr).

    A stop during the set-up that the run did not catch ends it as "stopped" too.
    """
    from pydrake.geometry import StartMeshcat  # noqa: PLC0415 (Meshcat's server starts here)

    refuse_teleop_headless(args)
    inputs = inputs if inputs is not None else load_from_args(recipe, args)
    viewer = not args.headless
    meshcat = StartMeshcat() if viewer or args.record else None
    run = recipe.make_run(inputs, args, meshcat=meshcat, realtime=viewer)
    duration = getattr(args, "duration", None) or run.default_duration(viewer=viewer)
    try:
        if meshcat is not None:
            run.set_up_viewer(meshcat)
            if args.record:
                meshcat.StartRecording()
        run.drive(duration, meshcat=meshcat if viewer else None, headless=args.headless)
    except BaseException as e:  # a stop between the set-up and the run's own loop
        if not cli.is_stop(e):
            raise
        run.end = "stopped"
    finally:
        if args.record:
            cli.write_replay(meshcat, args.record)
    report = run.finish()
    line = run.summary(report)
    if line:
        print(line, flush=True)
    if args.report:
        cli.write_text(args.report, json.dumps(report.to_dict(), indent=2) + "\n", "report")
    error = run.error(report)
    if error:
        print(f"error: {error}", file=sys.stderr, flush=True)
    if viewer:
        run.linger(meshcat)
    return cli.EXIT_FAILED if error else cli.EXIT_OK
