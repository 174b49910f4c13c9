"""``python -m drake_sim.sweep`` runs the command under the project's exit-code contract."""

import subprocess
import sys


def run(*argv):
    return subprocess.run(
        [sys.executable, "-m", "drake_sim.sweep", *argv], capture_output=True, text=True, timeout=60
    )


def test_help():
    result = run("--help")
    assert result.returncode == 0
    assert "--backend {local,ray}" in result.stdout and "--resume" in result.stdout


def test_no_arguments_is_bad_input():
    result = run()
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [
        "error: python -m drake_sim.sweep: give a sweep file, or --plot DIR (see --help)"
    ]
