"""Helpers for the command-line tests: edited robot files, the bad-input contract, and entry
points run in the test's own process."""

import contextlib
import importlib
import io
import os
import subprocess

import yaml

from drake_sim.base import cli
from drake_sim.robots.ddrive import default_robot_file


def run_module(module: str, *args, cwd=None) -> subprocess.CompletedProcess:
    """Runs ``python -m module args`` in this process, as its ``__main__`` does
    (``cli.run(main, args)``), with its stdout and stderr captured: what ``subprocess.run``
    returns, without starting an interpreter and importing Drake again (about 1.5 s a call).
    The bad-input contract is the same in both; each CLI's own tests start it as a real process
    at least once."""
    main = importlib.import_module(module).main
    argv = [str(a) for a in args]
    out, err = io.StringIO(), io.StringIO()
    previous = os.getcwd()
    try:
        if cwd is not None:
            os.chdir(cwd)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = cli.run(main, argv)
    finally:
        os.chdir(previous)
    return subprocess.CompletedProcess([module, *argv], code, out.getvalue(), err.getvalue())


def edited_robot_file(tmp_path, edit):
    """Writes ``config/ddrive.yaml`` after ``edit(data)`` to ``tmp_path`` and returns its path."""
    data = yaml.safe_load(default_robot_file().read_text())
    edit(data)
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def assert_bad_input(result, needle):
    """A finished ``subprocess.run``: exit code 2, one stderr line naming ``needle``."""
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert needle in lines[0]
    assert "Traceback" not in result.stderr
