"""Shared command-line plumbing: one-line errors and exit code 2 on bad input."""

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

from drake_sim.base.errors import ConfigError

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_BAD_INPUT = 2


class ArgumentParser(argparse.ArgumentParser):
    """An argparse parser whose usage errors are one line on stderr and exit code 2."""

    def error(self, message: str):  # noqa: D102 (argparse's own contract)
        raise ConfigError(f"{self.prog}: {message} (see --help)")


def run(main: Callable[[Sequence[str] | None], int], argv: Sequence[str] | None = None) -> int:
    """Runs ``main(argv)`` and turns bad input into one stderr line and exit code 2.

    ``ConfigError`` (every loader turns bad input into one) is reported as ``error: <message>``
    on one line; Ctrl-C ends the run quietly with code 0. Anything else is a bug and is raised.
    """
    try:
        return main(argv)
    except ConfigError as e:
        print(f"error: {' '.join(str(e).split())}", file=sys.stderr)  # one line
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        return EXIT_OK


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text!r}")
    return value


def non_negative_int(text: str) -> int:
    """argparse type: an integer >= 0 (e.g. a random seed)."""
    return _int_at_least(text, 0)


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1 (e.g. a count)."""
    return _int_at_least(text, 1)


def _int_at_least(text: str, minimum: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {value}")
    return value


def add_robot_and_config_options(
    parser: argparse.ArgumentParser, *, default_robot: Path, default_config: Path
) -> None:
    """Adds ``--robot FILE`` and ``--config FILE`` with these defaults."""
    parser.add_argument("--robot", type=Path, default=default_robot, help="robot YAML")
    parser.add_argument("--config", type=Path, default=default_config, help="scenario YAML")


def write_replay(meshcat, path: Path, *, recording: bool = True) -> None:
    """Writes Meshcat's scene as a self-contained HTML file, with the recording (stopped and
    published first) if ``recording``."""
    if recording:
        meshcat.StopRecording()
        meshcat.PublishRecording()
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(meshcat.StaticHtml())
    print(f"wrote {path}")
