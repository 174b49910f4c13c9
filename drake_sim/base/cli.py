"""Shared command-line plumbing: one-line errors and exit code 2 on bad input, path arguments
checked before a run starts, and SIGTERM handled like Ctrl-C.

An entry point builds its options with ``ArgumentParser`` and these argparse types (files it
reads: ``input_file``; files and folders it writes: ``output_file``, ``output_dir``), and runs
``sys.exit(run(main))``: a bad path, like any other bad input, is then one line on stderr and exit
code 2 before anything is built or simulated, and Ctrl-C or SIGTERM end the run with code 0.
"""

import argparse
import contextlib
import logging
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_BAD_INPUT = 2

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
"""The signals that stop a run like Ctrl-C (``stop_on_signals``)."""

_EMPTY_CHECK_BYTES = 4096  # A file shorter than this and only whitespace is empty.


class ArgumentParser(argparse.ArgumentParser):
    """An argparse parser whose usage errors are one line on stderr and exit code 2."""

    def error(self, message: str):  # noqa: D102 (argparse's own contract)
        raise ConfigError(f"{self.prog}: {message} (see --help)")


def run(main: Callable[[Sequence[str] | None], int], argv: Sequence[str] | None = None) -> int:
    """Runs ``main(argv)`` and turns bad input into one stderr line and exit code 2.

    ``ConfigError`` (every loader turns bad input into one) is reported as ``error: <message>``
    on one line; Ctrl-C and SIGTERM (``stop_on_signals``, ``is_stop``) end the run with code 0,
    after whatever summary ``main`` prints when it catches them (a stop ``main`` lets through, in
    its set-up, gets a line of its own). Anything else is a bug and is raised.
    """
    quiet_drake_logger()
    try:
        with stop_on_signals():
            try:
                return main(argv)
            except ConfigError:
                raise
            except BaseException as e:  # checked while the handler is in force
                if not is_stop(e):
                    raise
                print("stopped before the run began (while it was being set up)", flush=True)
                return EXIT_OK
    except ConfigError as e:
        print(f"error: {' '.join(str(e).split())}", file=sys.stderr)  # one line
        return EXIT_BAD_INPUT


def quiet_drake_logger() -> None:
    """Keeps Drake's INFO lines off stderr (stderr is for errors). pydrake sets its logger up
    when it is first imported, so it is imported here first."""
    import pydrake.common  # noqa: F401, PLC0415 (the import configures the "drake" logger)

    logging.getLogger("drake").setLevel(logging.WARNING)


@contextlib.contextmanager
def logger_level(name: str, level: int):
    """Within the block, the logger ``name`` passes only records of ``level`` and above (a
    command's own choice, e.g. a benchmark's table not buried in warnings); then its level is
    what it was, so a command run in-process (tests, notebooks) changes nothing after it."""
    logger = logging.getLogger(name)
    saved = logger.level
    logger.setLevel(level)
    try:
        yield
    finally:
        logger.setLevel(saved)


def is_stop(error: BaseException) -> bool:
    """Whether ``error`` is a user stop: a ``KeyboardInterrupt`` (Ctrl-C, or SIGTERM under
    ``stop_on_signals``), or any error raised after ``stop_on_signals`` received a stop signal.

    Compiled code can turn the interrupt that lands in its callbacks into another error:
    numba-compiled functions raise a ``SystemError`` caused by it, and pybind11 (Drake's
    bindings) reports an interrupt during argument conversion as a ``TypeError`` naming no
    matching overload. Catch ``BaseException`` and re-raise what this says is not a stop.
    """
    while isinstance(error, SystemError) and error.__cause__ is not None:
        error = error.__cause__
    handler = signal.getsignal(signal.SIGINT)
    stopped = isinstance(error, KeyboardInterrupt) or stop_received()
    if stopped and isinstance(handler, _SignalStop):
        handler.noticed.set()  # the run handles its stop: no watchdog ending
    return stopped


def run_ending(error: BaseException) -> tuple[str, str]:
    """How ``error`` ends a simulation run: ``("stopped", "")`` for a user stop (``is_stop``),
    ``("failed", <its first line>)`` for a ``RuntimeError`` (Drake's simulation errors); any
    other error is a bug and is raised again."""
    if is_stop(error):
        return "stopped", ""
    if isinstance(error, RuntimeError):
        return "failed", (str(error).strip().splitlines() or [type(error).__name__])[0]
    raise error


def stop_received() -> bool:
    """Whether the ``stop_on_signals`` block now in force has received a stop signal."""
    handler = signal.getsignal(signal.SIGINT)
    return isinstance(handler, _SignalStop) and handler.received is not None


