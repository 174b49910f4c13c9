"""drake_sim.base.cli: usage errors are ConfigErrors, ``run`` turns bad input into one stderr
line and exit code 2 (Ctrl-C and SIGTERM into 0), the argparse types reject bad text and bad
paths, and ``write_replay`` writes Meshcat's scene as HTML."""

import argparse
import logging
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from pydrake.geometry import Meshcat, Rgba, Sphere

import drake_sim.base.cli as mut
from drake_sim.base.errors import ConfigError
from tests.cli_helpers import assert_bad_input
from tests.meshcat_html import scene_paths


def _parser() -> mut.ArgumentParser:
    dut = mut.ArgumentParser(prog="tool")
    dut.add_argument("--rate", type=mut.positive_float, default=1.0)
    dut.add_argument("--seed", type=mut.non_negative_int, default=0)
    dut.add_argument("--count", type=mut.positive_int, default=1)
    return dut


def test_parser_errors_are_config_errors():
    dut = _parser()
    assert dut.parse_args(["--rate", "2.5", "--seed", "0", "--count", "3"]) == argparse.Namespace(
        rate=2.5, seed=0, count=3
    )
    with pytest.raises(
        ConfigError, match=r"^tool: unrecognized arguments: --bogus \(see --help\)$"
    ):
        dut.parse_args(["--bogus"])
    with pytest.raises(ConfigError, match=r"tool: argument --rate: must be a finite number > 0"):
        dut.parse_args(["--rate", "-1"])
    with pytest.raises(ConfigError, match=r"argument --count: must be >= 1, got 0"):
        dut.parse_args(["--count", "0"])


@pytest.mark.parametrize("text", ["0", "-1", "inf", "nan", "-inf", "abc", ""])
def test_positive_float_rejects(text):
    with pytest.raises(argparse.ArgumentTypeError, match=repr(text)):
        mut.positive_float(text)


def test_positive_float_accepts():
    assert mut.positive_float("2.5") == 2.5
    assert mut.positive_float("1e-3") == 1e-3


@pytest.mark.parametrize(
    "func, text, match",
    [
        (mut.non_negative_int, "-1", "must be >= 0, got -1"),
        (mut.non_negative_int, "1.5", "not an integer: '1.5'"),
        (mut.non_negative_int, "x", "not an integer: 'x'"),
        (mut.positive_int, "0", "must be >= 1, got 0"),
        (mut.positive_int, "", "not an integer: ''"),
    ],
)
def test_integer_types_reject(func, text, match):
    with pytest.raises(argparse.ArgumentTypeError, match=match):
        func(text)


def test_integer_types_accept():
    assert mut.non_negative_int("0") == 0 and mut.non_negative_int("7") == 7
    assert mut.positive_int("1") == 1 and mut.positive_int(" 12 ") == 12


def test_run_returns_main_code_and_passes_argv():
    seen = []

    def main(argv):
        seen.append(argv)
        return 1

    assert mut.run(main, ["--x"]) == mut.EXIT_FAILED
    assert seen == [["--x"]]


def test_run_turns_config_error_into_one_line_and_exit_2(capsys):
    def main(argv):
        raise ConfigError("f.yaml: 'rate'\n   must be > 0")

    assert mut.run(main, []) == mut.EXIT_BAD_INPUT == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err == "error: f.yaml: 'rate' must be > 0\n"


