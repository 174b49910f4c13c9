"""Every viewer entry point stops cleanly on Ctrl-C (SIGINT) and on SIGTERM: exit code 0 and its
summary line.

Each runs as ``python -m ...`` with a Meshcat viewer, is waited for until it prints the line
with its Meshcat URL that says it is running, and is then signalled. The timeouts bound a hang;
they are not speed assertions.
"""

import contextlib
import json
import queue
import signal
import subprocess
import sys
import threading

import pytest

START_TIMEOUT = 180.0  # s, for the process to say it is running.
STOP_TIMEOUT = 10.0  # s, for it to exit after the signal.


class Cli:
    """A ``python -m`` process whose stdout lines a thread collects as they come."""

    def __init__(self, *args):
        self.process = subprocess.Popen(
            [sys.executable, "-m", *map(str, args)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.lines: queue.Queue[str | None] = queue.Queue()
        self.seen: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        for line in self.process.stdout:
            self.lines.put(line)
        self.lines.put(None)  # end of output

    def wait_for(self, marker: str) -> str:
        """Returns the first stdout line holding ``marker`` (the process still running)."""
        while (line := self.lines.get(timeout=START_TIMEOUT)) is not None:
            self.seen.append(line)
            if marker in line:
                return line
        code = self.process.wait(timeout=STOP_TIMEOUT)
        raise AssertionError(f"exit code {code} before {marker!r}: {self.process.stderr.read()}")

    def stop(self, signum: int) -> int:
        """Sends ``signum``; returns the exit code, with the rest of stdout in ``seen``."""
        self.process.send_signal(signum)
        code = self.process.wait(timeout=STOP_TIMEOUT)
        self._reader.join(timeout=STOP_TIMEOUT)
        while (line := self.lines.get_nowait()) is not None:
            self.seen.append(line)
        return code

    def kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()


@pytest.fixture
def start():
    """Starts ``Cli``s and kills whichever still runs at the end of the test."""
    started = []

    def make(*args) -> Cli:
        started.append(Cli(*args))
        return started[-1]

    yield make
    for cli in started:
        cli.kill()


def _stopped_with(cli: Cli, signum: int, summary: str) -> None:
    """Asserts that ``signum`` ends ``cli`` with exit code 0 and a line starting ``summary``."""
    code = cli.stop(signum)
    stderr = cli.process.stderr.read()
    assert code == 0, stderr
    assert "Traceback" not in stderr
    assert any(line.startswith(summary) for line in cli.seen), cli.seen


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_flip_stops_with_its_summary_and_report(start, tmp_path, signum):
    report, replay = tmp_path / "report.json", tmp_path / "replay.html"
    cli = start("drake_sim.flip", "--set", "scene.world=''", "--report", report, "--record", replay)
    assert "http://" in cli.wait_for("(Ctrl-C stops)")
    _stopped_with(cli, signum, "flips ")
    assert json.loads(report.read_text())["sim_time_s"] >= 0.0
    assert replay.read_text().lstrip().lower().startswith("<!doctype html")


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
@pytest.mark.parametrize(
    "args, summary",
    [([], "simulated "), (["--view-only"], "viewed for ")],
    ids=["world", "view-only"],
)
def test_view_stops_with_its_summary(start, args, summary, signum):
    cli = start("drake_sim.view", *args)
    assert "http://" in cli.wait_for("(Ctrl-C stops)")
    _stopped_with(cli, signum, summary)


def test_pickplace_stops_while_waiting_for_pick(start):
    cli = start("drake_sim.pickplace", "--mode", "kinematic")
    assert "http://" in cli.wait_for("press 'Pick'")
    _stopped_with(cli, signal.SIGTERM, "stopped: 0 of ")


def test_pickplace_stops_during_the_task(start, tmp_path):
    report = tmp_path / "report.json"
    cli = start("drake_sim.pickplace", "--mode", "kinematic", "--no-wait", "--report", report)
    cli.wait_for("] check ")  # the first step is done; the arm moves next
    _stopped_with(cli, signal.SIGINT, "stopped: ")
    assert json.loads(report.read_text())["end"] == "stopped"  # the steps done, so far


def test_pickplace_stops_while_showing_the_result(start):
    cli = start("drake_sim.pickplace", "--mode", "kinematic", "--no-wait")
    assert "http://" in cli.wait_for("showing the result")
    assert any(line.startswith("success: ") for line in cli.seen)
    assert cli.stop(signal.SIGTERM) == 0


# ----------------------------------------------------------- headless runs, files kept ----
@pytest.fixture(scope="module")
def room_map(tmp_path_factory):
    from tests import navigation_helpers

    return navigation_helpers.saved_truth_map("room", tmp_path_factory.mktemp("maps"))[1]


def test_mapping_stopped_keeps_the_map_at_out_and_saves_a_partial_one_beside_it(
    start, tmp_path, room_map
):
    out = tmp_path / "room"
    for suffix in (".yaml", ".pgm"):  # a complete map from an earlier run
        (tmp_path / f"room{suffix}").write_bytes(room_map.with_suffix(suffix).read_bytes())
    (tmp_path / "room.yaml").write_text(
        room_map.read_text().replace(room_map.with_suffix(".pgm").name, "room.pgm")
    )
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    report = tmp_path / "report.json"
    cli = start("drake_sim.mapping", "--headless", "--out", out, "--report", report)
    cli.wait_for("mapping headless (Ctrl-C stops)")
    _stopped_with(cli, signal.SIGINT, "the run ended early (stopped)")
    for name, data in before.items():
        assert (tmp_path / name).read_bytes() == data, name  # byte for byte
    assert (tmp_path / "room.partial.yaml").is_file() and (tmp_path / "room.partial.pgm").is_file()
    assert json.loads(report.read_text())["end"] == "stopped"
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []


def test_navigate_headless_stopped_is_a_success_with_its_summary(start, tmp_path, room_map):
    report = tmp_path / "report.json"
    cli = start("drake_sim.navigate", "--map", room_map, "--headless", "--report", report)
    cli.wait_for("navigating headless (Ctrl-C stops)")
    code = cli.stop(signal.SIGINT)
    stderr = cli.process.stderr.read()
    assert code == 0, stderr
    assert stderr == ""  # a stop is not a failure
    assert any("ended by stopped" in line for line in cli.seen), cli.seen
    assert json.loads(report.read_text())["end"] == "stopped"


@pytest.mark.parametrize(
    "module, summary",
    [("drake_sim.walle", "both on oval.yaml: ended by stopped"), ("drake_sim.flip", "flips ")],
)
def test_headless_runs_stop_with_their_summary(start, tmp_path, module, summary):
    report = tmp_path / "report.json"
    cli = start(module, "--headless", "--duration", "600", "--report", report)
    cli.wait_for("running headless (Ctrl-C stops)")
    _stopped_with(cli, signal.SIGTERM, summary)
    assert json.loads(report.read_text())["end"] == "stopped"


def test_pickplace_stopped_during_the_task_reports_the_steps_done(start, tmp_path):
    report = tmp_path / "report.json"
    cli = start("drake_sim.pickplace", "--headless", "--mode", "kinematic", "--report", report)
    cli.wait_for("] check ")
    _stopped_with(cli, signal.SIGINT, "stopped: ")
    data = json.loads(report.read_text())
    assert data["end"] == "stopped" and not data["success"]
    assert data["steps"][0]["name"] == "check"


def test_a_first_compile_stops_at_once(start, tmp_path):
    """A first run on an empty numba cache: the planner's build goes to the background and the
    run compiles its own kernels meanwhile; a stop in the middle of that compile ends the run
    with code 0."""
    import os

    numba_cache = tmp_path / "numba"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(numba_cache), "DRAKE_SIM_KERNELS": "background"}
    process = subprocess.Popen(
        [sys.executable, "-m", "drake_sim.pickplace", "--headless", "--mode", "kinematic"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        line = process.stderr.readline()  # the first: the background build's note
        assert "compiling once for this machine in the background" in line, line
        process.send_signal(signal.SIGINT)  # while this run compiles its timing and IK
        out, err = process.communicate(timeout=STOP_TIMEOUT)
    finally:
        if process.poll() is None:
            process.kill()
        for status in numba_cache.rglob("status.json"):  # end the test's own background build
            pid = json.loads(status.read_text()).get("pid")
            if pid:
                with contextlib.suppress(OSError):
                    os.kill(pid, signal.SIGKILL)
    assert process.returncode == 0, err
    assert "stopped" in out
    assert "Traceback" not in err