def exit_at_once(code: int) -> None:
    """Ends the process with ``code`` now, with stdout and stderr flushed, but without waiting
    for worker threads or running ``atexit`` hooks.

    For an entry point whose worker threads may still be busy when Ctrl-C or SIGTERM stops it
    (a motion planner searching until its timeout), so that the stop takes effect at once:
    ``exit_at_once(run(main))``. Its files are written and closed by then.
    """
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):
            stream.flush()
    os._exit(code)


STOP_GRACE_S = 1.5
"""s a stopped run has to notice its stop (``is_stop``) before the process ends anyway."""


class _SignalStop:
    """The handler ``stop_on_signals`` installs: raises ``KeyboardInterrupt`` and remembers
    the signal, so that ``is_stop`` knows an error raised after it is the stop's doing.

    Compiled code may swallow that interrupt (numba's compiler in a long call into LLVM,
    a C++ library that catches everything): a watchdog thread then ends the process with code 0
    ``STOP_GRACE_S`` after the signal unless the run has noticed the stop by then (``is_stop``
    was asked). A second signal ends the process at once, with code 0: the user insists.
    A signal that lands inside a finalizer (``__del__``, where Python would print the interrupt
    with its traceback and drop it) is sent again ``REDELIVER_S`` later instead.
    """

    def __init__(self):
        self.received: int | None = None
        self.noticed = threading.Event()
        self._watchdog: threading.Thread | None = None

    def __call__(self, signum, frame):
        self._start_watchdog()
        if _in_finalizer(frame):
            # Raised here, the interrupt would be printed as "Exception ignored in ... __del__"
            # with its traceback and then lost: deliver the signal again once it has run.
            again = threading.Timer(REDELIVER_S, os.kill, (os.getpid(), signum))
            again.daemon = True
            again.start()
            return
        if self.received is not None:
            _end_now(f"stopped ({signal.Signals(signum).name} again)")
        self.received = signum
        raise KeyboardInterrupt(signal.Signals(signum).name)

    def _start_watchdog(self) -> None:
        if self._watchdog is None:
            self._watchdog = threading.Thread(target=self._watch, name="stop-watchdog", daemon=True)
            self._watchdog.start()

    def _watch(self) -> None:
        if not self.noticed.wait(STOP_GRACE_S):
            _end_now("stopped")


REDELIVER_S = 0.01
"""s after which a signal that arrived inside a finalizer is delivered again."""


def _in_finalizer(frame) -> bool:
    """Whether ``frame`` runs inside an object's ``__del__`` (directly or in what it calls):
    an exception raised there is printed and discarded (the garbage collector calls it, in
    llvmlite's compiled code objects for one, at any bytecode)."""
    while frame is not None:
        if frame.f_code.co_name == "__del__":
            return True
        frame = frame.f_back
    return False


def _end_now(line: str) -> None:
    """Ends the process with code 0 now, after one line on stdout (files being written are
    left as they were: every output is written atomically)."""
    with contextlib.suppress(OSError, ValueError):
        print(line, flush=True)
    exit_at_once(EXIT_OK)