def test_run_usage_error_is_bad_input(capsys):
    assert mut.run(lambda argv: _parser().parse_args(argv) and 0, ["--seed", "-3"]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: tool: argument --seed: must be >= 0")


STOPPED_IN_SETUP = ("stopped before the run began (while it was being set up)\n", "")


def test_run_ends_with_one_line_on_ctrl_c_that_main_lets_through(capsys):
    def main(argv):
        raise KeyboardInterrupt

    assert mut.run(main) == mut.EXIT_OK == 0
    assert capsys.readouterr() == STOPPED_IN_SETUP


def _wrapped_interrupt(argv):
    """Raises what numba makes of an interrupt that lands in one of its callbacks."""
    try:
        raise KeyboardInterrupt("SIGINT")
    except KeyboardInterrupt as e:
        raise SystemError(
            "<function _numba_unpickle> returned a result with an exception set"
        ) from e


def test_run_ends_quietly_on_an_interrupt_wrapped_by_compiled_code(capsys):
    assert mut.run(_wrapped_interrupt) == mut.EXIT_OK
    assert capsys.readouterr() == STOPPED_IN_SETUP
    with pytest.raises(SystemError) as raised:
        _wrapped_interrupt(None)
    assert mut.is_stop(raised.value) and mut.is_stop(KeyboardInterrupt())
    assert not mut.is_stop(SystemError("a real one")) and not mut.is_stop(ValueError())


def _swallowed_interrupt(argv):
    """Receives SIGTERM and raises what pybind11 makes of an interrupt that lands while it
    converts arguments: a TypeError naming no matching overload."""
    try:
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(60)
    except KeyboardInterrupt:
        pass  # swallowed by the compiled code
    raise TypeError("__init__(): incompatible constructor arguments")


def test_run_ends_quietly_on_any_error_raised_after_a_stop_signal(capsys):
    assert mut.run(_swallowed_interrupt) == mut.EXIT_OK
    assert capsys.readouterr() == STOPPED_IN_SETUP
    assert not mut.stop_received()  # the handler is gone with its block


def test_run_ending_sorts_stops_failures_and_bugs():
    assert mut.run_ending(KeyboardInterrupt()) == ("stopped", "")
    assert mut.run_ending(RuntimeError("  step failed\n  at t = 1\n")) == ("failed", "step failed")
    assert mut.run_ending(RuntimeError("")) == ("failed", "RuntimeError")
    with pytest.raises(ValueError, match="a bug"):
        mut.run_ending(ValueError("a bug"))


def test_is_stop_is_false_for_errors_before_any_stop_signal():
    with mut.stop_on_signals():
        assert not mut.stop_received()
        assert not mut.is_stop(TypeError("a real one"))
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(60)
        assert mut.stop_received() and mut.is_stop(TypeError("after the stop"))

    def main(argv):
        raise TypeError("a bug, not a stop")

    with pytest.raises(TypeError):
        mut.run(main)


def test_run_lets_a_system_error_through():
    def main(argv):
        raise SystemError("a bug, not a stop")

    with pytest.raises(SystemError):
        mut.run(main)


def test_run_lets_bugs_through():
    def main(argv):
        raise RuntimeError("a bug, not bad input")

    with pytest.raises(RuntimeError):
        mut.run(main)


def test_preset_or_file(tmp_path):
    check = mut.preset_or_file("lidar")
    assert check("sick_tim571") == "sick_tim571"  # a name: the loader finds it or says why
    assert check("lds-01") == "lds-01"
    good = tmp_path / "my_lidar.yaml"
    good.write_text("samples: 90\n")
    assert check(str(good)) == good
    with pytest.raises(argparse.ArgumentTypeError, match="lidar file not found"):
        check(str(tmp_path / "none.yaml"))
    (tmp_path / "empty.yaml").write_text("")
    with pytest.raises(argparse.ArgumentTypeError, match="lidar file is empty"):
        check(str(tmp_path / "empty.yaml"))


def test_input_file(tmp_path):
    check = mut.input_file("scene file")
    good = tmp_path / "scene.yaml"
    good.write_bytes(b"\xff\xfe not UTF-8: the loader's to say\n")
    assert check(str(good)) == good
    (tmp_path / "blank.yaml").write_text("  \n\t\n")
    (tmp_path / "empty.yaml").write_text("")
    for name, match in [
        ("none.yaml", "scene file not found: "),
        ("blank.yaml", "scene file is empty: "),
        ("empty.yaml", "scene file is empty: "),
        (".", "scene file is a directory: "),
    ]:
        with pytest.raises(argparse.ArgumentTypeError, match=match):
            check(str(tmp_path / name))
    assert mut.input_file()("/dev/null") == Path("/dev/null")  # not a regular file: not read


def test_input_path(tmp_path):
    check = mut.input_path("dataset")
    assert check(str(tmp_path)) == tmp_path
    with pytest.raises(argparse.ArgumentTypeError, match="dataset not found: "):
        check(str(tmp_path / "none"))


def test_output_file(tmp_path):
    check = mut.output_file("report")
    assert check(str(tmp_path / "r.json")) == tmp_path / "r.json"
    assert check(str(tmp_path / "new" / "dir" / "r.json")) == tmp_path / "new/dir/r.json"
    (tmp_path / "old.json").write_text("{}")
    assert check(str(tmp_path / "old.json")) == tmp_path / "old.json"  # overwritten
    for text, match in [
        (str(tmp_path), "report is a directory: "),
        (str(tmp_path / "new") + "/", "report is a directory: "),
        (str(tmp_path / "old.json" / "r.json"), r"old\.json is not a directory\)"),
        (str(tmp_path / "old.json" / "sub" / "r.json"), r"old\.json is not a directory\)"),
    ]:
        with pytest.raises(argparse.ArgumentTypeError, match=match):
            check(text)
    assert not (tmp_path / "new").exists()  # checked, not made


def test_output_dir(tmp_path):
    check = mut.output_dir("picture folder")
    assert check(str(tmp_path)) == tmp_path
    assert check(str(tmp_path / "new" / "images")) == tmp_path / "new/images"
    (tmp_path / "file").write_text("x")
    with pytest.raises(argparse.ArgumentTypeError, match="picture folder is not a directory: "):
        check(str(tmp_path / "file"))
    with pytest.raises(argparse.ArgumentTypeError, match=r"file is not a directory\)"):
        check(str(tmp_path / "file" / "images"))


def test_write_text(tmp_path):
    path = tmp_path / "a" / "b.json"
    mut.write_text(path, "{}\n")
    assert path.read_text() == "{}\n"
    with pytest.raises(ConfigError, match=r"^report cannot be written: .*b\.json/c\.json \("):
        mut.write_text(path / "c.json", "{}", "report")


def test_parse_errors_on_paths_are_one_line_and_exit_2(tmp_path, capsys):
    def main(argv):
        parser = mut.ArgumentParser(prog="tool")
        parser.add_argument("--report", type=mut.output_file("report"))
        parser.parse_args(argv)
        raise AssertionError("not reached: the path is checked first")

    assert mut.run(main, ["--report", str(tmp_path)]) == mut.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert (
        err == f"error: tool: argument --report: report is a directory: {tmp_path} (see --help)\n"
    )


def test_sigterm_stops_like_ctrl_c(capsys):
    before = signal.getsignal(signal.SIGTERM)
    stopped = []

    def main(argv):
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(60)  # not reached: the handler raises at once (or ends the sleep)
        except KeyboardInterrupt as e:
            stopped.append(str(e))
            print("summary")
            return mut.EXIT_OK
        return mut.EXIT_FAILED

    assert mut.run(main) == mut.EXIT_OK
    assert stopped == ["SIGTERM"]
    assert capsys.readouterr() == ("summary\n", "")
    assert signal.getsignal(signal.SIGTERM) is before  # put back


def test_stop_on_signals_raises_keyboard_interrupt_and_restores():
    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(KeyboardInterrupt), mut.stop_on_signals():
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(60)
    assert signal.getsignal(signal.SIGINT) is before


def test_a_signal_inside_a_finalizer_is_delivered_after_it(capsys):
    """A stop that lands in an object's ``__del__`` (llvmlite's, while numba compiles) would be
    printed as "Exception ignored" with a traceback and lost: it comes again once the finalizer
    has returned, and stops the run as usual."""
    finalized = []

    class Finalized:
        def __del__(self):
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):  # the handler runs at one of these bytecodes
                sum(range(10))
            finalized.append(True)

    with pytest.raises(KeyboardInterrupt), mut.stop_on_signals():
        Finalized()  # dropped at once: its __del__ runs here
        for _ in range(100):  # 1 s at most (the stop comes again within 10 ms); not longer, so
            time.sleep(0.01)  # a lost stop fails here before its watchdog would end pytest
    assert finalized == [True]
    assert "Exception ignored" not in capsys.readouterr().err


