"""planning.benchmark: the name DESIGN.md gives the MotionBenchMaker benchmark forwards to the app
(drake_sim.tools.plan_benchmark), and imports nothing of the project."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_command_runs_the_app():
    result = subprocess.run(
        [sys.executable, "-m", "planning.benchmark", "--help"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("usage: python -m planning.benchmark")
    assert "--families" in result.stdout


def test_importing_it_runs_nothing():
    import planning.benchmark  # noqa: F401, PLC0415 (the import is the test)

    text = (ROOT / "planning" / "benchmark.py").read_text()
    assert "import drake_sim" not in text and "from drake_sim" not in text