@contextlib.contextmanager
def stop_on_signals(signals: Sequence[int] = STOP_SIGNALS) -> Iterator[None]:
    """Within the block, each of ``signals`` raises ``KeyboardInterrupt`` in the main thread.

    So SIGTERM stops a run the way Ctrl-C does (Drake's ``Simulator.AdvanceTo`` checks for
    Python signals as it steps), and SIGINT does even where a parent process ignored it. After
    a stop, errors in finalizers (``sys.unraisablehook``: objects the stop interrupted while
    they were built) are not printed. The previous handlers come back at the end. Outside the
    main thread it does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    handler = _SignalStop()
    previous = {s: signal.signal(s, handler) for s in signals}
    previous_hook = sys.unraisablehook

    def quiet_after_a_stop(report) -> None:
        # An object the stop interrupted half-built (llvmlite's OutputString while numba
        # compiles) fails in its __del__ later: "Exception ignored ... no attribute '_ptr'".
        # That is the stop's doing, not an error to show the user.
        if handler.received is None:
            previous_hook(report)

    sys.unraisablehook = quiet_after_a_stop
    try:
        yield
    finally:
        handler.noticed.set()  # the block is over: whatever stop came has been handled
        for s, old in previous.items():
            signal.signal(s, old if old is not None else signal.SIG_DFL)
        sys.unraisablehook = previous_hook


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


def input_file(what: str = "file") -> Callable[[str], Path]:
    """argparse type for a file to read: it exists, is not a directory, can be opened and is
    not empty (nothing but whitespace). Messages name it ``what`` ("robot file").

    Whether its contents are valid (UTF-8, YAML, keys) is the loader's to say.
    """

    def check(text: str) -> Path:
        path = Path(text)
        if not path.exists():
            raise argparse.ArgumentTypeError(f"{what} not found: {text}")
        if path.is_dir():
            raise argparse.ArgumentTypeError(f"{what} is a directory: {text}")
        if path.is_file():  # not a pipe: reading one would take what the program needs
            try:
                with path.open("rb") as f:
                    head = f.read(_EMPTY_CHECK_BYTES)
            except OSError as e:
                raise argparse.ArgumentTypeError(
                    f"{what} cannot be read: {text} ({e.strerror})"
                ) from None
            if len(head) < _EMPTY_CHECK_BYTES and not head.strip():
                raise argparse.ArgumentTypeError(f"{what} is empty: {text}")
        return path

    return check


def preset_or_file(what: str) -> Callable[[str], Path | str]:
    """argparse type for a preset's name (``sick_tim571``: a word, returned as it is, for the
    loader to find or refuse) or a file to read (a path, checked like ``input_file``)."""
    check_file = input_file(f"{what} file")

    def check(text: str) -> Path | str:
        if text.replace("_", "").replace("-", "").isalnum() and not Path(text).is_file():
            return text
        return check_file(text)

    return check


def input_path(what: str = "path") -> Callable[[str], Path]:
    """argparse type for a file or folder to read: it exists and can be read."""

    def check(text: str) -> Path:
        path = Path(text)
        if not path.exists():
            raise argparse.ArgumentTypeError(f"{what} not found: {text}")
        if not os.access(path, os.R_OK):
            raise argparse.ArgumentTypeError(f"{what} cannot be read: {text} (no permission)")
        return path

    return check


def output_file(what: str = "file") -> Callable[[str], Path]:
    """argparse type for a file to write: not a directory, and its folder exists and can be
    written, or can be made (its nearest existing parent is a writable directory)."""

    def check(text: str) -> Path:
        path = Path(text)
        if text.endswith(("/", os.sep)) or path.is_dir():
            raise argparse.ArgumentTypeError(f"{what} is a directory: {text}")
        if path.exists() and not os.access(path, os.W_OK):
            raise argparse.ArgumentTypeError(f"{what} cannot be written: {text} (read-only)")
        _check_writable_parent(path.parent, what, text)
        return path

    return check


def output_dir(what: str = "folder") -> Callable[[str], Path]:
    """argparse type for a folder to write into: a writable directory, or one that can be
    made (its nearest existing parent is a writable directory)."""

    def check(text: str) -> Path:
        path = Path(text)
        if path.exists() and not path.is_dir():
            raise argparse.ArgumentTypeError(f"{what} is not a directory: {text}")
        _check_writable_parent(path, what, text)
        return path

    return check


def _check_writable_parent(folder: Path, what: str, text: str) -> None:
    """Raises ArgumentTypeError unless ``folder`` or its nearest existing parent is a directory
    that can be written."""
    folder = folder.absolute()
    existing = next(p for p in (folder, *folder.parents) if p.exists())
    if not existing.is_dir():
        raise argparse.ArgumentTypeError(
            f"{what} cannot be written: {text} ({existing} is not a directory)"
        )
    if not os.access(existing, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(
            f"{what} cannot be written: {text} ({existing} is not writable)"
        )


def write_text(path: Path, text: str, what: str = "file") -> None:
    """Writes ``text`` to ``path`` atomically (``files.write_atomic``), making its folder: a stop
    or an error leaves the file that was there, never half of the new one.

    Raises:
        ConfigError: the file cannot be written (one line naming it and why).
    """
    write_atomic(path, text, what)


def announce(meshcat, doing: str) -> None:
    """Prints, at once, that the run is ``doing`` at Meshcat's URL (headless when ``meshcat``
    is None) and that Ctrl-C stops it."""
    where = "headless" if meshcat is None else f"at {meshcat.web_url()}"
    print(f"{doing} {where} (Ctrl-C stops)", flush=True)


def write_replay(meshcat, path: Path, *, recording: bool = True) -> None:
    """Writes Meshcat's scene as a self-contained HTML file, with the recording (stopped and
    published first) if ``recording``.

    Raises:
        ConfigError: the file cannot be written.
    """
    if recording:
        meshcat.StopRecording()
        meshcat.PublishRecording()
    write_text(path, meshcat.StaticHtml(), "replay")
    print(f"wrote {path}")