class HalfBuilt:
    """An object whose construction a stop interrupted: its ``__del__`` then fails, as
    llvmlite's ``OutputString`` does ("no attribute '_ptr'") when Ctrl-C lands in its
    ``__init__``."""

    def __init__(self, interrupt: bool):
        if interrupt:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(60)
        self.handle = 1

    def __del__(self):
        del self.handle


def _unraisable(monkeypatch) -> list:
    """The reports Python would print as "Exception ignored" (kept, not printed)."""
    seen = []
    monkeypatch.setattr(sys, "unraisablehook", seen.append)
    return seen


def test_a_finalizer_failing_after_a_stop_is_not_printed(monkeypatch):
    seen = _unraisable(monkeypatch)
    stopped = False
    with mut.stop_on_signals():
        try:
            HalfBuilt(interrupt=True)
        except KeyboardInterrupt:  # as an app's run catches its stop; the object goes here
            stopped = True
    assert stopped and seen == []
    assert sys.unraisablehook == seen.append  # put back


def test_a_finalizer_failing_before_any_stop_is_printed(monkeypatch):
    seen = _unraisable(monkeypatch)
    with mut.stop_on_signals():
        broken = HalfBuilt(interrupt=False)
        del broken.handle
        del broken  # its __del__ fails: a bug, shown as Python shows it
    assert [type(r.exc_value) for r in seen] == [AttributeError]


@pytest.fixture(scope="module")
def meshcat():
    return Meshcat()


def test_write_replay_writes_html(meshcat, tmp_path, capsys):
    meshcat.StartRecording()
    meshcat.SetObject("ball", Sphere(0.1), Rgba(1, 0, 0, 1))
    path = tmp_path / "out" / "replay.html"  # the folder is created
    mut.write_replay(meshcat, path)
    html = path.read_text()
    assert html.lstrip().lower().startswith("<!doctype html")
    assert "/drake/ball" in scene_paths(html)
    assert capsys.readouterr().out == f"wrote {path}\n"


def test_write_replay_without_recording(meshcat, tmp_path):
    meshcat.SetObject("cube", Sphere(0.2), Rgba(0, 1, 0, 1))
    path = tmp_path / "scene.html"
    mut.write_replay(meshcat, path, recording=False)
    assert "/drake/cube" in scene_paths(path.read_text())


def test_exit_at_once_does_not_wait_for_worker_threads():
    script = (
        "import threading\n"
        "from drake_sim.base import cli\n"
        "never = threading.Event()\n"
        "threading.Thread(target=never.wait).start()  # would keep a normal exit waiting\n"
        "print('summary', end='')\n"
        "cli.exit_at_once(3)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60
    )
    assert (result.returncode, result.stdout, result.stderr) == (3, "summary", "")


@pytest.mark.parametrize(
    "module, args, needle",
    [
        ("drake_sim.flip", ["--headless", "--config", "{tmp}"], "scenario file is a directory"),
        ("drake_sim.view", ["--record", "{file}/r.html"], "is not a directory"),
        ("drake_sim.pickplace", ["--headless", "--scene", "{tmp}"], "scene file is a directory"),
        ("planning.benchmark", ["--report", "{tmp}"], "report is a directory"),
        ("planning.benchmark", ["--options", "{file}"], "options file is empty"),
        ("drake_sim.tools.regions", ["--scene", "{tmp}"], "scene file is a directory"),
        ("drake_sim.tools.generate_models", ["--models", "{file}"], "is not a directory"),
        ("drake_sim.tools.readme_pictures", ["--out", "{file}/images"], "is not a directory"),
        ("drake_sim.tools.replay_frames", ["{file}", "out.gif"], "replay is empty"),
        ("drake_sim.tools.replay_frames", ["{tmp}", "out.gif"], "replay is a directory"),
    ],
)
def test_every_entry_point_checks_its_paths_first(tmp_path, module, args, needle):
    file = tmp_path / "empty.txt"
    file.write_text("")
    argv = [a.format(tmp=tmp_path, file=file) for a in args]
    result = subprocess.run(
        [sys.executable, "-m", module, *argv], capture_output=True, text=True, timeout=300
    )
    assert_bad_input(result, needle)
    assert result.stdout == ""


# A main that swallows the interrupt (as compiled code may) and goes on working.
_DEAF_MAIN = """
import sys, time
from drake_sim.base import cli
def main(argv):
    end = time.monotonic() + 60
    while True:
        try:
            print("working", flush=True)
            while time.monotonic() < end:
                time.sleep(0.01)
            return 1
        except KeyboardInterrupt:
            pass  # swallowed: the run never notices its stop
sys.exit(cli.run(main))
"""


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_stop_the_run_swallows_still_ends_the_process_with_0(signum):
    process = subprocess.Popen(
        [sys.executable, "-c", _DEAF_MAIN],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert process.stdout.readline() == "working\n"
    process.send_signal(signum)
    out, err = process.communicate(timeout=30)  # a bound on a hang, not a speed assertion
    assert process.returncode == 0, err
    assert out.strip().splitlines()[-1] == "stopped"
    assert "Traceback" not in err


def test_a_second_signal_ends_the_process_at_once():
    code = _DEAF_MAIN.replace(
        "from drake_sim.base import cli", "from drake_sim.base import cli\ncli.STOP_GRACE_S = 600"
    )
    process = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert process.stdout.readline() == "working\n"
    process.send_signal(signal.SIGINT)
    time.sleep(0.5)
    assert process.poll() is None  # the first waits for its grace time (600 s here)
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=30)
    assert process.returncode == 0, err
    assert out.strip().splitlines()[-1] == "stopped (SIGINT again)"


def test_run_keeps_drakes_info_lines_off_stderr():
    logging.getLogger("drake").setLevel(logging.INFO)
    assert mut.run(lambda argv: 0) == 0
    assert logging.getLogger("drake").level == logging.WARNING  # stderr is for errors


def test_logger_level_holds_only_within_its_block():
    import logging

    logger = logging.getLogger("drake_sim.test_logger_level")
    logger.setLevel(logging.INFO)
    with mut.logger_level("drake_sim.test_logger_level", logging.ERROR):
        assert logger.level == logging.ERROR
    assert logger.level == logging.INFO
